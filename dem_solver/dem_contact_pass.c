/* dem_contact_pass — the parallel contact pass of a step over the detector table, and its
 * deterministic reduction: per-thread buffers joined in range order, then the spilled force
 * sums (walls, net nodes, spheres shared between ranges) in contact order. */
#include "dem_contact_pass.h"

#include <stdlib.h>
#include <string.h>

#include "dem_detect.h"
#include "dem_neighbor_list.h"
#include "dem_sim.h"

/* The detectors, in the order a sphere's contacts are listed (part of the results: the history
 * lookup and every force sum follow it). A new kind of wall is one dem_detect_<kind>.c file
 * and one line here. */
static const dem_detector *const detectors[] = {
    &dem_detect_sphere,
    &dem_detect_plane,
    &dem_detect_mesh,
    &dem_detect_net,
};
#define N_DETECTORS (sizeof detectors / sizeof *detectors)

int dem_thread_work_alloc(dem_thread_work *w, int n_buffers, size_t n_spheres, nc_error *err)
{
    w->n_buffers = n_buffers;
    w->buffers = calloc((size_t)n_buffers, sizeof *w->buffers);
    w->overflow = calloc((size_t)n_buffers, sizeof *w->overflow);
    w->spills = calloc((size_t)n_buffers, sizeof *w->spills);
    w->shared_sphere = calloc(n_spheres + 1, sizeof *w->shared_sphere);
    w->range_first = malloc(((size_t)n_buffers + 1) * sizeof *w->range_first);
    if (!w->buffers || !w->overflow || !w->spills || !w->shared_sphere || !w->range_first)
        return nc_error_set(err, 1, "dem: out of memory for %zu spheres", n_spheres);
    for (int b = 0; b <= n_buffers; b++)
        w->range_first[b] = n_spheres * (size_t)b / (size_t)n_buffers;
    size_t guess = 8 * n_spheres / (size_t)n_buffers + 64;
    for (int k = 0; k < n_buffers; k++)
        if (dem_contacts_reserve(&w->buffers[k], guess, err)) return -1;
    return 0;
}

void dem_thread_work_free(dem_thread_work *w)
{
    if (w->buffers)
        for (int k = 0; k < w->n_buffers; k++) dem_contacts_free(&w->buffers[k]);
    free(w->buffers);
    if (w->spills)
        for (int k = 0; k < w->n_buffers; k++) free(w->spills[k].r);
    free(w->spills);
    free(w->shared_sphere);
    free(w->range_first);
    free(w->overflow);
    memset(w, 0, sizeof *w);
}

/* Finds the contacts of the spheres of buffer b's range into that buffer; 1 when out of memory. */
static int detect_range(dem_sim *s, int b, const dem_detector *const *active, int n_active,
                        double dt)
{
    /* thread-local copies: the loop below then reloads nothing after a detector call */
    dem_detect_fn *detect[N_DETECTORS];
    int nd = n_active, overflow[N_DETECTORS] = {0}, ok = 1;
    for (int k = 0; k < nd; k++) detect[k] = active[k]->detect;
    dem_emit_ctx out = {&s->work.buffers[b], &s->work.spills[b], 0};
    out.out->n = 0;
    out.spill->n = 0;
    size_t lo = s->work.range_first[b], hi = s->work.range_first[b + 1];
    /* only this range writes the sums of its unshared spheres */
    memset(s->model.sph.force + 3 * lo, 0, 3 * (hi - lo) * sizeof(double));
    memset(s->model.sph.torque + 3 * lo, 0, 3 * (hi - lo) * sizeof(double));
    for (size_t i = lo; i < hi && ok; i++) {
        out.first = out.out->n;
        s->contact.first[i] = (int32_t)out.first; /* + the buffer's offset, below */
        for (int k = 0; k < nd && ok; k++) ok = detect[k](s, &out, i, dt, &overflow[k]) == 0;
    }
    s->work.overflow[b] = 0;
    for (int k = nd - 1; k >= 0; k--)
        if (overflow[k]) s->work.overflow[b] = 1 + k;
    return !ok;
}

