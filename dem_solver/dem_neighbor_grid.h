/* dem_neighbor_grid — spatial search without all-pairs loops.
 *
 * dem_cell_grid: a cell list of sphere centres rebuilt every step by a counting sort
 * (O(n), no allocation once the capacity is reached). With cells at least as large as the
 * largest contact distance, the partners of a sphere are in its own and the 26 adjacent cells.
 * dem_item_grid: boxes (triangles, net edges) inserted into every cell their box, inflated by
 * the search distance, overlaps; a query point then needs only its own cell.
 */
#ifndef DEM_NEIGHBOR_GRID_H
#define DEM_NEIGHBOR_GRID_H

#include <stddef.h>
#include <stdint.h>
#include "nc_error.h"

typedef struct dem_cell_grid {
    double origin[3];
    double cell;           /* cell edge length */
    int dims[3];
    size_t n_cells, cells_cap;
    size_t n_items, items_cap;
    int32_t *cell_start;   /* n_cells + 1 */
    int32_t *cell_items;   /* item indices sorted by cell */
    int32_t *item_cell;    /* cell of each item */
} dem_cell_grid;

/* Sorts n points into cells of size >= min_cell. */
int dem_cell_grid_build(dem_cell_grid *g, size_t n, const double *pos, double min_cell,
                        nc_error *err);
/* Cell coordinates of a point, clamped to the grid. */
void dem_cell_grid_coords(const dem_cell_grid *g, const double p[3], int c[3]);
void dem_cell_grid_free(dem_cell_grid *g);

typedef struct dem_item_grid {
    double origin[3];
    double cell;
    int dims[3];
    size_t n_cells, cells_cap;
    size_t n_entries, entries_cap;
    int32_t *cell_start;   /* n_cells + 1 */
    int32_t *entries;      /* item indices per cell */
} dem_item_grid;

/* Inserts n items with boxes [lo, hi] (3 per item) inflated by `inflate` into the grid. */
int dem_item_grid_build(dem_item_grid *g, size_t n, const double *lo, const double *hi,
                        double inflate, nc_error *err);
/* Items whose inflated box may contain p: *items points into the grid (count may be 0). */
size_t dem_item_grid_query(const dem_item_grid *g, const double p[3], const int32_t **items);
void dem_item_grid_free(dem_item_grid *g);

#endif
