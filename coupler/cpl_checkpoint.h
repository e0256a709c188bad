/* cpl_checkpoint — the coupler's own checkpoint: a table of {name, pointer, count} entries
 * that is written to and read back from one HDF5 file, bit for bit.
 *
 * Each module that holds state the rest of a run depends on adds its entries (the loop:
 * cpl_loop_checkpoint_entries; a relaxation method: its `checkpoint` operation,
 * cpl_relax_ops.h; the program: its output counters). The same table is used to save and to
 * load, so what is saved and what is loaded cannot drift apart. Entries are datasets named
 * by the entry ("/loop/u"); doubles are stored as IEEE doubles (NAN and INFINITY included),
 * integers as 64-bit integers. Loading requires every entry with exactly its count: a
 * checkpoint of another model or coupler.json fails naming the file and the entry.
 * cpl_ckpt_save writes a temporary file, flushes it to disk (fsync) and renames it into
 * place, so a crash leaves the old file or the new one, never half of one.
 */
#ifndef CPL_CHECKPOINT_H
#define CPL_CHECKPOINT_H

#include <stddef.h>
#include "nc_error.h"

typedef enum { CPL_CKPT_F64 = 0, CPL_CKPT_LONG, CPL_CKPT_INT, CPL_CKPT_SIZE } cpl_ckpt_type;

typedef struct cpl_ckpt_entry {
    char name[96];          /* dataset path, e.g. "/loop/u" */
    cpl_ckpt_type type;
    void *data;
    size_t count;           /* values (0 allowed) */
} cpl_ckpt_entry;

typedef struct cpl_ckpt_table {
    cpl_ckpt_entry *entries;
    size_t n, capacity;
    int failed;             /* an add ran out of memory or had a bad name (reported by save/load) */
} cpl_ckpt_table;

/* Adds one entry ("/" + prefix + "/" + name when prefix is not empty); a failure is kept in
 * the table and reported by cpl_ckpt_save / cpl_ckpt_load, so callers can add in a row. */
void cpl_ckpt_add(cpl_ckpt_table *t, const char *prefix, const char *name, cpl_ckpt_type type,
                  void *data, size_t count);
#define cpl_ckpt_f64(t, prefix, name, p, n) cpl_ckpt_add(t, prefix, name, CPL_CKPT_F64, (p), (n))
#define cpl_ckpt_long(t, prefix, name, p) cpl_ckpt_add(t, prefix, name, CPL_CKPT_LONG, (p), 1)
#define cpl_ckpt_int(t, prefix, name, p) cpl_ckpt_add(t, prefix, name, CPL_CKPT_INT, (p), 1)
#define cpl_ckpt_size(t, prefix, name, p) cpl_ckpt_add(t, prefix, name, CPL_CKPT_SIZE, (p), 1)
void cpl_ckpt_table_free(cpl_ckpt_table *t);

/* Writes every entry to `path` (tmp file, fsync, rename, fsync of the folder). */
int cpl_ckpt_save(const cpl_ckpt_table *t, const char *path, nc_error *err);
/* Reads every entry from `path` into its data. */
int cpl_ckpt_load(const cpl_ckpt_table *t, const char *path, nc_error *err);
/* One integer entry of a file, before the table can be built (sizes of arrays that vary). */
int cpl_ckpt_read_long(const char *path, const char *name, long *value, nc_error *err);

/* Writes `text` to `path` durably (tmp file, fsync, rename, fsync of the folder). */
int cpl_ckpt_write_text(const char *path, const char *text, nc_error *err);

#endif
