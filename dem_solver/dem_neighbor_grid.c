/* dem_neighbor_grid — cell list for spheres and box grid for triangles and net edges. */
#include "dem_neighbor_grid.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define DEM_GRID_MAX_CELLS ((size_t)1 << 24)

static int grow_i32(int32_t **a, size_t *cap, size_t need, nc_error *err)
{
    if (need <= *cap) return 0;
    size_t c = *cap ? *cap : 64;
    while (c < need) c *= 2;
    int32_t *p = realloc(*a, c * sizeof *p);
    if (!p) return nc_error_set(err, 1, "dem: out of memory for the neighbour grid (%zu cells)", c);
    *a = p;
    *cap = c;
    return 0;
}

/* Chooses origin, cell size and dims for the box [lo, hi] with cells >= min_cell, keeping the
 * number of cells below max_cells by enlarging the cells. */
static void layout(double origin[3], double *cell, int dims[3], const double lo[3],
                   const double hi[3], double min_cell, size_t max_cells)
{
    double c = min_cell > 0.0 ? min_cell : 1.0;
    for (;;) {
        size_t total = 1;
        for (int k = 0; k < 3; k++) {
            double extent = hi[k] - lo[k];
            double d = floor(extent / c) + 1.0;
            if (d > 1e6) d = 1e6;
            dims[k] = (int)d;
            total *= (size_t)dims[k];
        }
        if (total <= max_cells) break;
        c *= 1.5;
    }
    for (int k = 0; k < 3; k++) origin[k] = lo[k];
    *cell = c;
}

void dem_cell_grid_coords(const dem_cell_grid *g, const double p[3], int c[3])
{
    for (int k = 0; k < 3; k++) {
        double f = (p[k] - g->origin[k]) / g->cell;
        int v = f < 0.0 ? 0 : (f >= g->dims[k] ? g->dims[k] - 1 : (int)f);
        c[k] = v;
    }
}

int dem_cell_grid_build(dem_cell_grid *g, size_t n, const double *pos, double min_cell,
                        nc_error *err)
{
    double lo[3] = {0, 0, 0}, hi[3] = {0, 0, 0};
    if (n > 0) {
        for (int k = 0; k < 3; k++) lo[k] = hi[k] = pos[k];
        for (size_t i = 1; i < n; i++)
            for (int k = 0; k < 3; k++) {
                double v = pos[3 * i + k];
                if (v < lo[k]) lo[k] = v;
                if (v > hi[k]) hi[k] = v;
            }
    }
    for (int k = 0; k < 3; k++)
        if (!isfinite(lo[k]) || !isfinite(hi[k]))
            return nc_error_set(err, 1, "dem: a particle position is not finite (the simulation "
                                        "became unstable; reduce dt_s)");
    size_t max_cells = 8 * n + 64;
    if (max_cells > DEM_GRID_MAX_CELLS) max_cells = DEM_GRID_MAX_CELLS;
    layout(g->origin, &g->cell, g->dims, lo, hi, min_cell, max_cells);
    g->n_cells = (size_t)g->dims[0] * (size_t)g->dims[1] * (size_t)g->dims[2];
    if (grow_i32(&g->cell_start, &g->cells_cap, g->n_cells + 1, err)) return -1;
    size_t cap_items = g->items_cap;
    if (grow_i32(&g->cell_items, &cap_items, n, err)) return -1;
    if (grow_i32(&g->item_cell, &g->items_cap, n, err)) return -1;
    g->n_items = n;
    memset(g->cell_start, 0, (g->n_cells + 1) * sizeof *g->cell_start);
    for (size_t i = 0; i < n; i++) {
        int c[3];
        dem_cell_grid_coords(g, pos + 3 * i, c);
        int32_t id = (int32_t)(((size_t)c[2] * (size_t)g->dims[1] + (size_t)c[1]) * (size_t)g->dims[0] + (size_t)c[0]);
        g->item_cell[i] = id;
        g->cell_start[id + 1]++;
    }
    for (size_t c = 0; c < g->n_cells; c++) g->cell_start[c + 1] += g->cell_start[c];
    /* stable fill: items of a cell stay in increasing order (deterministic) */
    for (size_t i = 0; i < n; i++) {
        int32_t c = g->item_cell[i];
        g->cell_items[g->cell_start[c]++] = (int32_t)i;
    }
    for (size_t c = g->n_cells; c > 0; c--) g->cell_start[c] = g->cell_start[c - 1];
    g->cell_start[0] = 0;
    return 0;
}

