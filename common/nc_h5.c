/* nc_h5 — HDF5 helpers: create file, groups on demand, fixed datasets, growing series. */
#define _GNU_SOURCE   /* fallocate */
#include "nc_h5.h"

#include "nc_clock.h"

#include <errno.h>
#include <fcntl.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

static hid_t mem_type(nc_h5_type type)
{
    return type == NC_H5_F64 ? H5T_NATIVE_DOUBLE : H5T_NATIVE_INT32;
}

static hid_t file_type(nc_h5_type type)
{
    return type == NC_H5_F64 ? H5T_IEEE_F64LE : H5T_STD_I32LE;
}

/* HDF5's error stack of the call that just failed: the operating system's reason
 * ("No space left on device") where the file driver reported one, else the innermost
 * message, else errno. */
static herr_t walk_reason(unsigned n, const H5E_error2_t *e, void *data)
{
    char *out = data;
    const char *desc = e->desc ? e->desc : "";
    const char *m = strstr(desc, "error message = '");
    if (m) {
        m += strlen("error message = '");
        const char *end = strchr(m, '\'');
        int len = end ? (int)(end - m) : (int)strlen(m);
        snprintf(out, 200, "%.*s", len, m);
        return 1;   /* stop: the OS reason is the best there is */
    }
    if (n == 0 && desc[0]) snprintf(out, 200, "%s", desc);
    return 0;
}

static const char *reason(char *buf, int saved_errno)
{
    buf[0] = '\0';
    H5Ewalk2(H5E_DEFAULT, H5E_WALK_UPWARD, walk_reason, buf);
    if (!buf[0]) snprintf(buf, 200, "%s", saved_errno ? strerror(saved_errno) : "HDF5 error");
    return buf;
}

/* Records a failed write: the message names the file, what failed and why; the file is marked
 * failed so that nothing more is written to it. */
static int fail(nc_h5_file *f, nc_error *err, const char *what, const char *object)
{
    int saved = errno;
    char why[200];
    reason(why, saved);
    if (!f->failed) snprintf(f->failure, sizeof f->failure, "%s", why);
    f->failed = 1;
    return nc_error_set(err, 1, "%s: %s %s: %s", f->path, what, object, why);
}

/* What a write may add to the file besides what HDF5 has already allocated (its end of
 * allocation, H5Fget_eoa) and the chunks it starts: the chunk index's new nodes (a v1 B-tree
 * node is about 3 KiB; a root that splits takes two, which the margin covers), the
 * metadata aggregator's next 2 KiB block. Measured with every write traced, a flush went at
 * most 2 KiB past the chunks and HDF5's allocation without the margin and 22 KiB without the
 * index terms too; the margin makes a nearly full disk fail 64 KiB earlier. */
#define MARGIN_BYTES (64u << 10)
#define INDEX_BYTES_PER_SERIES (4u << 10)
#define INDEX_BYTES_PER_CHUNK 512u

/* The file's descriptor under HDF5's default (sec2) driver, the only one nc_h5 uses. */
static int file_descriptor(const nc_h5_file *f)
{
    void *handle = NULL;
    if (f->file < 0 || H5Fget_vfd_handle(f->file, H5P_DEFAULT, &handle) < 0 || !handle) return -1;
    return *(int *)handle;
}

/* Takes the disk space for the next write before HDF5 starts it: the file's blocks from its
 * end for what HDF5 has allocated and not yet written (metadata waiting in its cache), the
 * `bytes` this write adds and a margin (fallocate with the file's size unchanged; blocks
 * already taken are kept). A full disk then fails the write before any of it reached the
 * file, which stays as its last flush left it: a flush that failed part way could leave the
 * superblock and the objects it points to out of step, the file unreadable ("addr
 * overflow"). Nothing to add (no new chunk, nothing allocated past the end): nothing is
 * taken, so that a run's last small writes are not refused for the margin. A file system
 * without fallocate (ext2, some network file systems) is written to without; on a
 * copy-on-write one (btrfs, ZFS) rewriting a block in place needs new space, which this does
 * not cover (nc_h5.h). */