int dem_contact_pass(dem_sim *s, double dt, nc_error *err)
{
    size_t n = s->model.sph.n;
    /* the current list becomes the history */
    dem_contacts tmp = s->contact.prev;
    s->contact.prev = s->contact.list;
    s->contact.list = tmp;
    int32_t *tf = s->contact.prev_first;
    s->contact.prev_first = s->contact.first;
    s->contact.first = tf;

    if (dem_neighbor_list_update(s, err)) return -1;

    /* the detectors of the partner kinds this model has, in table order */
    const dem_detector *active[N_DETECTORS];
    int n_active = 0;
    for (size_t k = 0; k < N_DETECTORS; k++)
        if (detectors[k]->present(s)) active[n_active++] = detectors[k];

    int nb = s->work.n_buffers;
    int failed = 0;
    /* Fixed contiguous ranges per buffer: the concatenation order never changes. */
    if (n >= DEM_PARALLEL_MIN) {
#pragma omp parallel for schedule(static, 1) num_threads(nb) reduction(| : failed)
        for (int b = 0; b < nb; b++) failed |= detect_range(s, b, active, n_active, dt);
    } else {
        for (int b = 0; b < nb; b++) failed |= detect_range(s, b, active, n_active, dt);
    }
    if (failed) return nc_error_set(err, 1, "dem: out of memory growing the contact list");
    size_t total = 0;
    for (int b = 0; b < nb; b++) {
        if (s->work.overflow[b])
            return nc_error_set(err, 1, "dem: a sphere touches more than %d features of one %s "
                                        "wall (%s much finer than the spheres?)", DEM_MAX_FEATURES,
                                active[s->work.overflow[b] - 1]->name,
                                active[s->work.overflow[b] - 1]->name);
        total += s->work.buffers[b].n;
    }
    if (nb == 1) { /* the single buffer becomes the list: no copy */
        dem_contacts t = s->contact.list;
        s->contact.list = s->work.buffers[0];
        s->work.buffers[0] = t;
    } else {
        if (dem_contacts_reserve(&s->contact.list, total, err)) return -1;
        size_t at[DEM_MAX_BUFFERS + 1];
        at[0] = 0;
        for (int b = 0; b < nb; b++) at[b + 1] = at[b] + s->work.buffers[b].n;
        if (total >= DEM_PARALLEL_MIN) {
#pragma omp parallel for schedule(static, 1) num_threads(nb)
            for (int b = 0; b < nb; b++)
                dem_contacts_copy_range(&s->contact.list, at[b], &s->work.buffers[b], 0, s->work.buffers[b].n);
        } else {
            for (int b = 0; b < nb; b++)
                dem_contacts_copy_range(&s->contact.list, at[b], &s->work.buffers[b], 0, s->work.buffers[b].n);
        }
        s->contact.list.n = total;
    }

    /* CSR index by sphere: each buffer's local first contacts, shifted by its offset */
    if (nb > 1) {
        size_t off = 0;
        for (int b = 0; b < nb; b++) {
            size_t lo = s->work.range_first[b], hi = s->work.range_first[b + 1];
            for (size_t i = lo; i < hi; i++) s->contact.first[i] += (int32_t)off;
            off += s->work.buffers[b].n;
        }
    }
    s->contact.first[n] = (int32_t)total;

    /* the sums that cross ranges, in contact order (thread ranges are in sphere order) */
    memset(s->wall_force, 0, 3 * s->n_walls * sizeof(double));
    if (s->model.net.active) memset(s->model.net.force, 0, 3 * s->model.net.n_nodes * sizeof(double));
    double *net_total = s->wall_force + 3 * (s->model.n_planes + s->model.n_meshes);
    for (int b = 0; b < nb; b++) {
        const dem_spills *sp = &s->work.spills[b];
        for (size_t k = 0; k < sp->n; k++) {
            const dem_spill *r = &sp->r[k];
            const double *f = r->f;
            switch (r->kind) {
            case DEM_CONTACT_SPHERE: {
                double *fs = s->model.sph.force + 3 * (size_t)r->index, *ts = s->model.sph.torque + 3 * (size_t)r->index;
                for (int d = 0; d < 3; d++) {
                    fs[d] += f[d];
                    ts[d] += r->t[d];
                }
                break;
            }
            case DEM_CONTACT_PLANE:
                for (int d = 0; d < 3; d++) s->wall_force[3 * (size_t)r->index + d] -= f[d];
                break;
            case DEM_CONTACT_MESH:
                for (int d = 0; d < 3; d++) s->wall_force[3 * (s->model.n_planes + (size_t)r->index) + d] -= f[d];
                break;
            case DEM_CONTACT_NET_EDGE: { /* consistent nodal loads: (1-t) f, t f */
                const int32_t *e = s->model.net.edges + 2 * (size_t)r->index;
                double t = r->weight;
                for (int d = 0; d < 3; d++) {
                    s->model.net.force[3 * (size_t)e[0] + d] -= (1.0 - t) * f[d];
                    s->model.net.force[3 * (size_t)e[1] + d] -= t * f[d];
                    net_total[d] -= f[d];
                }
                break;
            }
            case DEM_CONTACT_NET_NODE:
                for (int d = 0; d < 3; d++) {
                    s->model.net.force[3 * (size_t)r->index + d] -= f[d];
                    net_total[d] -= f[d];
                }
                break;
            default:
                break;
            }
        }
    }

    return 0;
}