void dem_cell_grid_free(dem_cell_grid *g)
{
    free(g->cell_start);
    free(g->cell_items);
    free(g->item_cell);
    memset(g, 0, sizeof *g);
}

static void cell_range(const dem_item_grid *g, const double lo[3], const double hi[3], int a[3],
                       int b[3])
{
    for (int k = 0; k < 3; k++) {
        double fa = floor((lo[k] - g->origin[k]) / g->cell);
        double fb = floor((hi[k] - g->origin[k]) / g->cell);
        if (fa < 0) fa = 0;
        if (fb > g->dims[k] - 1) fb = g->dims[k] - 1;
        a[k] = (int)fa;
        b[k] = (int)fb;
    }
}

int dem_item_grid_build(dem_item_grid *g, size_t n, const double *lo, const double *hi,
                        double inflate, nc_error *err)
{
    double blo[3] = {0, 0, 0}, bhi[3] = {0, 0, 0}, mean = 0.0;
    for (size_t i = 0; i < n; i++) {
        for (int k = 0; k < 3; k++) {
            double l = lo[3 * i + k] - inflate, h = hi[3 * i + k] + inflate;
            if (!isfinite(l) || !isfinite(h))
                return nc_error_set(err, 1, "dem: a wall coordinate is not finite");
            if (i == 0 || l < blo[k]) blo[k] = l;
            if (i == 0 || h > bhi[k]) bhi[k] = h;
            mean += h - l;
        }
    }
    mean = n ? mean / (3.0 * (double)n) : 1.0;
    size_t max_cells = 4 * n + 64;
    if (max_cells > DEM_GRID_MAX_CELLS) max_cells = DEM_GRID_MAX_CELLS;
    layout(g->origin, &g->cell, g->dims, blo, bhi, mean > 0.0 ? mean : 1.0, max_cells);
    g->n_cells = (size_t)g->dims[0] * (size_t)g->dims[1] * (size_t)g->dims[2];
    if (grow_i32(&g->cell_start, &g->cells_cap, g->n_cells + 1, err)) return -1;
    memset(g->cell_start, 0, (g->n_cells + 1) * sizeof *g->cell_start);
    /* pass 1: count entries per cell */
    for (int pass = 0; pass < 2; pass++) {
        for (size_t i = 0; i < n; i++) {
            double l[3], h[3];
            for (int k = 0; k < 3; k++) {
                l[k] = lo[3 * i + k] - inflate;
                h[k] = hi[3 * i + k] + inflate;
            }
            int a[3], b[3];
            cell_range(g, l, h, a, b);
            for (int z = a[2]; z <= b[2]; z++)
                for (int y = a[1]; y <= b[1]; y++)
                    for (int x = a[0]; x <= b[0]; x++) {
                        size_t c = ((size_t)z * (size_t)g->dims[1] + (size_t)y) * (size_t)g->dims[0] + (size_t)x;
                        if (pass == 0) g->cell_start[c + 1]++;
                        else g->entries[g->cell_start[c]++] = (int32_t)i;
                    }
        }
        if (pass == 0) {
            for (size_t c = 0; c < g->n_cells; c++) g->cell_start[c + 1] += g->cell_start[c];
            g->n_entries = (size_t)g->cell_start[g->n_cells];
            if (grow_i32(&g->entries, &g->entries_cap, g->n_entries + 1, err)) return -1;
        }
    }
    for (size_t c = g->n_cells; c > 0; c--) g->cell_start[c] = g->cell_start[c - 1];
    g->cell_start[0] = 0;
    return 0;
}

size_t dem_item_grid_query(const dem_item_grid *g, const double p[3], const int32_t **items)
{
    *items = NULL;
    if (g->n_cells == 0) return 0;
    int c[3];
    for (int k = 0; k < 3; k++) {
        double f = floor((p[k] - g->origin[k]) / g->cell);
        if (!(f >= 0.0) || f >= g->dims[k]) return 0; /* outside every inflated box */
        c[k] = (int)f;
    }
    size_t id = ((size_t)c[2] * (size_t)g->dims[1] + (size_t)c[1]) * (size_t)g->dims[0] + (size_t)c[0];
    *items = g->entries + g->cell_start[id];
    return (size_t)(g->cell_start[id + 1] - g->cell_start[id]);
}

void dem_item_grid_free(dem_item_grid *g)
{
    if (!g) return;
    free(g->cell_start);
    free(g->entries);
    memset(g, 0, sizeof *g);
}