static int reserve(nc_h5_file *f, size_t bytes, nc_error *err)
{
    int fd = file_descriptor(f);
    struct stat st;
    haddr_t allocated = 0;
    if (fd < 0 || fstat(fd, &st) != 0) return 0;
    if (H5Fget_eoa(f->file, &allocated) >= 0 && allocated > (haddr_t)st.st_size)
        bytes += (size_t)(allocated - (haddr_t)st.st_size);
    if (bytes == 0) return 0;
    errno = 0;
    if (fallocate(fd, FALLOC_FL_KEEP_SIZE, st.st_size, (off_t)(bytes + MARGIN_BYTES)) == 0) {
        f->reserved = 1;
        return 0;
    }
    if (errno == ENOSPC || errno == EDQUOT || errno == EFBIG)
        return fail(f, err, "cannot take the disk space for", "the next write");
    return 0;
}

/* Gives back the blocks taken past the end of the file: truncating a file to its own size
 * frees them. A process killed before leaves them taken until the file is next truncated or
 * deleted. */
static void release(nc_h5_file *f, int fd)
{
    struct stat st;
    if (f->reserved && fd >= 0 && fstat(fd, &st) == 0 && ftruncate(fd, st.st_size) == 0)
        f->reserved = 0;
}

void nc_h5_quiet(void)
{
    /* HDF5 1.10 crashes in its exit handler when it closes a file whose flush fails (a full
     * disk): the programs close every file themselves, so the handler is not needed. Only
     * effective before HDF5's first use, which is here (nc_h5_create calls this first). */
    H5dont_atexit();
    H5Eset_auto2(H5E_DEFAULT, NULL, NULL);
}

int nc_h5_create(nc_h5_file *f, const char *path, nc_error *err)
{
    nc_h5_quiet();
    memset(f, 0, sizeof *f);
    f->file = H5I_INVALID_HID;
    snprintf(f->path, sizeof f->path, "%s", path);
    errno = 0;
    f->file = H5Fcreate(path, H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT);
    if (f->file < 0) {
        char why[200];
        reason(why, errno);
        return nc_error_set(err, 1, "%s: cannot create HDF5 file: %s", path, why);
    }
    return 0;
}

int nc_h5_open(nc_h5_file *f, const char *path, nc_error *err)
{
    nc_h5_quiet();
    memset(f, 0, sizeof *f);
    f->file = H5I_INVALID_HID;
    snprintf(f->path, sizeof f->path, "%s", path);
    errno = 0;
    htri_t is_hdf5 = H5Fis_hdf5(path);
    if (is_hdf5 <= 0) {
        char why[200];
        reason(why, errno);
        return nc_error_set(err, 1, "%s: cannot open the HDF5 file to append to it: %s", path,
                            is_hdf5 == 0 ? "not an HDF5 file" : why);
    }
    f->file = H5Fopen(path, H5F_ACC_RDWR, H5P_DEFAULT);
    if (f->file < 0) {
        char why[200];
        reason(why, errno);
        return nc_error_set(err, 1, "%s: cannot open the HDF5 file to append to it: %s", path, why);
    }
    return 0;
}

static int write_pending(nc_h5_series *s, nc_error *err);
static int enlist(nc_h5_file *f, nc_h5_series *s, nc_error *err);
static size_t pending_bytes(const nc_h5_series *s);

void nc_h5_set_buffered(nc_h5_file *f)
{
    f->buffered = 1;
    f->flushed_at_s = nc_clock_now_s();
}

int nc_h5_flush_due(nc_h5_file *f, nc_error *err)
{
    if (nc_clock_now_s() - f->flushed_at_s < NC_H5_FLUSH_INTERVAL_S) return 0;
    return nc_h5_flush(f, err) ? -1 : 1;
}

