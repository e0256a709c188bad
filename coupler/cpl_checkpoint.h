/* cpl_checkpoint — the coupler's own checkpoint, checkpoint/coupler_<name>.h5: the coupler's
 * names for the checkpoint table of common/nc_checkpoint.h, which saves it durably and loads
 * it bit for bit (every entry with exactly its count, else an error naming the file and the
 * entry: a checkpoint of another model or coupler.json).
 *
 * Each module that holds state the rest of a run depends on adds its entries under its own
 * prefix (the loop: cpl_loop_checkpoint_entries; a relaxation method: its `checkpoint`
 * operation, cpl_relax_ops.h; the history: cpl_history_checkpoint_entries; the program: its
 * output counters, main.c, which also writes the manifest latest.json and prunes).
 */
#ifndef CPL_CHECKPOINT_H
#define CPL_CHECKPOINT_H

#include "nc_checkpoint.h"

typedef nc_ckpt_table cpl_ckpt_table;
typedef nc_ckpt_type cpl_ckpt_type;
#define CPL_CKPT_F64 NC_CKPT_F64
#define CPL_CKPT_LONG NC_CKPT_LONG
#define CPL_CKPT_INT NC_CKPT_INT
#define CPL_CKPT_SIZE NC_CKPT_SIZE

#define cpl_ckpt_add nc_ckpt_add
#define cpl_ckpt_f64 nc_ckpt_f64
#define cpl_ckpt_long nc_ckpt_long
#define cpl_ckpt_int nc_ckpt_int
#define cpl_ckpt_size nc_ckpt_size
#define cpl_ckpt_table_free nc_ckpt_table_free
#define cpl_ckpt_save nc_ckpt_save
#define cpl_ckpt_load nc_ckpt_load

/* One integer entry of a file, before the table can be built (sizes of arrays that vary). */
static inline int cpl_ckpt_read_long(const char *path, const char *name, long *value,
                                     nc_error *err)
{
    return nc_ckpt_read_scalar(path, name, NC_CKPT_LONG, value, err);
}

/* DIR/checkpoint/coupler_<name>.h5 into out (DIR: the output folder). */
void cpl_checkpoint_path(const char *output_dir, const char *name, char *out, size_t size);

#endif
