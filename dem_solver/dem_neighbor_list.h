/* dem_neighbor_list — the Verlet list of sphere pairs that may touch, next to the cell grid
 * it is built from (dem_neighbor_grid.h).
 *
 * Contract: the list holds, for each sphere i, the spheres j > i of other bodies within
 * r_i + r_j + skin, in a fixed order (cell by cell, increasing index). dem_neighbor_list_update()
 * rebuilds it when `rebuild` is set (after a restore or a grid change, so that a repeated step
 * follows exactly the same path) or when a sphere has moved more than skin/2 since the last
 * build (max_disp2, measured by dem_integrate_bodies()); each thread lists its own range of
 * spheres and the parts are joined in range order, so the list does not depend on the thread
 * count. At every build it also rebalances the thread ranges of the contact pass and marks the
 * spheres shared between ranges (dem_thread_work in dem_contact_pass.h).
 */
#ifndef DEM_NEIGHBOR_LIST_H
#define DEM_NEIGHBOR_LIST_H

#include <stddef.h>
#include <stdint.h>

#include "dem_neighbor_grid.h"
#include "nc_error.h"

typedef struct dem_sim dem_sim;

typedef struct dem_neighbor_list {
    dem_cell_grid grid;            /* sphere centres (also used by the overlap checks) */
    double skin_m;                 /* neighbor_skin_m of the input; 0: 0.2 r_min */
    int rebuild;                   /* 1: rebuild at the next update */
    int32_t *first;                /* n_spheres + 1: first neighbour of each sphere */
    int32_t *nbr;                  /* neighbour indices */
    size_t cap;                    /* allocated entries of nbr */
    int n_parts;
    struct dem_nbr_part {          /* one per thread: its range's lists while building */
        int32_t *a;
        size_t cap;
    } *part;
    double *pos_at_build;          /* 3 per sphere */
    double max_disp2;              /* largest squared sphere displacement since the build */
    long n_builds;
} dem_neighbor_list;

/* Allocates the list of n_spheres spheres for n_parts threads; a skin of 0 becomes 0.2 r_min. */
int dem_neighbor_list_alloc(dem_neighbor_list *nl, int n_parts, size_t n_spheres, double r_min,
                            nc_error *err);
void dem_neighbor_list_free(dem_neighbor_list *nl);

/* Rebuilds the list of s's spheres if needed (see above). */
int dem_neighbor_list_update(dem_sim *s, nc_error *err);

/* Number of sphere pairs (of different bodies) whose surfaces are closer than `gap`. Uses the
 * grid with another cell size, so the next update rebuilds. */
int dem_neighbor_list_close_pairs(dem_sim *s, double gap, long *count, nc_error *err);

#endif
