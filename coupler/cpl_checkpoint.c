/* cpl_checkpoint — the table of checkpoint entries and its HDF5 file (cpl_checkpoint.h). */
#include "cpl_checkpoint.h"

#include <errno.h>
#include <fcntl.h>
#include <hdf5.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

void cpl_ckpt_add(cpl_ckpt_table *t, const char *prefix, const char *name, cpl_ckpt_type type,
                  void *data, size_t count)
{
    if (t->failed) return;
    if (t->n == t->capacity) {
        size_t cap = t->capacity ? 2 * t->capacity : 64;
        cpl_ckpt_entry *e = realloc(t->entries, cap * sizeof *e);
        if (!e) {
            t->failed = 1;
            return;
        }
        t->entries = e;
        t->capacity = cap;
    }
    cpl_ckpt_entry *e = &t->entries[t->n];
    int len = prefix && prefix[0] ? snprintf(e->name, sizeof e->name, "/%s/%s", prefix, name)
                                  : snprintf(e->name, sizeof e->name, "/%s", name);
    if (len < 0 || (size_t)len >= sizeof e->name || (count > 0 && !data)) {
        t->failed = 1;
        return;
    }
    e->type = type;
    e->data = data;
    e->count = count;
    t->n++;
}

void cpl_ckpt_table_free(cpl_ckpt_table *t)
{
    free(t->entries);
    memset(t, 0, sizeof *t);
}

/* Flushes a file or folder to disk. */
static int sync_path(const char *path, int directory, nc_error *err)
{
    int fd = open(path, directory ? O_RDONLY | O_DIRECTORY : O_RDONLY);
    if (fd < 0) return nc_error_set(err, 1, "%s: cannot open to flush: %s", path, strerror(errno));
    int rc = fsync(fd);
    int e = errno;
    close(fd);
    if (rc != 0 && !(directory && (e == EINVAL || e == EROFS)))
        return nc_error_set(err, 1, "%s: flush to disk failed: %s", path, strerror(e));
    return 0;
}

static void folder_of(const char *path, char *dir, size_t size)
{
    snprintf(dir, size, "%s", path);
    char *slash = strrchr(dir, '/');
    if (!slash) snprintf(dir, size, ".");
    else if (slash == dir) dir[1] = '\0';
    else *slash = '\0';
}

/* tmp -> path, durably */
static int commit(const char *tmp, const char *path, nc_error *err)
{
    if (sync_path(tmp, 0, err)) return -1;
    if (rename(tmp, path) != 0)
        return nc_error_set(err, 1, "%s: cannot rename %s into place: %s", path, tmp,
                            strerror(errno));
    char dir[2048];
    folder_of(path, dir, sizeof dir);
    return sync_path(dir, 1, err);
}

int cpl_ckpt_write_text(const char *path, const char *text, nc_error *err)
{
    char tmp[2048];
    snprintf(tmp, sizeof tmp, "%s.tmp", path);
    FILE *f = fopen(tmp, "w");
    if (!f) return nc_error_set(err, 1, "%s: cannot create: %s", tmp, strerror(errno));
    size_t len = strlen(text);
    int bad = fwrite(text, 1, len, f) != len;
    bad |= fclose(f) != 0;
    if (bad) {
        remove(tmp);
        return nc_error_set(err, 1, "%s: write failed (disk full?)", tmp);
    }
    return commit(tmp, path, err);
}

static int table_ok(const cpl_ckpt_table *t, const char *path, nc_error *err)
{
    if (t->failed)
        return nc_error_set(err, 1, "%s: checkpoint table incomplete (out of memory or a name "
                            "too long)", path);
    return 0;
}

