/* dem_checkpoint — the complete state of a coupled DEM run in one HDF5 file: what CHECKPOINT
 * saves and RESUME loads (protocol/README.md §3.3), so that a resumed run replies bit for bit
 * what the uninterrupted one replies.
 *
 * Contract: the state is a checkpoint table (common/nc_checkpoint.h: entries {dataset, type,
 * first value, elements, values per element, stride}), built in one function of
 * dem_checkpoint.c from the simulation's parts and the output counters (a new state array is
 * one line there), plus the caller's own entries (the participant's last nodal force and
 * output time). dem_checkpoint_save() writes every entry and the identity of the model (counts
 * of spheres, bodies, clusters, materials, planes, meshes, interface nodes and elements, the
 * DEM step, radii, masses, interface coordinates) durably (PATH.tmp, fsync, rename, fsync of
 * the folder): once it returns, the checkpoint survives a crash. dem_checkpoint_load() checks
 * that PATH is a dem_solver checkpoint of this model, step and time (the error names the file
 * and what differs), then loads the state all or nothing, so a failed load leaves the
 * simulation as it was.
 * Not stored, because the same dem.json and INTERFACE give it again or it is rebuilt before
 * use: parameters, materials, masses and inertia, the pair table, the net's edge grid (rebuilt
 * every sub-step), the start-of-step snapshot (taken at BEGIN_STEP), the Jacobian's record (of
 * one solve) and the contact pass's scratch buffers.
 */
#ifndef DEM_CHECKPOINT_H
#define DEM_CHECKPOINT_H

#include <stddef.h>

#include "dem_output.h"
#include "dem_sim.h"
#include "nc_checkpoint.h"
#include "nc_error.h"

/* Saves the state of s and the counters of o, and the caller's items, as the checkpoint of
 * `step` steps accepted at `time_s` (the command's values) under `name`. */
int dem_checkpoint_save(const char *path, const char *name, dem_sim *s, dem_output *o,
                        const nc_ckpt_table *extra, long step, double time_s, nc_error *err);

/* Loads the checkpoint at path into s, o's counters and the caller's items (the same list as
 * at saving, sized for this model), after checking model, step and time. o's files are not
 * touched: dem_output_resume() reopens them from the counters loaded. */
int dem_checkpoint_load(const char *path, dem_sim *s, dem_output *o, const nc_ckpt_table *extra,
                        long step, double time_s, nc_error *err);

#endif
