/* dem_checkpoint — the complete state of a coupled DEM run in one HDF5 file: what CHECKPOINT
 * saves and RESUME loads (protocol/README.md §3.3), so that a resumed run replies bit for bit
 * what the uninterrupted one replies.
 *
 * Contract: the state is a table of items {dataset, type, first value, elements, values per
 * element, stride}, built in one function of dem_checkpoint.c from the simulation's parts and
 * the output counters (a new state array is one line there), plus the caller's own items (the
 * participant's last nodal force and output time). dem_checkpoint_save() writes every item and
 * the identity of the model (counts of spheres, bodies, clusters, materials, planes, meshes,
 * interface nodes and elements, the DEM step, radii, masses, interface coordinates) to
 * PATH.tmp, flushes it to the disk (fsync), renames it to PATH and syncs the folder: once it
 * returns, the checkpoint survives a crash. dem_checkpoint_load() checks that PATH is a
 * dem_solver checkpoint of this model, step and time (the error names the file and what
 * differs), reads every item into memory and only then replaces the state, so a failed load
 * leaves the simulation as it was.
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
#include "nc_error.h"

/* How an item's values are held in memory (in the file: f64 for the first three, i32 else;
 * long and size_t are exact in a double up to 2^53). */
typedef enum {
    DEM_CK_F64,    /* double */
    DEM_CK_LONG,   /* long */
    DEM_CK_SIZE,   /* size_t */
    DEM_CK_I32,    /* int32_t */
    DEM_CK_INT,    /* int */
    DEM_CK_U8      /* uint8_t */
} dem_ck_type;

/* One array of the state: `count` elements of `width` values each, the first at `data`, one
 * element `stride` bytes after the other (0: packed, width values). Stored as the dataset
 * `name`, [count] for width 1, else [count, width]. */
typedef struct dem_ck_item {
    const char *name;
    dem_ck_type type;
    void *data;
    size_t count, width, stride;
} dem_ck_item;

/* Saves the state of s and the counters of o, and the caller's items, as the checkpoint of
 * `step` steps accepted at `time_s` (the command's values) under `name`. */
int dem_checkpoint_save(const char *path, const char *name, dem_sim *s, dem_output *o,
                        const dem_ck_item *extra, size_t n_extra, long step, double time_s,
                        nc_error *err);

/* Loads the checkpoint at path into s, o's counters and the caller's items (the same list as
 * at saving, sized for this model), after checking model, step and time. o's files are not
 * touched: dem_output_resume() reopens them from the counters loaded. */
int dem_checkpoint_load(const char *path, dem_sim *s, dem_output *o, const dem_ck_item *extra,
                        size_t n_extra, long step, double time_s, nc_error *err);

#endif
