/* dem_coupling — the net wall from the interface mesh, the snapshot of a coupling step
 * (begin_step / restore), the coupled sub-stepping with its free-flight shortcut, and the
 * particle–net gap. */
#include "dem_coupling.h"
#include "nc_time.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "dem_contact_geometry.h"
#include "dem_integrate.h"
#include "dem_net_jacobian.h"
#include "dem_net_strands.h"
#include "dem_neighbor_list.h"
#include "dem_sim.h"

int dem_snapshot_alloc(dem_snapshot *p, size_t n_bodies, size_t n_spheres, nc_error *err)
{
    size_t nbod = n_bodies ? n_bodies : 1, nsph = n_spheres ? n_spheres : 1;
    p->body_pos = malloc(3 * nbod * sizeof(double));
    p->body_vel = malloc(3 * nbod * sizeof(double));
    p->body_omega = malloc(3 * nbod * sizeof(double));
    p->body_angmom = malloc(3 * nbod * sizeof(double));
    p->body_quat = malloc(4 * nbod * sizeof(double));
    p->sph_pos = malloc(3 * nsph * sizeof(double));
    p->sph_vel = malloc(3 * nsph * sizeof(double));
    p->contact_first = malloc((n_spheres + 1) * sizeof(int32_t));
    if (!p->body_pos || !p->body_vel || !p->body_omega || !p->body_angmom || !p->body_quat ||
        !p->sph_pos || !p->sph_vel || !p->contact_first)
        return nc_error_set(err, 1, "dem: out of memory for %zu spheres", n_spheres);
    return 0;
}

void dem_snapshot_free(dem_snapshot *p)
{
    free(p->body_pos); free(p->body_vel); free(p->body_omega); free(p->body_angmom);
    free(p->body_quat); free(p->sph_pos); free(p->sph_vel); free(p->contact_first);
    free(p->net_cur); free(p->net_vel);
    dem_contacts_free(&p->contacts);
    memset(p, 0, sizeof *p);
}

/* Boxes of the net edges into the net's item grid: each edge's box holds it at positions
 * `from` and `to` and, since the wall moves linearly between them, everywhere in between. */
static int build_net_grid_over(dem_sim *s, const double *from, const double *to, nc_error *err)
{
    dem_net *net = &s->model.net;
    for (size_t e = 0; e < net->n_edges; e++) {
        const double *p[4] = {from + 3 * (size_t)net->edges[2 * e], from + 3 * (size_t)net->edges[2 * e + 1],
                              to + 3 * (size_t)net->edges[2 * e], to + 3 * (size_t)net->edges[2 * e + 1]};
        for (int k = 0; k < 3; k++) {
            net->box_lo[3 * e + k] = fmin(fmin(p[0][k], p[1][k]), fmin(p[2][k], p[3][k]));
            net->box_hi[3 * e + k] = fmax(fmax(p[0][k], p[1][k]), fmax(p[2][k], p[3][k]));
        }
    }
    double inflate = s->model.r_max + net->cable_radius_m + net->near_distance_m;
    return dem_item_grid_build(net->grid, net->n_edges, net->box_lo, net->box_hi, inflate, err);
}

/* The grid of the net edges at their current position. */
static int build_net_grid(dem_sim *s, nc_error *err)
{
    return build_net_grid_over(s, s->model.net.cur, s->model.net.cur, err);
}

