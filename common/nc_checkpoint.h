/* nc_checkpoint — a program's checkpoint (protocol/README.md §3.3): a table of entries
 * {name, type, pointer, count} saved to one HDF5 file and loaded back bit for bit.
 *
 * Contract:
 * - The same table saves and loads, so what is saved and what is loaded cannot drift apart.
 *   Adding never fails on the spot: running out of memory or a bad name is kept in the table
 *   and reported by save and load, so callers add in a row.
 * - One dataset per entry, named by the entry ("/loop/u"; parent groups are created): [count]
 *   values, or [rows, width] for entries added as rows. Doubles are stored as IEEE doubles
 *   unconverted (NaN payloads, ±0, subnormals kept), int and int32 as 32-bit, long and int64
 *   as 64-bit, size_t as unsigned 64-bit, u8 as 8-bit integers.
 * - nc_ckpt_save builds the file in memory and writes it with nc_file_write_durably (PATH.tmp,
 *   fsync, rename, fsync of the folder): once it returns 0 the file survives a crash; on an
 *   error the previous PATH is as it was, no PATH.tmp is left, and the message names the file
 *   and the operating system's reason.
 * - nc_ckpt_load requires every entry, of its kind, with exactly its count (and width), else
 *   an error naming the file and the entry. It reads everything before it changes anything:
 *   on an error no entry's data has changed.
 * - Pruning deletes a program's older checkpoint files in a folder by one of two rules
 *   (below); files of other programs (other prefixes) are never touched.
 */
#ifndef NC_CHECKPOINT_H
#define NC_CHECKPOINT_H

#include <stddef.h>

#include "nc_error.h"

typedef enum {
    NC_CKPT_F64,    /* double */
    NC_CKPT_I32,    /* int32_t */
    NC_CKPT_INT,    /* int */
    NC_CKPT_LONG,   /* long */
    NC_CKPT_I64,    /* int64_t */
    NC_CKPT_SIZE,   /* size_t */
    NC_CKPT_U8      /* uint8_t, unsigned char */
} nc_ckpt_type;

typedef struct nc_ckpt_entry {
    char name[96];          /* dataset path, always starting with '/' */
    nc_ckpt_type type;
    void *data;             /* the first value */
    size_t count, width;    /* count elements (rows) of width values */
    size_t stride;          /* bytes from one element to the next (0: packed) */
} nc_ckpt_entry;

typedef struct nc_ckpt_table {
    nc_ckpt_entry *entries;
    size_t n, capacity;
    int failed;             /* an add ran out of memory or had a bad name */
} nc_ckpt_table;            /* {0} is an empty table */

/* Adds `count` values at data as "/prefix/name" ("/name" when prefix is NULL or ""; a leading
 * '/' of name is not doubled). data may be NULL when count is 0. */
void nc_ckpt_add(nc_ckpt_table *t, const char *prefix, const char *name, nc_ckpt_type type,
                 void *data, size_t count);
/* Adds `rows` elements of `width` values each, one element `stride` bytes after the other
 * (0: packed), stored as [rows, width] (as [rows] when width is 1). */
void nc_ckpt_add_rows(nc_ckpt_table *t, const char *prefix, const char *name,
                      nc_ckpt_type type, void *data, size_t rows, size_t width, size_t stride);
#define nc_ckpt_f64(t, prefix, name, p, n) nc_ckpt_add(t, prefix, name, NC_CKPT_F64, (p), (n))
#define nc_ckpt_int(t, prefix, name, p) nc_ckpt_add(t, prefix, name, NC_CKPT_INT, (p), 1)
#define nc_ckpt_long(t, prefix, name, p) nc_ckpt_add(t, prefix, name, NC_CKPT_LONG, (p), 1)
#define nc_ckpt_size(t, prefix, name, p) nc_ckpt_add(t, prefix, name, NC_CKPT_SIZE, (p), 1)
/* Adds every entry of `from` (may be NULL) to t; a failure of `from` carries over. */
void nc_ckpt_add_table(nc_ckpt_table *t, const nc_ckpt_table *from);
/* Empties t (its memory is kept for the next adds). */
void nc_ckpt_clear(nc_ckpt_table *t);
void nc_ckpt_table_free(nc_ckpt_table *t);
/* Bytes of one value of the type in memory. */
size_t nc_ckpt_type_size(nc_ckpt_type type);

/* Writes every entry to `path`, durably (above). */
int nc_ckpt_save(const nc_ckpt_table *t, const char *path, nc_error *err);
/* Reads every entry of t from `path` into its data, all or nothing (above). */
int nc_ckpt_load(const nc_ckpt_table *t, const char *path, nc_error *err);
/* One value of `path`, before the table can be built (sizes of arrays that vary). */
int nc_ckpt_read_scalar(const char *path, const char *name, nc_ckpt_type type, void *value,
                        nc_error *err);

/* Deletes the files <prefix>*.h5 and <prefix>*.h5.tmp of folder `dir` except the n_keep
 * files named in keep (file names; NULL or "" entries are skipped). */
void nc_ckpt_prune_except(const char *dir, const char *prefix, const char *const *keep,
                          size_t n_keep);
/* Of the files <prefix>*.h5 of folder `dir` other than `keep` (the one just written) whose
 * integer entry `step_entry` is at most `step`, keeps the n_older newest (by that step, then
 * by modification time) and deletes the others. Files of later steps and files whose step
 * cannot be read are left alone. */
void nc_ckpt_prune_by_step(const char *dir, const char *prefix, const char *keep,
                           const char *step_entry, long step, size_t n_older);

#endif
