/* nc_checkpoint — the table of checkpoint entries, its HDF5 file and the pruning of old
 * checkpoint files (nc_checkpoint.h). */
#include "nc_checkpoint.h"

#include <dirent.h>
#include <errno.h>
#include <hdf5.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "nc_file.h"

_Static_assert(sizeof(int) == 4, "int entries are stored as 32-bit integers");
_Static_assert(sizeof(long) <= 8 && sizeof(size_t) <= 8, "long and size_t fit 64 bits");

/* ---- the table ------------------------------------------------------------------------ */

void nc_ckpt_add_rows(nc_ckpt_table *t, const char *prefix, const char *name,
                      nc_ckpt_type type, void *data, size_t rows, size_t width, size_t stride)
{
    if (t->failed) return;
    if (t->n == t->capacity) {
        size_t cap = t->capacity ? 2 * t->capacity : 64;
        nc_ckpt_entry *e = realloc(t->entries, cap * sizeof *e);
        if (!e) {
            t->failed = 1;
            return;
        }
        t->entries = e;
        t->capacity = cap;
    }
    nc_ckpt_entry *e = &t->entries[t->n];
    if (name[0] == '/') name++;
    int len = prefix && prefix[0]
                  ? snprintf(e->name, sizeof e->name, "%s%s/%s", prefix[0] == '/' ? "" : "/",
                             prefix, name)
                  : snprintf(e->name, sizeof e->name, "/%s", name);
    if (len < 0 || (size_t)len >= sizeof e->name || !name[0] || width == 0 ||
        (rows > 0 && !data)) {
        t->failed = 1;
        return;
    }
    e->type = type;
    e->data = data;
    e->count = rows;
    e->width = width;
    e->stride = stride;
    t->n++;
}

void nc_ckpt_add(nc_ckpt_table *t, const char *prefix, const char *name, nc_ckpt_type type,
                 void *data, size_t count)
{
    nc_ckpt_add_rows(t, prefix, name, type, data, count, 1, 0);
}

void nc_ckpt_add_table(nc_ckpt_table *t, const nc_ckpt_table *from)
{
    if (!from) return;
    if (from->failed) t->failed = 1;
    for (size_t k = 0; k < from->n; k++) {
        const nc_ckpt_entry *e = &from->entries[k];
        nc_ckpt_add_rows(t, NULL, e->name, e->type, e->data, e->count, e->width, e->stride);
    }
}

void nc_ckpt_clear(nc_ckpt_table *t)
{
    t->n = 0;
    t->failed = 0;
}

void nc_ckpt_table_free(nc_ckpt_table *t)
{
    free(t->entries);
    memset(t, 0, sizeof *t);
}

size_t nc_ckpt_type_size(nc_ckpt_type type)
{
    switch (type) {
    case NC_CKPT_F64: return sizeof(double);
    case NC_CKPT_I32: return sizeof(int32_t);
    case NC_CKPT_INT: return sizeof(int);
    case NC_CKPT_LONG: return sizeof(long);
    case NC_CKPT_I64: return sizeof(int64_t);
    case NC_CKPT_SIZE: return sizeof(size_t);
    case NC_CKPT_U8: return sizeof(uint8_t);
    }
    return 1;
}

static hid_t mem_type(nc_ckpt_type type)
{
    switch (type) {
    case NC_CKPT_F64: return H5T_NATIVE_DOUBLE;
    case NC_CKPT_I32: return H5T_NATIVE_INT32;
    case NC_CKPT_INT: return H5T_NATIVE_INT;
    case NC_CKPT_LONG: return H5T_NATIVE_LONG;
    case NC_CKPT_I64: return H5T_NATIVE_INT64;
    case NC_CKPT_SIZE: return sizeof(size_t) == 8 ? H5T_NATIVE_UINT64 : H5T_NATIVE_UINT32;
    case NC_CKPT_U8: return H5T_NATIVE_UINT8;
    }
    return H5T_NATIVE_UINT8;
}

