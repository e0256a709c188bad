/* fem_checkpoint — the FEM's checkpoint file DIR/checkpoint/fem_<name>.h5: everything the rest
 * of a run depends on, saved between steps, and loaded into a freshly started solver of the
 * same model so that it continues bit for bit as if it had never stopped
 * (protocol/README.md §3.3).
 *
 * What is saved is one table of entries {name, type, pointer, count} (common/nc_checkpoint.h;
 * fem_checkpoint.c: analysis_entries, output_entries): save writes every entry as a dataset,
 * load reads every entry back and checks that the file has it with exactly that count, so a
 * new history array is one line in the table. Three parts are not copied but rebuilt from what defines them,
 * because the solver derives them (and CHOLMOD's ordering) from it:
 *   the sparse pattern — the extra node pairs a linearisation added
 *                        (fem_analysis_set_pattern_pairs: the same pairs give the same
 *                        pattern and ordering);
 *   the interface linearisation of the last solve — its blocks (fem_ijac_set);
 *   the factorisations modified Newton keeps (current and saved) — the matrix values they
 *                        were computed from (fem_sparse_refactor: the same values on the same
 *                        pattern give the same factors).
 * The caller adds its own entries (run counters, next output time) in `extra`.
 * The file also holds the model's counts (nodes, elements, dofs, free equations, interface
 * and monitor nodes) and checksums of its geometry, properties, supports and loads; a
 * checkpoint of another model is refused naming what differs.
 *
 * The file is common/nc_checkpoint's (durable save, every entry checked on load). After a
 * save older fem checkpoints are deleted: the one just written and the newest one before it
 * (by step) are kept; checkpoints of later steps (from before a resume to an earlier one) and
 * files that cannot be read are left alone.
 */
#ifndef FEM_CHECKPOINT_H
#define FEM_CHECKPOINT_H

#include <stddef.h>
#include "fem_analysis.h"
#include "fem_output.h"
#include "nc_checkpoint.h"
#include "nc_error.h"

/* 0 when `name` is a checkpoint name (1-64 letters, digits, '_', '-'), else -1 naming it. */
int fem_checkpoint_name_check(const char *name, nc_error *err);
/* DIR/checkpoint/fem_<name>.h5 into out. */
void fem_checkpoint_path(const char *dir, const char *name, char *out, size_t size);

/* Saves the state of s and o and the caller's entries (extra, may be NULL) as checkpoint
 * `name` of step `step` (steps accepted so far) at time_s; the folder is created. */
int fem_checkpoint_save(const char *dir, const char *name, long step, double time_s,
                        fem_analysis *s, fem_output *o, const nc_ckpt_table *extra, nc_error *err);

/* Loads checkpoint `name` into s (initialised for the same model), o (not open; its n_out,
 * times, n_mon, max |u| and peak force fields are set, for fem_output_reopen) and the extra entries,
 * after checking that it is of this model and of `step` at time_s. Errors name the file and
 * what is wrong (missing, unreadable, another model, another step). On an error s, o and the
 * extra fields may be partly overwritten: the caller starts them afresh. */
int fem_checkpoint_load(const char *dir, const char *name, long step, double time_s,
                        fem_analysis *s, fem_output *o, const nc_ckpt_table *extra, nc_error *err);

#endif
