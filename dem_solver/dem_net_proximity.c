/* dem_net_proximity — zero Jacobian blocks at the nodes a particle in contact may reach
 * (dem_net_proximity.h). */
#include "dem_net_proximity.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "dem_contact_geometry.h"

static double speed(const double *v)
{
    return sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
}

/* Appends the zero block (i, i). */
static int add_zero_block(dem_net_jacobian *jac, int32_t i, nc_error *err)
{
    if (jac->n_blocks == jac->cap_blocks) {
        const size_t cap = 2 * jac->cap_blocks + 16;
        int32_t *nodes = realloc(jac->nodes, 2 * cap * sizeof *nodes);
        if (!nodes) return nc_error_set(err, 1, "dem: out of memory for the interface Jacobian");
        jac->nodes = nodes;
        double *K = realloc(jac->K, 9 * cap * sizeof *K);
        if (!K) return nc_error_set(err, 1, "dem: out of memory for the interface Jacobian");
        jac->K = K;
        jac->cap_blocks = cap;
    }
    jac->nodes[2 * jac->n_blocks] = jac->nodes[2 * jac->n_blocks + 1] = i;
    memset(jac->K + 9 * jac->n_blocks, 0, 9 * sizeof *jac->K);
    jac->n_blocks++;
    return 0;
}

/* A node near a particle in contact, and how far it is from that particle's surface. */
typedef struct candidate {
    int32_t node;
    double gap_m;
} candidate;

static int by_gap(const void *a, const void *b)
{
    const candidate *x = a, *y = b;
    if (x->gap_m != y->gap_m) return x->gap_m < y->gap_m ? -1 : 1;
    return (x->node > y->node) - (x->node < y->node);
}

int dem_net_jacobian_add_proximity(const dem_sim *s, dem_net_jacobian *jac, double dt_s,
                                   size_t max_nodes, size_t *added, nc_error *err)
{
    if (added) *added = 0;
    const dem_net *net = &s->model.net;
    const size_t n_nodes = net->n_nodes, n_bodies = s->model.bod.n;
    if (jac->n_rec == 0 || n_nodes == 0) return 0;
    /* per node: 1 in a block, 2 a candidate (at cand[slot[i]]); per body: 1 with a net contact */
    unsigned char *named = calloc(n_nodes, 1), *touching = calloc(n_bodies ? n_bodies : 1, 1);
    candidate *cand = malloc(n_nodes * sizeof *cand);
    int32_t *slot = malloc(n_nodes * sizeof *slot);
    double *node_speed = malloc(n_nodes * sizeof *node_speed);
    int rc = -1;
    if (!named || !touching || !cand || !slot || !node_speed) {
        nc_error_set(err, 1, "dem: out of memory for the nodes near the particles");
        goto done;
    }
    for (size_t b = 0; b < jac->n_blocks; b++)
        named[jac->nodes[2 * b]] = named[jac->nodes[2 * b + 1]] = 1;
    for (size_t r = 0; r < jac->n_rec; r++) touching[jac->rec[r].body] = 1;
    for (size_t k = 0; k < n_nodes; k++) node_speed[k] = speed(net->vel + 3 * k);
    size_t count = 0;
    for (size_t i = 0; i < s->model.sph.n; i++) {
        if (!touching[s->model.sph.body[i]]) continue;
        const double *p = s->model.sph.pos + 3 * i;
        const double reach = s->model.sph.radius[i] + net->cable_radius_m;
        const double v_sphere = speed(s->model.sph.vel + 3 * i);
        for (size_t e = 0; e < net->n_edges; e++) {
            const int32_t a = net->edges[2 * e], b = net->edges[2 * e + 1];
            if (named[a] == 1 && named[b] == 1) continue;
            const double v_node = fmax(node_speed[a], node_speed[b]);
            const double gap = reach + DEM_PROXIMITY_STEPS * (v_sphere + v_node) * dt_s;
            double q[3], t;
            if (dem_closest_on_segment(p, net->cur + 3 * (size_t)a, net->cur + 3 * (size_t)b, q,
                                       &t) >= gap * gap)
                continue;
            const int32_t ends[2] = {a, b};
            for (int k = 0; k < 2; k++) {
                const int32_t n = ends[k];
                if (named[n] == 1) continue;
                const double *x = net->cur + 3 * (size_t)n;
                const double d = sqrt((x[0] - p[0]) * (x[0] - p[0]) +
                                      (x[1] - p[1]) * (x[1] - p[1]) +
                                      (x[2] - p[2]) * (x[2] - p[2])) - reach;
                if (named[n] == 2) {
                    cand[slot[n]].gap_m = fmin(cand[slot[n]].gap_m, d);
                } else {
                    named[n] = 2;
                    slot[n] = (int32_t)count;
                    cand[count++] = (candidate){n, d};
                }
            }
        }
    }
    /* the nearest first, at most max_nodes (the compliance's size bounds the DEM's and the
     * FEM's work: a dense m x m search matrix, 3 FEM solves per node) */
    if (count > max_nodes) qsort(cand, count, sizeof *cand, by_gap);
    const size_t take = count < max_nodes ? count : max_nodes;
    for (size_t k = 0; k < take; k++)
        if (add_zero_block(jac, cand[k].node, err)) goto done;
    if (added) *added = take;
    rc = 0;
done:
    free(named);
    free(touching);
    free(cand);
    free(slot);
    free(node_speed);
    return rc;
}