/* parent groups of an absolute dataset path */
static int make_groups(hid_t file, const char *name)
{
    char buf[96];
    snprintf(buf, sizeof buf, "%s", name);
    for (char *p = strchr(buf + 1, '/'); p; p = strchr(p + 1, '/')) {
        *p = '\0';
        if (H5Lexists(file, buf, H5P_DEFAULT) <= 0) {
            hid_t g = H5Gcreate2(file, buf, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
            if (g < 0) return -1;
            H5Gclose(g);
        }
        *p = '/';
    }
    return 0;
}

/* integers go through int64 buffers */
static void to_i64(const cpl_ckpt_entry *e, int64_t *out)
{
    for (size_t i = 0; i < e->count; i++)
        out[i] = e->type == CPL_CKPT_LONG ? (int64_t)((const long *)e->data)[i]
               : e->type == CPL_CKPT_INT  ? (int64_t)((const int *)e->data)[i]
                                          : (int64_t)((const size_t *)e->data)[i];
}

static void from_i64(const cpl_ckpt_entry *e, const int64_t *in)
{
    for (size_t i = 0; i < e->count; i++) {
        if (e->type == CPL_CKPT_LONG) ((long *)e->data)[i] = (long)in[i];
        else if (e->type == CPL_CKPT_INT) ((int *)e->data)[i] = (int)in[i];
        else ((size_t *)e->data)[i] = (size_t)in[i];
    }
}

int cpl_ckpt_save(const cpl_ckpt_table *t, const char *path, nc_error *err)
{
    if (table_ok(t, path, err)) return -1;
    char tmp[2048];
    snprintf(tmp, sizeof tmp, "%s.tmp", path);
    hid_t file = H5Fcreate(tmp, H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT);
    if (file < 0) return nc_error_set(err, 1, "%s: cannot create the checkpoint file", tmp);
    int rc = 0;
    for (size_t k = 0; k < t->n && rc == 0; k++) {
        const cpl_ckpt_entry *e = &t->entries[k];
        const int f64 = e->type == CPL_CKPT_F64;
        hsize_t dims[1] = {e->count};
        int64_t *buf = NULL;
        if (!f64 && e->count) {
            buf = malloc(e->count * sizeof *buf);
            if (!buf) {
                rc = nc_error_set(err, 1, "%s: out of memory for %s", tmp, e->name);
                break;
            }
            to_i64(e, buf);
        }
        hid_t space = make_groups(file, e->name) == 0 ? H5Screate_simple(1, dims, NULL) : -1;
        hid_t set = space >= 0 ? H5Dcreate2(file, e->name, f64 ? H5T_IEEE_F64LE : H5T_STD_I64LE,
                                            space, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT)
                               : -1;
        if (set < 0 || (e->count && H5Dwrite(set, f64 ? H5T_NATIVE_DOUBLE : H5T_NATIVE_INT64,
                                             H5S_ALL, H5S_ALL, H5P_DEFAULT,
                                             f64 ? e->data : (const void *)buf) < 0))
            rc = nc_error_set(err, 1, "%s: cannot write %s (disk full?)", tmp, e->name);
        if (set >= 0) H5Dclose(set);
        if (space >= 0) H5Sclose(space);
        free(buf);
    }
    if (H5Fclose(file) < 0 && rc == 0) rc = nc_error_set(err, 1, "%s: cannot close (disk full?)", tmp);
    if (rc) {
        remove(tmp);
        return -1;
    }
    return commit(tmp, path, err);
}

static hid_t open_file(const char *path, nc_error *err)
{
    if (access(path, R_OK) != 0)
        return nc_error_set(err, 1, "%s: cannot read the checkpoint file: %s", path,
                            strerror(errno)), -1;
    hid_t file = -1;
    H5E_BEGIN_TRY { file = H5Fopen(path, H5F_ACC_RDONLY, H5P_DEFAULT); } H5E_END_TRY;
    if (file < 0) nc_error_set(err, 1, "%s: not a readable HDF5 checkpoint file", path);
    return file;
}

static int read_entry(hid_t file, const char *path, const cpl_ckpt_entry *e, nc_error *err)
{
    if (H5Lexists(file, e->name, H5P_DEFAULT) <= 0)
        return nc_error_set(err, 1, "%s: checkpoint has no %s (written by another coupler "
                            "version?)", path, e->name);
    hid_t set = H5Dopen2(file, e->name, H5P_DEFAULT);
    if (set < 0) return nc_error_set(err, 1, "%s: cannot open %s", path, e->name);
    hid_t space = H5Dget_space(set);
    hssize_t n = H5Sget_simple_extent_npoints(space);
    H5Sclose(space);
    int rc = 0;
    if (n < 0 || (size_t)n != e->count) {
        rc = nc_error_set(err, 1, "%s: %s holds %lld values, this run needs %zu (a checkpoint "
                          "of another model or coupler.json)", path, e->name, (long long)n,
                          e->count);
    } else if (e->count) {
        const int f64 = e->type == CPL_CKPT_F64;
        int64_t *buf = f64 ? NULL : malloc(e->count * sizeof *buf);
        if (!f64 && !buf) rc = nc_error_set(err, 1, "%s: out of memory for %s", path, e->name);
        else if (H5Dread(set, f64 ? H5T_NATIVE_DOUBLE : H5T_NATIVE_INT64, H5S_ALL, H5S_ALL,
                         H5P_DEFAULT, f64 ? e->data : (void *)buf) < 0)
            rc = nc_error_set(err, 1, "%s: cannot read %s", path, e->name);
        else if (!f64)
            from_i64(e, buf);
        free(buf);
    }
    H5Dclose(set);
    return rc;
}

int cpl_ckpt_load(const cpl_ckpt_table *t, const char *path, nc_error *err)
{
    if (table_ok(t, path, err)) return -1;
    hid_t file = open_file(path, err);
    if (file < 0) return -1;
    int rc = 0;
    for (size_t k = 0; k < t->n && rc == 0; k++) rc = read_entry(file, path, &t->entries[k], err);
    H5Fclose(file);
    return rc;
}

int cpl_ckpt_read_long(const char *path, const char *name, long *value, nc_error *err)
{
    hid_t file = open_file(path, err);
    if (file < 0) return -1;
    cpl_ckpt_entry e = {.type = CPL_CKPT_LONG, .data = value, .count = 1};
    snprintf(e.name, sizeof e.name, "%s", name);
    int rc = read_entry(file, path, &e, err);
    H5Fclose(file);
    return rc;
}
