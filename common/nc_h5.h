/* nc_h5 — small HDF5 writing layer shared by the three programs.
 *
 * Files are created fresh (truncating) or reopened to append (nc_h5_open), datasets are addressed by absolute paths whose
 * parent groups are created on demand, and time series grow along their first dimension
 * one row at a time. nc_h5_flush() keeps everything written so far readable if the process
 * is later stopped or killed (the file stays in the default, pre-1.10 format, which has no
 * "file open for writing" flag to clear after a crash); a file whose rows wait in memory
 * (nc_h5_set_buffered) is then as its last flush left it.
 *
 * Write errors (a full disk): the message names the file, what failed and the operating
 * system's reason ("No space left on device"); the file is then marked failed, nothing more
 * is written to it and nc_h5_close() leaves it as the last successful flush wrote it (HDF5
 * can neither flush nor safely close it). Each write and flush first takes the disk space
 * it may need past the file's end (fallocate, the file's size unchanged; given back at
 * close), so that a full disk stops it before any of it reaches the file: a flush that
 * failed part way could leave the file unreadable. Not covered: file systems without
 * fallocate (ext2, some network file systems), where the write goes ahead without, and
 * copy-on-write ones (btrfs, ZFS), where rewriting a block in place needs new space too. HDF5's exit handler is switched off for the same
 * reason: every program closes its files itself.
 */
#ifndef NC_H5_H
#define NC_H5_H

#include <hdf5.h>
#include <stddef.h>
#include "nc_error.h"

struct nc_h5_series;
typedef struct nc_h5_file {
    hid_t file;
    char path[512];
    int failed;         /* a write or flush failed: nothing more is written (see nc_h5_close) */
    char failure[200];  /* the first failure's reason, repeated by every later refusal */
    int buffered;       /* series rows wait in memory for nc_h5_flush (nc_h5_set_buffered) */
    double flushed_at_s;   /* nc_clock_now_s() at the last flush (or when opened) */
    struct nc_h5_series **series;   /* buffered: the open series, which nc_h5_flush writes */
    int n_series, cap_series;
    int reserved;             /* disk space was taken past the file's end (given back at close) */
} nc_h5_file;

typedef enum { NC_H5_F64, NC_H5_I32 } nc_h5_type;

/* A dataset that grows along dimension 0: rank 1 (steps), 2 (steps × a) or 3 (steps × a × b). */
typedef struct nc_h5_series {
    hid_t dataset;
    nc_h5_type type;
    int rank;
    hsize_t dims[3];
    char name[256];
    nc_h5_file *owner;
    hsize_t chunk_rows;              /* rows per chunk of the dataset */
    unsigned char *pending;          /* buffered file: rows appended since the last flush */
    size_t pending_rows, pending_cap;
} nc_h5_series;

int nc_h5_create(nc_h5_file *f, const char *path, nc_error *err);
/* Opens an existing file for writing (a resumed run appends to its results); nc_h5_write of
 * a dataset that exists replaces it, attributes are replaced too. */
int nc_h5_open(nc_h5_file *f, const char *path, nc_error *err);
int nc_h5_flush(nc_h5_file *f, nc_error *err);
/* From now on (call it before the file's series are created or opened) the rows appended
 * to the file's series wait in memory, and nc_h5_flush writes each series' rows in one go
 * before flushing the file (nc_h5_series_close and nc_h5_close write what waits, too). No
 * series row reaches the file between two flushes, so a process killed there leaves its
 * series as the last flush wrote them; a writer that appends rows often flushes only every
 * so often instead of after each row (coupler/cpl_history.c). Datasets and attributes
 * written directly (nc_h5_write, nc_h5_attr_*) still go to the file at once. */
void nc_h5_set_buffered(nc_h5_file *f);
/* The buffered files' write policy: nc_h5_flush once NC_H5_FLUSH_INTERVAL_S or more of wall
 * time passed since the file's last flush (or its opening). 1 when it wrote, 0 when not due
 * yet, -1 on a write error. Writing after every step took a third of the coupler's own
 * time, and HDF5 an eighth of the DEM's, in runs of small steps (docs/notes/interface_jacobian.md,
 * "Speed"). Called after every row it adds, a writer leaves unwritten when it is killed only
 * the rows it added within that interval after its last write. */
#define NC_H5_FLUSH_INTERVAL_S 0.25
int nc_h5_flush_due(nc_h5_file *f, nc_error *err);
/* nc_h5_flush, then the file to the disk (fsync): rows a checkpoint counts survive a crash of
 * the machine, not only of the process. */
int nc_h5_sync(nc_h5_file *f, nc_error *err);
void nc_h5_close(nc_h5_file *f);           /* safe on a zeroed or already closed struct */

/* Fixed-size datasets: rank 1..3, dims[rank]. */
int nc_h5_write(nc_h5_file *f, const char *path, nc_h5_type type, int rank,
                const hsize_t *dims, const void *data, nc_error *err);
/* Scalar attribute on an existing object (group or dataset) or on "/" */
int nc_h5_attr_double(nc_h5_file *f, const char *object, const char *name, double value,
                      nc_error *err);
int nc_h5_attr_string(nc_h5_file *f, const char *object, const char *name, const char *value,
                      nc_error *err);

/* row_dims has rank-1 entries (NULL for rank 1). */
int nc_h5_series_create(nc_h5_file *f, nc_h5_series *s, const char *path, nc_h5_type type,
                        int rank, const hsize_t *row_dims, nc_error *err);
/* Appends one row of prod(row_dims) values (on a buffered file: in memory, until the next
 * flush). */
int nc_h5_series_append(nc_h5_series *s, const void *row, nc_error *err);
void nc_h5_series_close(nc_h5_series *s);
/* Opens an existing series of an opened file for appending, checking type, rank and row_dims,
 * and cuts it to its first keep_rows rows (what it held at a checkpoint; an error when it
 * holds fewer). */
int nc_h5_series_open(nc_h5_file *f, nc_h5_series *s, const char *path, nc_h5_type type,
                      int rank, const hsize_t *row_dims, hsize_t keep_rows, nc_error *err);
hsize_t nc_h5_series_rows(const nc_h5_series *s);   /* rows appended (0 if not open) */

/* The same with a "units" string attribute on the dataset ("m", "N", "m/s", "1", ...). */
int nc_h5_write_units(nc_h5_file *f, const char *path, nc_h5_type type, int rank,
                      const hsize_t *dims, const void *data, const char *units, nc_error *err);
int nc_h5_series_create_units(nc_h5_file *f, nc_h5_series *s, const char *path, nc_h5_type type,
                              int rank, const hsize_t *row_dims, const char *units,
                              nc_error *err);

/* XDMF text of one row of a series: the XDMF 3 HDF DataItem whose heavy-data reference
 * "FILE:DATASET|start:stride:count:space" selects row `row` of a dataset with row_rank
 * further dimensions row_dims (so "Dimensions" is row_dims). ParaView's default XDMF reader
 * (Xdmf3) reads this form; its HyperSlab DataItem it does not. The space named is
 * (row + 1) x row_dims, which the dataset holds once the row is written, so the text of a
 * row never changes as the series grows. Returns the length written (snprintf rules). */
int nc_xdmf_row_item(char *out, size_t cap, const char *h5_file, const char *dataset,
                     long row, int row_rank, const hsize_t *row_dims, nc_h5_type type);

/* Turns off HDF5's own error stack printing (messages go through nc_error instead). */
void nc_h5_quiet(void);

#endif