int dem_sim_set_interface(dem_sim *s, size_t n_nodes, const int32_t *node_ids,
                          const double *coords, size_t n_edges, const int32_t *edges,
                          nc_error *err)
{
    if (!s->prepared) return nc_error_set(err, 1, "dem: interface before the model was prepared");
    if (!(s->model.net.youngs_modulus_pa > 0.0))
        return nc_error_set(err, 1, "%s: net_wall: the coupled net wall needs net_wall."
                                    "youngs_modulus_pa > 0", s->model.source);
    if (n_nodes == 0) return nc_error_set(err, 1, "interface: no nodes");
    if (n_edges == 0) return nc_error_set(err, 1, "interface: no elements");
    for (size_t k = 0; k < 3 * n_nodes; k++)
        if (!isfinite(coords[k]))
            return nc_error_set(err, 1, "interface: coordinates[%zu] is not finite", k / 3);
    for (size_t e = 0; e < n_edges; e++) {
        int32_t a = edges[2 * e], b = edges[2 * e + 1];
        if (a < 0 || b < 0 || (size_t)a >= n_nodes || (size_t)b >= n_nodes)
            return nc_error_set(err, 1, "interface: elements[%zu] = [%d, %d]: node index out of "
                                        "range 0..%zu", e, a, b, n_nodes - 1);
        if (a == b)
            return nc_error_set(err, 1, "interface: elements[%zu] joins node %d to itself", e, a);
    }
    dem_net *net = &s->model.net;
    dem_net_free(net);
    net->n_nodes = n_nodes;
    net->n_edges = n_edges;
    net->node_ids = malloc(n_nodes * sizeof(int32_t));
    net->edges = malloc(2 * n_edges * sizeof(int32_t));
    net->strand = malloc(2 * n_edges * sizeof(int32_t));
    double **arrays[] = {&net->ref, &net->start, &net->end, &net->end_vel, &net->cur,
                         &net->vel, &net->force, &net->impulse};
    int ok = net->node_ids && net->edges && net->strand;
    for (size_t k = 0; k < sizeof arrays / sizeof *arrays; k++) {
        *arrays[k] = calloc(3 * n_nodes, sizeof(double));
        ok = ok && *arrays[k];
    }
    net->box_lo = malloc(3 * n_edges * sizeof(double));
    net->box_hi = malloc(3 * n_edges * sizeof(double));
    net->grid = calloc(1, sizeof *net->grid);
    dem_snapshot *p = &s->snap;
    free(p->net_cur);
    free(p->net_vel);
    p->net_cur = malloc(3 * n_nodes * sizeof(double));
    p->net_vel = malloc(3 * n_nodes * sizeof(double));
    p->net_nodes = n_nodes;
    if (!ok || !net->box_lo || !net->box_hi || !net->grid || !p->net_cur || !p->net_vel)
        return nc_error_set(err, 1, "dem: out of memory for the interface (%zu nodes)", n_nodes);
    for (size_t k = 0; k < n_nodes; k++) net->node_ids[k] = node_ids ? node_ids[k] : (int32_t)k;
    memcpy(net->edges, edges, 2 * n_edges * sizeof(int32_t));
    memcpy(net->ref, coords, 3 * n_nodes * sizeof(double));
    memcpy(net->start, coords, 3 * n_nodes * sizeof(double));
    memcpy(net->end, coords, 3 * n_nodes * sizeof(double));
    memcpy(net->cur, coords, 3 * n_nodes * sizeof(double));
    if (dem_net_find_strands(n_nodes, coords, n_edges, edges, net->strand, err)) return -1;
    net->active = 1;
    s->snap.valid = 0;
    return build_net_grid(s, err);
}

int dem_sim_begin_step(dem_sim *s, nc_error *err)
{
    dem_snapshot *p = &s->snap;
    size_t nb = s->model.bod.n, n = s->model.sph.n;
    memcpy(p->body_pos, s->model.bod.pos, 3 * nb * sizeof(double));
    memcpy(p->body_vel, s->model.bod.vel, 3 * nb * sizeof(double));
    memcpy(p->body_omega, s->model.bod.omega, 3 * nb * sizeof(double));
    memcpy(p->body_angmom, s->model.bod.angmom, 3 * nb * sizeof(double));
    memcpy(p->body_quat, s->model.bod.quat, 4 * nb * sizeof(double));
    memcpy(p->sph_pos, s->model.sph.pos, 3 * n * sizeof(double));
    memcpy(p->sph_vel, s->model.sph.vel, 3 * n * sizeof(double));
    if (dem_contacts_copy(&p->contacts, &s->contact.list, err)) return -1;
    memcpy(p->contact_first, s->contact.first, (n + 1) * sizeof(int32_t));
    if (s->model.net.active) {
        memcpy(s->model.net.start, s->model.net.cur, 3 * s->model.net.n_nodes * sizeof(double));
        memcpy(p->net_cur, s->model.net.cur, 3 * s->model.net.n_nodes * sizeof(double));
        memcpy(p->net_vel, s->model.net.vel, 3 * s->model.net.n_nodes * sizeof(double));
    }
    p->time_s = s->time_s;
    p->step = s->step;
    p->valid = 1;
    s->nlist.rebuild = 1; /* the repeated step (after a restore) rebuilds at this same state */
    return 0;
}