static hid_t file_type(nc_ckpt_type type)
{
    switch (type) {
    case NC_CKPT_F64: return H5T_IEEE_F64LE;
    case NC_CKPT_I32: case NC_CKPT_INT: return H5T_STD_I32LE;
    case NC_CKPT_LONG: case NC_CKPT_I64: return H5T_STD_I64LE;
    case NC_CKPT_SIZE: return H5T_STD_U64LE;
    case NC_CKPT_U8: return H5T_STD_U8LE;
    }
    return H5T_STD_U8LE;
}

static const char *type_label(nc_ckpt_type type)
{
    switch (type) {
    case NC_CKPT_F64: return "64-bit float";
    case NC_CKPT_I32: case NC_CKPT_INT: return "32-bit integer";
    case NC_CKPT_LONG: case NC_CKPT_I64: return "64-bit integer";
    case NC_CKPT_SIZE: return "unsigned 64-bit integer";
    case NC_CKPT_U8: return "8-bit integer";
    }
    return "?";
}

static int packed(const nc_ckpt_entry *e)
{
    return e->stride == 0 || e->stride == e->width * nc_ckpt_type_size(e->type);
}

/* Copies a strided entry's values to or from a packed buffer. */
static void gather(const nc_ckpt_entry *e, void *buf, int to_entry)
{
    size_t row = e->width * nc_ckpt_type_size(e->type);
    for (size_t k = 0; k < e->count; k++) {
        char *p = (char *)e->data + k * (e->stride ? e->stride : row);
        if (to_entry) memcpy(p, (const char *)buf + k * row, row);
        else memcpy((char *)buf + k * row, p, row);
    }
}

static int table_ok(const nc_ckpt_table *t, const char *path, nc_error *err)
{
    if (t->failed)
        return nc_error_set(err, 1, "%s: checkpoint table incomplete (out of memory or a name "
                            "too long)", path);
    return 0;
}

/* ---- saving --------------------------------------------------------------------------- */

static int write_entry(hid_t f, hid_t lcpl, const nc_ckpt_entry *e, const char *path,
                       nc_error *err)
{
    hsize_t dims[2] = {e->count, e->width};
    size_t bytes = e->count * e->width * nc_ckpt_type_size(e->type);
    void *buf = NULL;
    if (!packed(e) && bytes) {
        if (!(buf = malloc(bytes))) return nc_error_set(err, 1, "%s: out of memory for %s", path, e->name);
        gather(e, buf, 0);
    }
    hid_t space = H5Screate_simple(e->width == 1 ? 1 : 2, dims, NULL);
    hid_t d = space < 0 ? -1 : H5Dcreate2(f, e->name, file_type(e->type), space, lcpl,
                                          H5P_DEFAULT, H5P_DEFAULT);
    int rc = 0;
    if (d < 0 || (bytes && H5Dwrite(d, mem_type(e->type), H5S_ALL, H5S_ALL, H5P_DEFAULT,
                                    buf ? buf : e->data) < 0))
        rc = nc_error_set(err, 1, "%s: cannot write %s (a name used twice?)", path, e->name);
    if (d >= 0) H5Dclose(d);
    if (space >= 0) H5Sclose(space);
    free(buf);
    return rc;
}

int nc_ckpt_save(const nc_ckpt_table *t, const char *path, nc_error *err)
{
    if (table_ok(t, path, err)) return -1;
    /* built in memory (HDF5's core driver), then written with plain system calls, whose
     * errors (a full disk) are reported exactly and leave no half-written file */
    hid_t fapl = H5Pcreate(H5P_FILE_ACCESS);
    H5Pset_fapl_core(fapl, 1u << 20, 0);
    hid_t f = -1;
    H5E_BEGIN_TRY { f = H5Fcreate(path, H5F_ACC_TRUNC, H5P_DEFAULT, fapl); } H5E_END_TRY;
    H5Pclose(fapl);
    if (f < 0) return nc_error_set(err, 1, "%s: cannot build the checkpoint in memory", path);
    hid_t lcpl = H5Pcreate(H5P_LINK_CREATE);
    H5Pset_create_intermediate_group(lcpl, 1);
    int rc = 0;
    H5E_BEGIN_TRY {
        for (size_t k = 0; k < t->n && rc == 0; k++) rc = write_entry(f, lcpl, &t->entries[k], path, err);
    } H5E_END_TRY;
    H5Pclose(lcpl);
    void *image = NULL;
    ssize_t size = -1;
    if (rc == 0 && H5Fflush(f, H5F_SCOPE_GLOBAL) >= 0) size = H5Fget_file_image(f, NULL, 0);
    if (size > 0 && (image = malloc((size_t)size)) != NULL &&
        H5Fget_file_image(f, image, (size_t)size) != size) {
        free(image);
        image = NULL;
    }
    H5Fclose(f);
    if (rc == 0 && !image) rc = nc_error_set(err, 1, "%s: cannot build the checkpoint image", path);
    if (rc == 0) rc = nc_file_write_durably(path, image, (size_t)size, err);
    free(image);
    return rc ? -1 : 0;
}

