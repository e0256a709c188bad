/* dem_neighbor_list — building the Verlet list in parallel from the cell grid, the thread
 * ranges it balances, and the close-pair count of the free-flight test. */
#include "dem_neighbor_list.h"

#include <stdlib.h>
#include <string.h>

#include "dem_sim.h"

int dem_neighbor_list_alloc(dem_neighbor_list *nl, int n_parts, size_t n_spheres, double r_min,
                            nc_error *err)
{
    nl->n_parts = n_parts;
    nl->part = calloc((size_t)n_parts, sizeof *nl->part);
    nl->first = calloc(n_spheres + 1, sizeof *nl->first);
    nl->pos_at_build = malloc((3 * n_spheres + 1) * sizeof *nl->pos_at_build);
    if (!nl->part || !nl->first || !nl->pos_at_build)
        return nc_error_set(err, 1, "dem: out of memory for %zu spheres", n_spheres);
    if (!(nl->skin_m > 0.0)) nl->skin_m = 0.2 * r_min;
    nl->rebuild = 1;
    return 0;
}

void dem_neighbor_list_free(dem_neighbor_list *nl)
{
    free(nl->first);
    free(nl->nbr);
    if (nl->part)
        for (int k = 0; k < nl->n_parts; k++) free(nl->part[k].a);
    free(nl->part);
    free(nl->pos_at_build);
    dem_cell_grid_free(&nl->grid);
    memset(nl, 0, sizeof *nl);
}

/* Counts the neighbours j > i of sphere i within r_i + r_j + skin, other bodies only, from
 * the cell grid, and lists the first `room` of them in out (if not NULL). */
static int32_t neighbours_of(const dem_sim *s, size_t i, double skin, int32_t *out, size_t room)
{
    const double *pi = s->model.sph.pos + 3 * i;
    double ri = s->model.sph.radius[i];
    int32_t bi = s->model.sph.body[i], count = 0;
    const dem_cell_grid *g = &s->nlist.grid;
    int c[3];
    dem_cell_grid_coords(g, pi, c);
    for (int dz = -1; dz <= 1; dz++) {
        int z = c[2] + dz;
        if (z < 0 || z >= g->dims[2]) continue;
        for (int dy = -1; dy <= 1; dy++) {
            int y = c[1] + dy;
            if (y < 0 || y >= g->dims[1]) continue;
            for (int dx = -1; dx <= 1; dx++) {
                int x = c[0] + dx;
                if (x < 0 || x >= g->dims[0]) continue;
                size_t cell = ((size_t)z * (size_t)g->dims[1] + (size_t)y) * (size_t)g->dims[0] + (size_t)x;
                /* items of a cell are in increasing order: skip to those above i (one
                 * mispredicted branch per cell instead of one per item) */
                int32_t q0 = g->cell_start[cell], q1 = g->cell_start[cell + 1];
                int32_t first = q1;
                while (first > q0 && (size_t)g->cell_items[first - 1] > i) first--;
                for (int32_t q = first; q < q1; q++) {
                    int32_t j = g->cell_items[q];
                    if (s->model.sph.body[j] == bi) continue;
                    const double *pj = s->model.sph.pos + 3 * (size_t)j;
                    double d[3] = {pj[0] - pi[0], pj[1] - pi[1], pj[2] - pi[2]};
                    double cut = ri + s->model.sph.radius[j] + skin;
                    if (d[0] * d[0] + d[1] * d[1] + d[2] * d[2] >= cut * cut) continue;
                    if (out && (size_t)count < room) out[count] = j;
                    count++;
                }
            }
        }
    }
    return count;
}

/* The neighbours of the spheres of buffer b's range into its part; 1 when out of memory. */
static int neighbours_of_range(dem_sim *s, int b)
{
    struct dem_nbr_part *part = &s->nlist.part[b];
    size_t lo = s->work.range_first[b], hi = s->work.range_first[b + 1];
    size_t used = 0;
    for (size_t i = lo; i < hi; i++) {
        size_t room = part->cap - used;
        int32_t count = neighbours_of(s, i, s->nlist.skin_m, part->a ? part->a + used : NULL, room);
        if ((size_t)count > room || part->cap - used - (size_t)count < 64) {
            size_t cap = 2 * (used + (size_t)count) + 1024;
            int32_t *a = realloc(part->a, cap * sizeof *a);
            if (!a) return 1;
            part->a = a;
            part->cap = cap;
            if ((size_t)count > room) neighbours_of(s, i, s->nlist.skin_m, part->a + used, (size_t)count);
        }
        s->nlist.first[i + 1] = count;
        used += (size_t)count;
    }
    return 0;
}

/* Part b's neighbours into their place in the list. */
static void copy_part(dem_sim *s, int b)
{
    size_t lo = s->work.range_first[b], hi = s->work.range_first[b + 1];
    size_t from = (size_t)s->nlist.first[lo], count = (size_t)s->nlist.first[hi] - from;
    if (count) memcpy(s->nlist.nbr + from, s->nlist.part[b].a, count * sizeof(int32_t));
}