int dem_sim_restore(dem_sim *s, nc_error *err)
{
    dem_snapshot *p = &s->snap;
    if (!p->valid) return nc_error_set(err, 1, "dem: restore requested but no step was begun");
    size_t nb = s->model.bod.n, n = s->model.sph.n;
    memcpy(s->model.bod.pos, p->body_pos, 3 * nb * sizeof(double));
    memcpy(s->model.bod.vel, p->body_vel, 3 * nb * sizeof(double));
    memcpy(s->model.bod.omega, p->body_omega, 3 * nb * sizeof(double));
    memcpy(s->model.bod.angmom, p->body_angmom, 3 * nb * sizeof(double));
    memcpy(s->model.bod.quat, p->body_quat, 4 * nb * sizeof(double));
    memcpy(s->model.sph.pos, p->sph_pos, 3 * n * sizeof(double));
    memcpy(s->model.sph.vel, p->sph_vel, 3 * n * sizeof(double));
    if (dem_contacts_copy(&s->contact.list, &p->contacts, err)) return -1;
    memcpy(s->contact.first, p->contact_first, (n + 1) * sizeof(int32_t));
    if (s->model.net.active && p->net_nodes == s->model.net.n_nodes) {
        memcpy(s->model.net.cur, p->net_cur, 3 * s->model.net.n_nodes * sizeof(double));
        memcpy(s->model.net.vel, p->net_vel, 3 * s->model.net.n_nodes * sizeof(double));
        memcpy(s->model.net.start, p->net_cur, 3 * s->model.net.n_nodes * sizeof(double));
    }
    s->time_s = p->time_s;
    s->step = p->step;
    s->nlist.rebuild = 1;
    return 0;
}

/* The smaller of gap and sphere i's clearance to the net edges near it. */
static double sphere_net_gap(const dem_sim *s, const dem_net *net, long i, double gap)
{
    const double *p = s->model.sph.pos + 3 * i;
    const int32_t *items;
    size_t count = dem_item_grid_query(net->grid, p, &items);
    for (size_t c = 0; c < count; c++) {
        const int32_t *e = net->edges + 2 * (size_t)items[c];
        double q[3], t;
        double d2 = dem_closest_on_segment(p, net->cur + 3 * (size_t)e[0],
                                           net->cur + 3 * (size_t)e[1], q, &t);
        double g = sqrt(d2) - s->model.sph.radius[i] - net->cable_radius_m;
        if (g < gap) gap = g;
    }
    return gap;
}

void dem_sim_net_gap(const dem_sim *s, dem_coupled_info *info)
{
    const dem_net *net = &s->model.net;
    double gap = 1e30;
    long n = (long)s->model.sph.n;
    if (!net->active) {
        /* no net wall: no gap */
    } else if (n >= DEM_PARALLEL_MIN) {
#pragma omp parallel for schedule(static) reduction(min : gap) num_threads(s->work.n_buffers)
        for (long i = 0; i < n; i++) gap = sphere_net_gap(s, net, i, gap);
    } else {
        for (long i = 0; i < n; i++) gap = sphere_net_gap(s, net, i, gap);
    }
    info->min_gap_m = gap;
    info->near_interface = gap < net->near_distance_m;
    long contacts = 0;
    for (size_t k = 0; k < s->contact.list.n; k++)
        contacts += s->contact.list.kind[k] == DEM_CONTACT_NET_EDGE || s->contact.list.kind[k] == DEM_CONTACT_NET_NODE;
    info->contacts = contacts;
}

int dem_sim_check_net_start(const dem_sim *s, nc_error *err)
{
    const dem_net *net = &s->model.net;
    if (!net->active) return 0;
    for (size_t i = 0; i < s->model.sph.n; i++) {
        const double r = s->model.sph.radius[i];
        const double gap = sphere_net_gap(s, net, (long)i, 1e30);
        if (gap < -DEM_START_NET_OVERLAP * r)
            return nc_error_set(err, 1, "%s: particle %d starts %.3g m inside the net (%.0f %% of "
                                "its radius %.3g m past a rope's surface; the net's start "
                                "geometry is the FEM's): place it outside the net, touching at most",
                                s->model.source[0] ? s->model.source : "dem", s->model.sph.id[i],
                                -gap, -100.0 * gap / r, r);
    }
    return 0;
}

/* Algorithm 1's larger step: when no sphere can reach another sphere, a plane or the net
 * during the whole coupling step (travel bound |v| dt + ½ |g| dt² + rotation sweep), the
 * bodies fly ballistically in one exact step instead of sub-stepping. Not with STL meshes
 * (their grid only reaches contact distance). Sets *done when it was applied. */