/* ---- loading -------------------------------------------------------------------------- */

static hid_t open_file(const char *path, nc_error *err)
{
    if (access(path, R_OK) != 0)
        return nc_error_set(err, 1, "%s: cannot read the checkpoint: %s", path, strerror(errno)), -1;
    hid_t f = -1;
    H5E_BEGIN_TRY {
        if (H5Fis_hdf5(path) > 0) f = H5Fopen(path, H5F_ACC_RDONLY, H5P_DEFAULT);
    } H5E_END_TRY;
    if (f < 0) nc_error_set(err, 1, "%s: not a readable HDF5 file (a damaged checkpoint?)", path);
    return f;
}

/* Reads entry e into buf (packed values), checking presence, kind and shape. */
static int read_entry(hid_t f, const char *path, const nc_ckpt_entry *e, void *buf, nc_error *err)
{
    if (H5Lexists(f, e->name, H5P_DEFAULT) <= 0)
        return nc_error_set(err, 1, "%s: has no %s (a checkpoint of another program or "
                            "version?)", path, e->name);
    hid_t d = H5Dopen2(f, e->name, H5P_DEFAULT);
    if (d < 0) return nc_error_set(err, 1, "%s: cannot open %s", path, e->name);
    hid_t space = H5Dget_space(d), type = H5Dget_type(d);
    int rank = space >= 0 ? H5Sget_simple_extent_ndims(space) : -1;
    hsize_t dims[2] = {0, 1};
    if (rank == 1 || rank == 2) H5Sget_simple_extent_dims(space, dims, NULL);
    int want_rank = e->width == 1 ? 1 : 2, rc = 0;
    if ((rank != 1 && rank != 2) || dims[0] != e->count || (rank == 2 ? dims[1] : 1) != e->width ||
        rank != want_rank)
        rc = nc_error_set(err, 1, "%s: %s holds %llu x %llu values, this run needs %zu x %zu (a "
                          "checkpoint of another model or input?)", path, e->name,
                          (unsigned long long)dims[0], (unsigned long long)(rank == 2 ? dims[1] : 1),
                          e->count, e->width);
    else if (type < 0 || H5Tequal(type, file_type(e->type)) <= 0)
        rc = nc_error_set(err, 1, "%s: %s is not stored as a %s", path, e->name, type_label(e->type));
    else if (e->count && H5Dread(d, mem_type(e->type), H5S_ALL, H5S_ALL, H5P_DEFAULT, buf) < 0)
        rc = nc_error_set(err, 1, "%s: cannot read %s", path, e->name);
    if (type >= 0) H5Tclose(type);
    if (space >= 0) H5Sclose(space);
    H5Dclose(d);
    return rc;
}

int nc_ckpt_load(const nc_ckpt_table *t, const char *path, nc_error *err)
{
    if (table_ok(t, path, err)) return -1;
    hid_t f = open_file(path, err);
    if (f < 0) return -1;
    void **bufs = calloc(t->n + 1, sizeof *bufs);
    int rc = bufs ? 0 : nc_error_set(err, 1, "%s: out of memory", path);
    H5E_BEGIN_TRY {
        for (size_t k = 0; k < t->n && rc == 0; k++) {
            const nc_ckpt_entry *e = &t->entries[k];
            size_t bytes = e->count * e->width * nc_ckpt_type_size(e->type);
            if (!(bufs[k] = malloc(bytes ? bytes : 1)))
                rc = nc_error_set(err, 1, "%s: out of memory for %s", path, e->name);
            else
                rc = read_entry(f, path, e, bufs[k], err);
        }
    } H5E_END_TRY;
    H5Fclose(f);
    /* everything was read: only now are the entries' data replaced */
    for (size_t k = 0; rc == 0 && k < t->n; k++) {
        const nc_ckpt_entry *e = &t->entries[k];
        if (!e->count) continue;
        if (packed(e)) memcpy(e->data, bufs[k], e->count * e->width * nc_ckpt_type_size(e->type));
        else gather(e, bufs[k], 1);
    }
    for (size_t k = 0; bufs && k < t->n; k++) free(bufs[k]);
    free(bufs);
    return rc ? -1 : 0;
}