int nc_h5_flush(nc_h5_file *f, nc_error *err)
{
    if (f->file < 0) return 0;
    if (f->failed) return nc_error_set(err, 1, "%s: not written after an earlier write error (%s)", f->path, f->failure);
    f->flushed_at_s = nc_clock_now_s();
    size_t bytes = 0;
    for (int i = 0; i < f->n_series; i++) bytes += pending_bytes(f->series[i]);
    if (reserve(f, bytes, err)) return -1;
    for (int i = 0; i < f->n_series; i++)
        if (write_pending(f->series[i], err)) return -1;
    errno = 0;
    if (H5Fflush(f->file, H5F_SCOPE_GLOBAL) < 0) return fail(f, err, "cannot flush", "the file");
    return 0;
}

int nc_h5_sync(nc_h5_file *f, nc_error *err)
{
    if (f->file < 0) return 0;
    if (nc_h5_flush(f, err)) return -1;
    void *handle = NULL;
    errno = 0;
    if (H5Fget_vfd_handle(f->file, H5P_DEFAULT, &handle) >= 0 && handle && fsync(*(int *)handle) != 0)
        return fail(f, err, "cannot flush to the disk", "the file");
    return 0;
}

void nc_h5_close(nc_h5_file *f)
{
    if (!f) return;
    if (f->file > 0 && !f->failed) nc_h5_flush(f, NULL);
    free(f->series);
    f->series = NULL;
    f->n_series = f->cap_series = 0;
    if (f->file > 0) {
        /* after a failed write HDF5 cannot flush the file and would fail (or crash) closing
         * it: it is left as the last successful flush wrote it and released by the OS */
        /* HDF5 writes its last metadata in H5Fclose, so the blocks are given back after it,
         * through a descriptor of its own */
        int fd = f->reserved ? file_descriptor(f) : -1;
        fd = fd >= 0 ? dup(fd) : -1;
        if (!f->failed && H5Fclose(f->file) < 0) f->failed = 1;
        release(f, fd);
        if (fd >= 0) close(fd);
        f->file = H5I_INVALID_HID;
    }
}