static int try_free_flight(dem_sim *s, double dt, long substeps, int *done, nc_error *err)
{
    *done = 0;
    if (!s->model.prm.free_flight || s->model.n_meshes > 0 || s->model.sph.n == 0) return 0;
    const double *g = s->model.prm.gravity;
    double gmag = sqrt(g[0] * g[0] + g[1] * g[1] + g[2] * g[2]), travel = 0.0;
    for (size_t b = 0; b < s->model.bod.n; b++) {
        const double *v = s->model.bod.vel + 3 * b, *w = s->model.bod.omega + 3 * b;
        double d = sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]) * dt + 0.5 * gmag * dt * dt;
        if (s->model.bod.is_cluster[b]) {
            double reach = 0.0;
            for (int32_t q = s->model.bod.first_sphere[b]; q < s->model.bod.first_sphere[b] + s->model.bod.n_spheres[b]; q++) {
                const double *o = s->model.sph.offset + 3 * (size_t)q;
                reach = fmax(reach, sqrt(o[0] * o[0] + o[1] * o[1] + o[2] * o[2]));
            }
            d += fmin(sqrt(w[0] * w[0] + w[1] * w[1] + w[2] * w[2]) * dt, 2.0) * reach;
        }
        travel = fmax(travel, d);
    }
    double margin = 1e-6 * travel + 1e-12;
    /* planes (they may move too) */
    for (size_t i = 0; i < s->model.sph.n; i++) {
        const double *p = s->model.sph.pos + 3 * i;
        for (size_t w = 0; w < s->model.n_planes; w++) {
            const dem_plane *pl = &s->model.planes[w];
            double d = (p[0] - pl->point[0]) * pl->normal[0] + (p[1] - pl->point[1]) * pl->normal[1] +
                       (p[2] - pl->point[2]) * pl->normal[2];
            double vp = sqrt(pl->velocity[0] * pl->velocity[0] + pl->velocity[1] * pl->velocity[1] +
                             pl->velocity[2] * pl->velocity[2]);
            if (d > -s->model.sph.radius[i] && d - s->model.sph.radius[i] <= travel + vp * dt + margin) return 0;
        }
    }
    /* the net: gap at the start against sphere travel plus the largest node motion */
    dem_net *net = &s->model.net;
    double node_move = 0.0;
    for (size_t k = 0; k < net->n_nodes; k++) {
        double d[3] = {net->end[3 * k] - net->start[3 * k], net->end[3 * k + 1] - net->start[3 * k + 1],
                       net->end[3 * k + 2] - net->start[3 * k + 2]};
        node_move = fmax(node_move, sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]));
    }
    /* The grid finds every edge within near_distance_m of a sphere; beyond it a sphere's cell
     * may hold a farther edge and miss a nearer one, so a larger gap is not trusted. */
    dem_coupled_info gap;
    dem_sim_net_gap(s, &gap);
    double net_gap = fmin(gap.min_gap_m, net->near_distance_m);
    if (net_gap <= travel + node_move + margin) return 0;
    /* sphere pairs */
    long close;
    if (dem_neighbor_list_close_pairs(s, 2.0 * travel + margin, &close, err)) return -1;
    if (close > 0) return 0;

    dem_free_flight(s, dt, substeps);
    s->time_s += dt;
    s->step++;
    s->contact.list.n = 0;
    memset(s->contact.first, 0, (s->model.sph.n + 1) * sizeof *s->contact.first);
    memset(s->wall_force, 0, 3 * s->n_walls * sizeof *s->wall_force);
    memset(net->force, 0, 3 * net->n_nodes * sizeof *net->force);
    *done = 1;
    return 0;
}

int dem_sim_solve_coupled(dem_sim *s, double dt_step, const double *disp_end,
                          const double *vel_end, double *force_out, dem_coupled_info *info,
                          nc_error *err)
{
    return dem_sim_solve_coupled_jacobian(s, dt_step, disp_end, vel_end, force_out, info, NULL, err);
}