int nc_ckpt_read_scalar(const char *path, const char *name, nc_ckpt_type type, void *value,
                        nc_error *err)
{
    nc_ckpt_table t = {0};
    nc_ckpt_add(&t, NULL, name, type, value, 1);
    int rc = nc_ckpt_load(&t, path, err);
    nc_ckpt_table_free(&t);
    return rc;
}

/* ---- pruning -------------------------------------------------------------------------- */

static int ends_with(const char *s, size_t len, const char *tail)
{
    size_t n = strlen(tail);
    return len > n && strcmp(s + len - n, tail) == 0;
}

void nc_ckpt_prune_except(const char *dir, const char *prefix, const char *const *keep,
                          size_t n_keep)
{
    DIR *d = opendir(dir);
    if (!d) return;
    size_t np = strlen(prefix);
    struct dirent *de;
    while ((de = readdir(d)) != NULL) {
        const char *f = de->d_name;
        size_t len = strlen(f);
        if (strncmp(f, prefix, np) != 0 || len <= np ||
            !(ends_with(f, len, ".h5") || ends_with(f, len, ".h5.tmp")))
            continue;
        int kept = 0;
        for (size_t k = 0; k < n_keep && !kept; k++) kept = keep[k] && keep[k][0] && strcmp(f, keep[k]) == 0;
        if (kept) continue;
        char path[4400];
        snprintf(path, sizeof path, "%s/%s", dir, f);
        unlink(path);
    }
    closedir(d);
}

typedef struct ckpt_file {
    char name[256];
    long step;
    double mtime_s;
} ckpt_file;

/* Newer first: by step, then by modification time. */
static int newer_first(const void *a, const void *b)
{
    const ckpt_file *x = a, *y = b;
    if (x->step != y->step) return x->step > y->step ? -1 : 1;
    return x->mtime_s > y->mtime_s ? -1 : x->mtime_s < y->mtime_s;
}

void nc_ckpt_prune_by_step(const char *dir, const char *prefix, const char *keep,
                           const char *step_entry, long step, size_t n_older)
{
    DIR *d = opendir(dir);
    if (!d) return;
    ckpt_file *files = NULL;
    size_t n = 0, cap = 0, np = strlen(prefix);
    struct dirent *de;
    while ((de = readdir(d)) != NULL) {
        const char *f = de->d_name;
        size_t len = strlen(f);
        if (strncmp(f, prefix, np) != 0 || len <= np + 3 || len >= sizeof files->name ||
            !ends_with(f, len, ".h5") || strcmp(f, keep) == 0)
            continue;
        char path[4400];
        snprintf(path, sizeof path, "%s/%s", dir, f);
        long s = -1;
        struct stat st;
        nc_error ignored;
        if (nc_ckpt_read_scalar(path, step_entry, NC_CKPT_LONG, &s, &ignored) || s > step ||
            stat(path, &st) != 0)
            continue;
        if (n == cap) {
            size_t c = cap ? 2 * cap : 16;
            ckpt_file *g = realloc(files, c * sizeof *g);
            if (!g) break;   /* nothing more is deleted */
            files = g;
            cap = c;
        }
        snprintf(files[n].name, sizeof files[n].name, "%s", f);
        files[n].step = s;
        files[n].mtime_s = (double)st.st_mtim.tv_sec + 1e-9 * (double)st.st_mtim.tv_nsec;
        n++;
    }
    closedir(d);
    if (n) qsort(files, n, sizeof *files, newer_first);
    for (size_t k = n_older; k < n; k++) {
        char path[4400];
        snprintf(path, sizeof path, "%s/%s", dir, files[k].name);
        unlink(path);
    }
    free(files);
}