int dem_neighbor_list_update(dem_sim *s, nc_error *err)
{
    size_t n = s->model.sph.n;
    int nb = s->work.n_buffers;
    /* s->nlist.max_disp2 was measured by dem_integrate_bodies() while moving the spheres */
    if (!(s->nlist.max_disp2 <= 0.25 * s->nlist.skin_m * s->nlist.skin_m)) s->nlist.rebuild = 1; /* also NaN */
    if (!s->nlist.rebuild) return 0;
    if (dem_cell_grid_build(&s->nlist.grid, n, s->model.sph.pos, 2.0 * s->model.r_max + s->nlist.skin_m, err)) return -1;
    int failed = 0;
    if (n >= DEM_PARALLEL_MIN) {
#pragma omp parallel for schedule(static, 1) num_threads(nb) reduction(| : failed)
        for (int b = 0; b < nb; b++) failed |= neighbours_of_range(s, b);
    } else {
        for (int b = 0; b < nb; b++) failed |= neighbours_of_range(s, b);
    }
    if (failed) return nc_error_set(err, 1, "dem: out of memory for the neighbour list");
    s->nlist.first[0] = 0;
    for (size_t i = 0; i < n; i++) s->nlist.first[i + 1] += s->nlist.first[i];
    size_t total = (size_t)s->nlist.first[n];
    if (nb == 1) { /* the single part is the list: no copy */
        int32_t *a = s->nlist.nbr;
        size_t cap = s->nlist.cap;
        s->nlist.nbr = s->nlist.part[0].a;
        s->nlist.cap = s->nlist.part[0].cap;
        s->nlist.part[0].a = a;
        s->nlist.part[0].cap = cap;
    } else {
        if (total > s->nlist.cap) {
            size_t cap = total + total / 4 + 64;
            int32_t *p = realloc(s->nlist.nbr, cap * sizeof *p);
            if (!p) return nc_error_set(err, 1, "dem: out of memory for %zu neighbour pairs", cap);
            s->nlist.nbr = p;
            s->nlist.cap = cap;
        }
        if (total >= DEM_PARALLEL_MIN) {
#pragma omp parallel for schedule(static, 1) num_threads(nb)
            for (int b = 0; b < nb; b++) copy_part(s, b);
        } else {
            for (int b = 0; b < nb; b++) copy_part(s, b);
        }
    }
    /* new ranges for the contact passes, balanced by the expected work of each sphere: its
     * neighbours and (weighing more) its contacts of the last step */
    if (nb > 1) {
        double work = 0.0;
        for (size_t i = 0; i < n; i++)
            work += 1.0 + (double)(s->nlist.first[i + 1] - s->nlist.first[i]) +
                    4.0 * (double)(s->contact.prev_first[i + 1] - s->contact.prev_first[i]);
        double acc = 0.0;
        int b = 1;
        s->work.range_first[0] = 0;
        for (size_t i = 0; i < n && b < nb; i++) {
            while (b < nb && acc >= work * (double)b / (double)nb) s->work.range_first[b++] = i;
            acc += 1.0 + (double)(s->nlist.first[i + 1] - s->nlist.first[i]) +
                   4.0 * (double)(s->contact.prev_first[i + 1] - s->contact.prev_first[i]);
        }
        while (b < nb) s->work.range_first[b++] = n;
        s->work.range_first[nb] = n;
    }
    /* spheres with a neighbour in another thread's range get their force sums through the
     * spills (the ranges are those of dem_contact_pass) */
    memset(s->work.shared_sphere, 0, n * sizeof *s->work.shared_sphere);
    for (int b = 0; b + 1 < nb; b++) {
        size_t lo = s->work.range_first[b], hi = s->work.range_first[b + 1];
        for (size_t i = lo; i < hi; i++)
            for (int32_t q = s->nlist.first[i]; q < s->nlist.first[i + 1]; q++)
                if ((size_t)s->nlist.nbr[q] >= hi) s->work.shared_sphere[s->nlist.nbr[q]] = 1;
    }
    memcpy(s->nlist.pos_at_build, s->model.sph.pos, 3 * n * sizeof(double));
    s->nlist.max_disp2 = 0.0;
    s->nlist.rebuild = 0;
    s->nlist.n_builds++;
    return 0;
}

int dem_neighbor_list_close_pairs(dem_sim *s, double gap, long *count, nc_error *err)
{
    size_t n = s->model.sph.n;
    *count = 0;
    if (n < 2) return 0;
    if (dem_cell_grid_build(&s->nlist.grid, n, s->model.sph.pos, 2.0 * s->model.r_max + gap, err)) return -1;
    long nl = (long)n, total = 0;
    if (nl >= DEM_PARALLEL_MIN) {
#pragma omp parallel for schedule(static) reduction(+ : total) num_threads(s->work.n_buffers)
        for (long i = 0; i < nl; i++) total += neighbours_of(s, (size_t)i, gap, NULL, 0);
    } else {
        for (long i = 0; i < nl; i++) total += neighbours_of(s, (size_t)i, gap, NULL, 0);
    }
    *count = total;
    s->nlist.rebuild = 1; /* the grid now has another cell size */
    return 0;
}