int dem_sim_solve_coupled_jacobian(dem_sim *s, double dt_step, const double *disp_end,
                                   const double *vel_end, double *force_out,
                                   dem_coupled_info *info, dem_net_jacobian *jac, nc_error *err)
{
    dem_net *net = &s->model.net;
    if (!net->active) return nc_error_set(err, 1, "dem: solve before the interface was received");
    if (!(dt_step > 0.0) || !isfinite(dt_step))
        return nc_error_set(err, 1, "dem: coupling step dt_s must be > 0, got %g", dt_step);
    size_t nn = net->n_nodes;
    const double t_start = s->time_s;
    for (size_t k = 0; k < 3 * nn; k++) {
        if (!isfinite(disp_end[k]) || (vel_end && !isfinite(vel_end[k])))
            return nc_error_set(err, 1, "dem: interface displacement/velocity of node %zu is not "
                                        "finite", k / 3);
        net->end[k] = net->ref[k] + disp_end[k];
        net->end_vel[k] = vel_end ? vel_end[k] : 0.0;
    }
    /* bounded before it becomes a count: a coupling step of 1e6 s would otherwise mean 1e9
     * sub-steps that no SHUTDOWN interrupts (nc_time.h) */
    long substeps;
    if (nc_time_check_step(dt_step, s->time_s + dt_step, "dem: coupling step dt_s", err) ||
        nc_time_step_count(dt_step, s->model.prm.dt_s, NC_TIME_MAX_SUBSTEPS,
                           "dem: coupling step dt_s (in DEM sub-steps)", &substeps, err))
        return -1;
    if (substeps < 1) substeps = 1;
    double h = dt_step / (double)substeps;
    if (nc_time_check_step(h, s->time_s + dt_step, "dem: DEM sub-step", err)) return -1;
    memset(net->impulse, 0, 3 * nn * sizeof(double));
    /* the wall moves linearly from start to end: constant velocity over the step */
    for (size_t k = 0; k < 3 * nn; k++) net->vel[k] = (net->end[k] - net->start[k]) / dt_step;
    memcpy(net->cur, net->start, 3 * nn * sizeof(double));
    /* One grid for the whole step, of the edges' boxes over it: every search of the step (the
     * free-flight gap at the start, the contacts of every sub-step, the gap at the end) finds
     * the edges within its reach as a grid of the current positions would (each box holds
     * its edge at any time of the step, and each candidate's distance is tested). Rebuilding
     * the grid at every sub-step took 70 % of the DEM's time on a net of 2000 edges; three
     * builds per step (start, step, end) still 40 % of it on a net of 840 with one rock. */
    if (build_net_grid_over(s, net->start, net->end, err)) return -1;
    int flown = 0;
    if (substeps > 1) {
        if (try_free_flight(s, dt_step, substeps, &flown, err)) return -1;
        if (flown) substeps = 0; /* reported as 1 step below */
    }
    if (jac && dem_net_jacobian_begin(jac, s, dt_step, substeps, err)) return -1;
    for (long sub = 0; sub < substeps; sub++) {
        /* The wall is placed where it is at the END of the sub-step (default): the last
         * sub-step uses exactly the position the FEM returned, so even a single sub-step
         * responds to the iterated interface position (strong coupling then is implicit on the
         * interface instead of silently degenerating to the weak scheme). With wall_position
         * "middle" it is where it is at the middle of the sub-step: centred in time, the
         * average force then belongs to the whole step, which is what a structure applying it
         * over the whole step (fem_solver coupling_load "step_constant") needs to exchange
         * energy without creating any (docs/notes/centred_coupling.md). */
        double frac = ((double)sub + (net->wall_at_middle ? 0.5 : 1.0)) / (double)substeps;
        for (size_t k = 0; k < 3 * nn; k++)
            net->cur[k] = net->start[k] + frac * (net->end[k] - net->start[k]);
        if (jac) { /* the particles as the contact pass saw them, before they move */
            if (dem_sim_step_forces(s, h, err) || dem_net_jacobian_record(jac, s, sub, err)) return -1;
            dem_sim_step_advance(s, h);
        } else if (dem_sim_step(s, h, err)) {
            return -1;
        }
        for (size_t k = 0; k < 3 * nn; k++) net->impulse[k] += h * net->force[k];
    }
    /* the step ends at t_n + dt exactly: sub-step sums drift past the output gate's 1e-12 s */
    s->time_s = t_start + dt_step;
    memcpy(net->cur, net->end, 3 * nn * sizeof(double));
    if (net->force_at_end) {
        /* The force of the last sub-step, whose wall is at its end-of-step position (see the
         * loop above): the load at t_n+1 that a structure with equilibrium at t_n+1 (Newmark,
         * Bossak) needs, and the force the particles received last. The step average stands
         * for the middle of the step: applied as the t_n+1 load it lags the wall by about
         * dt/2, a delayed contact spring that pumps energy into a light net
         * (docs/notes/rest_position.md). After a free flight nothing touches the net
         * and net->force is zero. */
        memcpy(force_out, net->force, 3 * nn * sizeof(double));
    } else {
        for (size_t k = 0; k < 3 * nn; k++) force_out[k] = net->impulse[k] / dt_step;
    }
    dem_sim_net_gap(s, info);
    info->substeps = flown ? 1 : substeps;
    if (jac && dem_net_jacobian_replay(s, jac, disp_end, NULL, 2, err)) return -1;
    return 0;
}
