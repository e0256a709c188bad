/* dem_detect_net — contacts of a sphere with the coupled net (eqs. (14), (15)): the closest
 * point of every nearby cable edge at its current position, an interior point as an edge
 * contact (its reaction split onto the two nodes), an end as a node contact. A node is touched
 * once per rope through it (dem_net_strands.h), not by a rope one of whose edges at that node
 * is touched in its interior, and not by the end of a rope fastened there to another (that
 * rope's contact is the one). So the force stays continuous as the closest point passes
 * from an edge to the node, and a sphere over the crossing of two ropes presses on both, as it
 * does a hair beside it (one node contact per node halved the force over the node and on the
 * rope lines through it). */
#include "dem_detect.h"

#include <string.h>

#include "dem_contact_geometry.h"

/* Adds x unless listed: an edge once, a node once per strand (x.owner). */
static void add_feature(dem_feature *f, int *n, const dem_feature *x, int *overflow)
{
    for (int k = 0; k < *n; k++)
        if (f[k].type == x->type && f[k].id == x->id && (x->type == 1 || f[k].owner == x->owner))
            return;
    if (*n == DEM_MAX_FEATURES) {
        *overflow = 1;
        return;
    }
    f[(*n)++] = *x;
}

/* The strand of edge e at node v. */
static int32_t strand_at(const dem_net *net, int32_t e, int32_t v)
{
    return net->strand[2 * (size_t)e + (net->edges[2 * (size_t)e] == v ? 0 : 1)];
}

static int present(const dem_sim *s)
{
    return s->model.net.active;
}

static int detect(const dem_sim *s, dem_emit_ctx *out, size_t i, double dt, int *overflow)
{
    const dem_net *net = &s->model.net;
    const double *p = s->model.sph.pos + 3 * i;
    double reach = s->model.sph.radius[i] + net->cable_radius_m;
    const int32_t *items;
    size_t count = dem_item_grid_query(net->grid, p, &items);
    dem_feature f[DEM_MAX_FEATURES];
    int nf = 0;
    for (size_t c = 0; c < count; c++) {
        int32_t e = items[c];
        /* the edge's box over the step's motion (its grid entry) farther than reach: the
         * closest point is too (a third of the DEM's time on the MEL test went to this loop) */
        const double *lo = net->box_lo + 3 * (size_t)e, *hi = net->box_hi + 3 * (size_t)e;
        if (p[0] < lo[0] - reach || p[0] > hi[0] + reach || p[1] < lo[1] - reach ||
            p[1] > hi[1] + reach || p[2] < lo[2] - reach || p[2] > hi[2] + reach)
            continue;
        int32_t a = net->edges[2 * (size_t)e], b = net->edges[2 * (size_t)e + 1];
        dem_feature x;
        x.d2 = dem_closest_on_segment(p, net->cur + 3 * (size_t)a, net->cur + 3 * (size_t)b, x.q, &x.t);
        if (x.d2 >= reach * reach || x.d2 == 0.0) continue; /* eqs. (14), (15) */
        if (x.t <= 0.0 || x.t >= 1.0) {
            x.type = 2;
            x.id = x.t <= 0.0 ? a : b;
            x.owner = net->strand[2 * (size_t)e + (x.t <= 0.0 ? 0 : 1)];
            if (x.owner < 0) continue; /* an attached end: the rope it is fastened to counts */
        } else {
            x.type = 1;
            x.id = e;
            x.owner = e;
        }
        add_feature(f, &nf, &x, overflow);
    }
    for (int a = 0; a < nf; a++) {
        if (f[a].type == 2) { /* the rope touched in an edge's interior at this node */
            int drop = 0;
            for (int b = 0; b < nf && !drop; b++) {
                if (f[b].type != 1) continue;
                const int32_t *e = net->edges + 2 * (size_t)f[b].id;
                drop = (e[0] == f[a].id || e[1] == f[a].id) &&
                       strand_at(net, f[b].id, f[a].id) == f[a].owner;
            }
            if (drop) continue;
        }
        double dist = sqrt(f[a].d2);
        dem_contact_in in;
        in.aux = f[a].type == 2 ? f[a].owner : 0;
        in.reach = reach;
        in.overlap = reach - dist;
        for (int k = 0; k < 3; k++) in.n[k] = (f[a].q[k] - p[k]) / dist;
        in.lever_i = s->model.sph.radius[i] - 0.5 * in.overlap;
        in.lever_j = 0.0;
        if (f[a].type == 1) {
            in.kind = DEM_CONTACT_NET_EDGE;
            in.j = f[a].id;
            in.weight = f[a].t;
            const int32_t *e = net->edges + 2 * (size_t)f[a].id;
            const double *va = net->vel + 3 * (size_t)e[0], *vb = net->vel + 3 * (size_t)e[1];
            for (int k = 0; k < 3; k++) in.v_other[k] = (1.0 - in.weight) * va[k] + in.weight * vb[k];
        } else {
            in.kind = DEM_CONTACT_NET_NODE;
            in.j = f[a].id;
            in.weight = 0.0;
            memcpy(in.v_other, net->vel + 3 * (size_t)f[a].id, sizeof in.v_other);
        }
        dem_net_wall_pair(&s->model, i, &in.pair);
        if (dem_emit_wall_contact(s, out, i, &in, dt)) return -1;
    }
    return 0;
}

const dem_detector dem_detect_net = {"net", present, detect};