/* Creates every missing group on the way to the parent of `path` ("/a/b/data" -> /a, /a/b). */
static int make_parents(nc_h5_file *f, const char *path, nc_error *err)
{
    char buf[512];
    snprintf(buf, sizeof buf, "%s", path);
    for (char *slash = strchr(buf + 1, '/'); slash; slash = strchr(slash + 1, '/')) {
        *slash = '\0';
        htri_t exists = H5Lexists(f->file, buf, H5P_DEFAULT);
        if (exists < 0) return nc_error_set(err, 1, "%s: bad HDF5 path %s", f->path, buf);
        if (!exists) {
            if (reserve(f, 0, err)) return -1;
            errno = 0;
            hid_t group = H5Gcreate2(f->file, buf, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
            if (group < 0) return fail(f, err, "cannot create group", buf);
            H5Gclose(group);
        }
        *slash = '/';
    }
    return 0;
}

int nc_h5_write(nc_h5_file *f, const char *path, nc_h5_type type, int rank,
                const hsize_t *dims, const void *data, nc_error *err)
{
    if (rank < 1 || rank > 3) return nc_error_set(err, 1, "%s: %s: rank %d not supported", f->path, path, rank);
    if (f->failed) return nc_error_set(err, 1, "%s: %s not written after an earlier write error (%s)", f->path, path, f->failure);
    if (make_parents(f, path, err)) return -1;
    size_t bytes = type == NC_H5_F64 ? sizeof(double) : sizeof(int32_t);
    for (int i = 0; i < rank; i++) bytes *= (size_t)dims[i];
    if (reserve(f, bytes, err)) return -1;
    /* a file reopened to append to (a resumed run) already holds the end-of-run datasets */
    if (H5Lexists(f->file, path, H5P_DEFAULT) > 0 && H5Ldelete(f->file, path, H5P_DEFAULT) < 0)
        return fail(f, err, "cannot replace dataset", path);
    errno = 0;
    hid_t space = H5Screate_simple(rank, dims, NULL);
    hid_t dataset = H5Dcreate2(f->file, path, file_type(type), space, H5P_DEFAULT, H5P_DEFAULT,
                               H5P_DEFAULT);
    int rc = 0;
    if (dataset < 0) {
        rc = fail(f, err, "cannot create dataset", path);
    } else {
        hsize_t total = 1;
        for (int i = 0; i < rank; i++) total *= dims[i];
        if (total > 0 && H5Dwrite(dataset, mem_type(type), H5S_ALL, H5S_ALL, H5P_DEFAULT, data) < 0)
            rc = fail(f, err, "cannot write dataset", path);
        H5Dclose(dataset);
    }
    H5Sclose(space);
    return rc;
}

static int write_attr(nc_h5_file *f, const char *object, const char *name, hid_t type,
                      const void *value, nc_error *err)
{
    if (f->failed) return nc_error_set(err, 1, "%s: attribute %s not written after an earlier write error (%s)", f->path, name, f->failure);
    if (reserve(f, 0, err)) return -1;   /* the value goes into the object's header */
    errno = 0;
    hid_t space = H5Screate(H5S_SCALAR);
    if (H5Aexists_by_name(f->file, object, name, H5P_DEFAULT) > 0)
        H5Adelete_by_name(f->file, object, name, H5P_DEFAULT);
    hid_t attr = H5Acreate_by_name(f->file, object, name, type, space, H5P_DEFAULT, H5P_DEFAULT,
                                   H5P_DEFAULT);
    int rc = 0;
    if (attr < 0 || H5Awrite(attr, type, value) < 0)
        rc = fail(f, err, "cannot write attribute", name);
    if (attr >= 0) H5Aclose(attr);
    H5Sclose(space);
    return rc;
}

int nc_h5_attr_double(nc_h5_file *f, const char *object, const char *name, double value,
                      nc_error *err)
{
    return write_attr(f, object, name, H5T_NATIVE_DOUBLE, &value, err);
}

int nc_h5_attr_string(nc_h5_file *f, const char *object, const char *name, const char *value,
                      nc_error *err)
{
    hid_t type = H5Tcopy(H5T_C_S1);
    H5Tset_size(type, strlen(value) + 1);
    H5Tset_strpad(type, H5T_STR_NULLTERM);
    int rc = write_attr(f, object, name, type, value, err);
    H5Tclose(type);
    return rc;
}

int nc_h5_series_create(nc_h5_file *f, nc_h5_series *s, const char *path, nc_h5_type type,
                        int rank, const hsize_t *row_dims, nc_error *err)
{
    memset(s, 0, sizeof *s);
    s->dataset = H5I_INVALID_HID;
    if (rank < 1 || rank > 3) return nc_error_set(err, 1, "%s: %s: rank %d not supported", f->path, path, rank);
    if (f->failed) return nc_error_set(err, 1, "%s: %s not created after an earlier write error (%s)", f->path, path, f->failure);
    if (make_parents(f, path, err)) return -1;
    s->type = type;
    s->rank = rank;
    s->owner = f;
    snprintf(s->name, sizeof s->name, "%s", path);
    hsize_t maxdims[3] = {H5S_UNLIMITED, 0, 0};
    hsize_t chunk[3] = {1, 1, 1};
    s->dims[0] = 0;
    size_t row_values = 1;
    for (int i = 1; i < rank; i++) {
        s->dims[i] = maxdims[i] = chunk[i] = row_dims[i - 1] ? row_dims[i - 1] : 1;
        row_values *= (size_t)s->dims[i];
    }
    /* Aim for chunks of a few hundred kB: many rows of a small series, one row of a big one. */
    size_t rows = row_values >= 32768 ? 1 : 32768 / row_values;
    if (rows > 1024) rows = 1024;
    chunk[0] = rows;
    s->chunk_rows = rows;
    if (row_values == 0) chunk[1] = 1;
    if (reserve(f, 0, err)) return -1;
    errno = 0;
    hid_t space = H5Screate_simple(rank, s->dims, maxdims);
    hid_t props = H5Pcreate(H5P_DATASET_CREATE);
    for (int i = 1; i < rank; i++) if (chunk[i] == 0) chunk[i] = 1;
    H5Pset_chunk(props, rank, chunk);
    s->dataset = H5Dcreate2(f->file, path, file_type(type), space, H5P_DEFAULT, props, H5P_DEFAULT);
    H5Pclose(props);
    H5Sclose(space);
    if (s->dataset < 0) return fail(f, err, "cannot create dataset", path);
    return enlist(f, s, err);
}

int nc_h5_series_open(nc_h5_file *f, nc_h5_series *s, const char *path, nc_h5_type type,
                      int rank, const hsize_t *row_dims, hsize_t keep_rows, nc_error *err)
{
    memset(s, 0, sizeof *s);
    s->dataset = H5I_INVALID_HID;
    if (rank < 1 || rank > 3) return nc_error_set(err, 1, "%s: %s: rank %d not supported", f->path, path, rank);
    if (f->failed) return nc_error_set(err, 1, "%s: %s not opened after an earlier write error (%s)", f->path, path, f->failure);
    s->type = type;
    s->rank = rank;
    s->owner = f;
    snprintf(s->name, sizeof s->name, "%s", path);
    if (H5Lexists(f->file, path, H5P_DEFAULT) <= 0)
        return nc_error_set(err, 1, "%s: has no dataset %s to append to", f->path, path);
    s->dataset = H5Dopen2(f->file, path, H5P_DEFAULT);
    if (s->dataset < 0) return nc_error_set(err, 1, "%s: cannot open dataset %s", f->path, path);
    hid_t space = H5Dget_space(s->dataset);
    int file_rank = H5Sget_simple_extent_ndims(space);
    hsize_t dims[3] = {0, 0, 0};
    if (file_rank == rank) H5Sget_simple_extent_dims(space, dims, NULL);
    H5Sclose(space);
    hid_t stored = H5Dget_type(s->dataset);
    int same_type = stored >= 0 && H5Tequal(stored, file_type(type)) > 0;
    if (stored >= 0) H5Tclose(stored);
    if (file_rank != rank || !same_type)
        return nc_error_set(err, 1, "%s: dataset %s has another type or rank than this run writes",
                            f->path, path);
    for (int i = 1; i < rank; i++) {
        hsize_t want = row_dims[i - 1] ? row_dims[i - 1] : 1;
        if (dims[i] != want)
            return nc_error_set(err, 1, "%s: dataset %s has rows of %llu values in dimension %d, "
                                "this run writes %llu", f->path, path, (unsigned long long)dims[i],
                                i, (unsigned long long)want);
        s->dims[i] = dims[i];
    }
    if (dims[0] < keep_rows)
        return nc_error_set(err, 1, "%s: dataset %s has %llu rows, the checkpoint needs %llu "
                            "(the file is older than the checkpoint)", f->path, path,
                            (unsigned long long)dims[0], (unsigned long long)keep_rows);
    hid_t create = H5Dget_create_plist(s->dataset);
    hsize_t chunk[3] = {1, 1, 1};
    if (create >= 0 && H5Pget_chunk(create, 3, chunk) >= 1) s->chunk_rows = chunk[0];
    if (create >= 0) H5Pclose(create);
    s->dims[0] = keep_rows;
    if (reserve(f, 0, err)) return -1;
    errno = 0;
    if (dims[0] != keep_rows && H5Dset_extent(s->dataset, s->dims) < 0)
        return fail(f, err, "cannot truncate", path);
    return enlist(f, s, err);
}

hsize_t nc_h5_series_rows(const nc_h5_series *s)
{
    return s->dataset > 0 ? s->dims[0] + s->pending_rows : 0;
}

static size_t row_bytes(const nc_h5_series *s)
{
    size_t n = s->type == NC_H5_F64 ? sizeof(double) : sizeof(int32_t);
    for (int i = 1; i < s->rank; i++) n *= (size_t)s->dims[i];
    return n;
}

/* What writing rows more rows may add to the file: the chunks they start, in full (a chunk
 * is stored whole from its first row on), and the chunk index's share. */
static size_t rows_bytes(const nc_h5_series *s, hsize_t rows)
{
    if (rows == 0) return 0;
    hsize_t per_chunk = s->chunk_rows ? s->chunk_rows : 1;
    hsize_t chunks = (s->dims[0] + rows + per_chunk - 1) / per_chunk - (s->dims[0] + per_chunk - 1) / per_chunk;
    return chunks ? (size_t)(chunks * per_chunk) * row_bytes(s) + INDEX_BYTES_PER_SERIES + (size_t)chunks * INDEX_BYTES_PER_CHUNK : 0;
}

static size_t pending_bytes(const nc_h5_series *s)
{
    return s->dataset > 0 ? rows_bytes(s, s->pending_rows) : 0;
}

/* rows more rows at the end of the dataset */
static int write_rows(nc_h5_series *s, const void *data, hsize_t rows, nc_error *err)
{
    hsize_t new_dims[3] = {s->dims[0] + rows, s->dims[1], s->dims[2]};
    errno = 0;
    if (H5Dset_extent(s->dataset, new_dims) < 0) return fail(s->owner, err, "cannot extend", s->name);
    hid_t file_space = H5Dget_space(s->dataset);
    hsize_t start[3] = {s->dims[0], 0, 0};
    hsize_t count[3] = {rows, s->dims[1], s->dims[2]};
    H5Sselect_hyperslab(file_space, H5S_SELECT_SET, start, NULL, count, NULL);
    hid_t mem_space = H5Screate_simple(s->rank, count, NULL);
    herr_t rc = H5Dwrite(s->dataset, mem_type(s->type), mem_space, file_space, H5P_DEFAULT, data);
    H5Sclose(mem_space);
    H5Sclose(file_space);
    if (rc < 0) return fail(s->owner, err, "cannot write to", s->name);
    s->dims[0] += rows;
    return 0;
}

static int write_pending(nc_h5_series *s, nc_error *err)
{
    if (s->pending_rows == 0 || s->dataset <= 0) return 0;
    if (s->owner->failed)
        return nc_error_set(err, 1, "%s: %s not written after an earlier write error (%s)", s->owner->path, s->name, s->owner->failure);
    int rc = write_rows(s, s->pending, (hsize_t)s->pending_rows, err);
    s->pending_rows = 0;
    return rc;
}

/* A series of a buffered file joins the file's list, which nc_h5_flush writes. */
static int enlist(nc_h5_file *f, nc_h5_series *s, nc_error *err)
{
    if (!f->buffered) return 0;
    if (f->n_series == f->cap_series) {
        int cap = f->cap_series ? 2 * f->cap_series : 16;
        nc_h5_series **list = realloc(f->series, (size_t)cap * sizeof *list);
        if (!list) return nc_error_set(err, 1, "%s: out of memory for %s", f->path, s->name);
        f->series = list;
        f->cap_series = cap;
    }
    f->series[f->n_series++] = s;
    return 0;
}

static void delist(nc_h5_file *f, const nc_h5_series *s)
{
    for (int i = 0; i < f->n_series; i++)
        if (f->series[i] == s) {
            f->series[i] = f->series[--f->n_series];
            return;
        }
}

int nc_h5_series_append(nc_h5_series *s, const void *row, nc_error *err)
{
    if (s->owner->failed)
        return nc_error_set(err, 1, "%s: %s not written after an earlier write error (%s)", s->owner->path, s->name, s->owner->failure);
    if (!s->owner->buffered)
        return reserve(s->owner, rows_bytes(s, 1), err) ? -1 : write_rows(s, row, 1, err);
    const size_t bytes = row_bytes(s);
    if (s->pending_rows == s->pending_cap) {
        /* the first room for 64 rows or 1 MiB of them, whichever is fewer (a row of a large
         * model's field is megabytes), then doubled */
        size_t first = (1u << 20) / (bytes ? bytes : 1);
        size_t cap = s->pending_cap ? 2 * s->pending_cap : first < 1 ? 1 : first > 64 ? 64 : first;
        unsigned char *grown = realloc(s->pending, cap * bytes);
        if (!grown) return nc_error_set(err, 1, "%s: out of memory for %s", s->owner->path, s->name);
        s->pending = grown;
        s->pending_cap = cap;
    }
    memcpy(s->pending + s->pending_rows * bytes, row, bytes);
    s->pending_rows++;
    return 0;
}

void nc_h5_series_close(nc_h5_series *s)
{
    if (!s) return;
    if (s->dataset > 0) {
        if (!s->owner->failed && !reserve(s->owner, pending_bytes(s), NULL))
            write_pending(s, NULL);
        delist(s->owner, s);
        H5Dclose(s->dataset);
        s->dataset = H5I_INVALID_HID;
    }
    free(s->pending);
    s->pending = NULL;
    s->pending_rows = s->pending_cap = 0;
}

int nc_h5_write_units(nc_h5_file *f, const char *path, nc_h5_type type, int rank,
                      const hsize_t *dims, const void *data, const char *units, nc_error *err)
{
    if (nc_h5_write(f, path, type, rank, dims, data, err)) return -1;
    return nc_h5_attr_string(f, path, "units", units, err);
}

int nc_h5_series_create_units(nc_h5_file *f, nc_h5_series *s, const char *path, nc_h5_type type,
                              int rank, const hsize_t *row_dims, const char *units,
                              nc_error *err)
{
    if (nc_h5_series_create(f, s, path, type, rank, row_dims, err)) return -1;
    return nc_h5_attr_string(f, path, "units", units, err);
}

int nc_xdmf_row_item(char *out, size_t cap, const char *h5_file, const char *dataset,
                     long row, int row_rank, const hsize_t *row_dims, nc_h5_type type)
{
    char dims[64] = "", start[64] = "", stride[64] = "1", count[64] = "1", space[80];
    snprintf(start, sizeof start, "%ld", row);
    snprintf(space, sizeof space, "%ld", row + 1);
    for (int i = 0; i < row_rank; i++) {
        size_t used = strlen(dims);
        snprintf(dims + used, sizeof dims - used, "%s%llu", i ? " " : "", (unsigned long long)row_dims[i]);
        used = strlen(start);
        snprintf(start + used, sizeof start - used, " 0");
        used = strlen(stride);
        snprintf(stride + used, sizeof stride - used, " 1");
        used = strlen(count);
        snprintf(count + used, sizeof count - used, " %llu", (unsigned long long)row_dims[i]);
        used = strlen(space);
        snprintf(space + used, sizeof space - used, " %llu", (unsigned long long)row_dims[i]);
    }
    if (row_rank == 0) snprintf(dims, sizeof dims, "1");
    return snprintf(out, cap,
                    "<DataItem Dimensions=\"%s\" NumberType=\"%s\" Precision=\"%d\" Format=\"HDF\">"
                    "%s:%s|%s:%s:%s:%s</DataItem>",
                    dims, type == NC_H5_F64 ? "Float" : "Int", type == NC_H5_F64 ? 8 : 4, h5_file,
                    dataset, start, stride, count, space);
}
