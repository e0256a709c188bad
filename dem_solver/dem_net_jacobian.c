/* dem_net_jacobian — the record of a coupled step's net contacts and its replay with forward
 * derivatives (the contract is in dem_net_jacobian.h). The replay repeats dem_detect_net.c,
 * dem_emit_wall_contact() and dem_contact_force() for one contact and carries, beside each
 * value, its derivative with respect to the end positions of the nodes the particle touches
 * (3 columns per node); a responding particle (free sphere, or cluster as a rigid body)
 * integrates the change of its net forces as dem_integrate.c does. */
#include "dem_net_jacobian.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "dem_contact_geometry.h"
#include "dem_contact_law.h"
#include "dem_detect.h"
#include "dem_integrate.h"
#include "dem_sim.h"

void dem_net_jacobian_init(dem_net_jacobian *jac)
{
    memset(jac, 0, sizeof *jac);
    jac->particle_response = DEM_JAC_RESPOND_LOCAL;
}

void dem_net_jacobian_free(dem_net_jacobian *jac)
{
    free(jac->nodes);
    free(jac->K);
    free(jac->rec);
    free(jac->frac);
    free(jac->weight);
    free(jac->sub_first);
    free(jac->start);
    int response = jac->particle_response;
    dem_net_jacobian_init(jac);
    jac->particle_response = response;
}

static int grow(void **p, size_t *cap, size_t need, size_t size, nc_error *err)
{
    if (need <= *cap) return 0;
    size_t c = *cap ? *cap : 16;
    while (c < need) c *= 2;
    void *q = realloc(*p, c * size);
    if (!q) return nc_error_set(err, 1, "dem: out of memory for the interface Jacobian");
    *p = q;
    *cap = c;
    return 0;
}

int dem_net_jacobian_begin(dem_net_jacobian *jac, const dem_sim *s, double dt_step,
                           long substeps, nc_error *err)
{
    const dem_net *net = &s->model.net;
    size_t ns = (size_t)(substeps > 0 ? substeps : 0), cap_sub = jac->cap_sub;
    if (ns + 1 > cap_sub) {
        size_t c = ns + 1;
        double *f = realloc(jac->frac, c * sizeof *f), *w = f ? realloc(jac->weight, c * sizeof *w) : NULL;
        if (f) jac->frac = f;
        if (w) jac->weight = w;
        size_t *sf = w ? realloc(jac->sub_first, c * sizeof *sf) : NULL;
        if (!sf) return nc_error_set(err, 1, "dem: out of memory for the interface Jacobian");
        jac->sub_first = sf;
        jac->cap_sub = c;
    }
    if (jac->n_nodes != net->n_nodes) {
        free(jac->start);
        jac->start = malloc(3 * net->n_nodes * sizeof *jac->start);
        if (!jac->start) return nc_error_set(err, 1, "dem: out of memory for the interface Jacobian");
        jac->n_nodes = net->n_nodes;
    }
    memcpy(jac->start, net->start, 3 * net->n_nodes * sizeof *jac->start);
    jac->n_sub = (long)ns;
    jac->n_rec = 0;
    jac->n_blocks = 0;
    jac->dt_step = dt_step;
    jac->h = ns > 0 ? dt_step / (double)ns : dt_step;
    jac->force_at_end = net->force_at_end;
    for (size_t k = 0; k < ns; k++) {
        /* as in dem_sim_solve_coupled() */
        jac->frac[k] = ((double)k + (net->wall_at_middle ? 0.5 : 1.0)) / (double)ns;
        jac->weight[k] = net->force_at_end ? (k + 1 == ns ? 1.0 : 0.0) : jac->h / dt_step;
    }
    jac->sub_first[0] = 0;
    return 0;
}

int dem_net_jacobian_record(dem_net_jacobian *jac, const dem_sim *s, long sub, nc_error *err)
{
    const dem_contacts *c = &s->contact.list, *pv = &s->contact.prev;
    size_t lo = sub > 0 ? jac->sub_first[sub - 1] : 0, hi = jac->n_rec, q = lo;
    for (size_t k = 0; k < c->n; k++) {
        int kind = c->kind[k];
        if (kind != DEM_CONTACT_NET_EDGE && kind != DEM_CONTACT_NET_NODE) continue;
        if (grow((void **)&jac->rec, &jac->cap_rec, jac->n_rec + 1, sizeof *jac->rec, err)) return -1;
        dem_jac_record *r = &jac->rec[jac->n_rec];
        size_t i = (size_t)c->i[k];
        r->sub = (int32_t)sub;
        r->i = (int32_t)i;
        r->kind = kind;
        r->j = c->j[k];
        r->aux = c->aux[k];
        memcpy(r->p, s->model.sph.pos + 3 * i, sizeof r->p);
        memcpy(r->v, s->model.sph.vel + 3 * i, sizeof r->v);
        r->body = s->model.sph.body[i];
        memcpy(r->w, s->model.bod.omega + 3 * (size_t)r->body, sizeof r->w);
        memcpy(r->quat, s->model.bod.quat + 4 * (size_t)r->body, sizeof r->quat);
        for (int k = 0; k < 3; k++) r->offset[k] = r->p[k] - s->model.bod.pos[3 * (size_t)r->body + (size_t)k];
        r->radius = s->model.sph.radius[i];
        r->reach = r->radius + s->model.net.cable_radius_m;
        dem_net_wall_pair(&s->model, i, &r->pair);
        /* the incoming history, looked up by key as dem_new_record() does */
        r->has_prev = 0;
        memset(r->ft, 0, sizeof r->ft);
        memset(r->n_prev, 0, sizeof r->n_prev);
        r->kt_prev = r->fn_prev = r->impact_speed = 0.0;
        for (int32_t p = s->contact.prev_first[i]; p < s->contact.prev_first[i + 1]; p++)
            if (pv->kind[p] == kind && pv->j[p] == r->j && pv->aux[p] == r->aux) {
                r->has_prev = 1;
                memcpy(r->ft, pv->ft + 3 * (size_t)p, sizeof r->ft);
                memcpy(r->n_prev, pv->normal + 3 * (size_t)p, sizeof r->n_prev);
                r->kt_prev = pv->kt_prev[p];
                r->fn_prev = pv->fn_prev[p];
                r->impact_speed = pv->impact_speed[p];
                break;
            }
        /* the same contact in the previous sub-step (both lists are ordered by sphere) */
        r->link = -1;
        while (q < hi && (size_t)jac->rec[q].i < i) q++;
        for (size_t u = q; u < hi && (size_t)jac->rec[u].i == i; u++)
            if (jac->rec[u].kind == kind && jac->rec[u].j == r->j &&
                jac->rec[u].aux == r->aux) {
                r->link = (int32_t)u;
                break;
            }
        jac->n_rec++;
    }
    jac->sub_first[sub + 1] = jac->n_rec;
    return 0;
}

/* ---- the replay ------------------------------------------------------------------------ */

#define NCOL (3 * DEM_JAC_MAX_NODES)

/* The motion of a sphere (or of a body's centre of mass) as changes from the recorded
 * state, and their tangents (columns: the particle's nodes, 3 each). */
typedef struct motion {
    double dx[3], dv[3], dw[3];   /* centre (m), its velocity (m/s), the body's spin (rad/s) */
    double Dx[3][NCOL], Dv[3][NCOL], Dw[3][NCOL];
} motion;

/* A particle that touches the net in the step — a free sphere, a cluster as one rigid body,
 * or one sphere of a cluster split for its many nodes — with its nodes (the columns of its
 * tangents) and, with the particle response, the tangents and value changes of its state. */
typedef struct particle {
    int32_t body, sphere;     /* sphere: -1 for the whole body */
    int n_nodes, respond, has_edge, cluster;
    int overflow;             /* touches more than DEM_JAC_MAX_NODES nodes: left out of K */
    int32_t node[DEM_JAC_MAX_NODES];
    motion m;                 /* the body's centre of mass and spin */
    double dth[3], Dth[3][NCOL];   /* the body's turn (rad; clusters) */
    double inv_inertia[9];    /* world frame, at its first recorded contact (clusters) */
    double sf[3], st[3], Dsf[3][NCOL], Dst[3][NCOL]; /* net force / torque (about the centre
                                                        of mass) change of a sub-step */
} particle;

/* The motion of record r's sphere from its body's (place_spheres() of dem_integrate.c):
 * x = x_b + o, v = v_b + ω × o, with the offset o turned by the body's turn θ (δo = θ × o),
 * to first order. A free sphere (o = 0) moves as its body. */
static const motion *sphere_motion(const particle *pt, const dem_jac_record *r, int nc,
                                   int want, motion *scratch)
{
    const double *o = r->offset;
    if (o[0] == 0.0 && o[1] == 0.0 && o[2] == 0.0) return &pt->m;
    double to[3], wto[3], dwo[3];
    dem_cross3(pt->dth, o, to);
    dem_cross3(r->w, to, wto);
    dem_cross3(pt->m.dw, o, dwo);
    for (int k = 0; k < 3; k++) {
        scratch->dx[k] = pt->m.dx[k] + to[k];
        scratch->dv[k] = pt->m.dv[k] + dwo[k] + wto[k];
        scratch->dw[k] = pt->m.dw[k];
    }
    for (int c = 0; c < nc && want; c++) {
        double Dth[3] = {pt->Dth[0][c], pt->Dth[1][c], pt->Dth[2][c]};
        double Dw[3] = {pt->m.Dw[0][c], pt->m.Dw[1][c], pt->m.Dw[2][c]}, Dto[3], wDto[3], Dwo[3];
        dem_cross3(Dth, o, Dto);
        dem_cross3(r->w, Dto, wDto);
        dem_cross3(Dw, o, Dwo);
        for (int k = 0; k < 3; k++) {
            scratch->Dx[k][c] = pt->m.Dx[k][c] + Dto[k];
            scratch->Dv[k][c] = pt->m.Dv[k][c] + Dwo[k] + wDto[k];
            scratch->Dw[k][c] = Dw[k];
        }
    }
    return scratch;
}

/* The net nodes of record r: 1 (a node contact) or 2 (an edge's). */
static int record_nodes(const dem_net *net, const dem_jac_record *r, int32_t nodes[2])
{
    int edge = r->kind == DEM_CONTACT_NET_EDGE;
    nodes[0] = edge ? net->edges[2 * (size_t)r->j] : r->j;
    nodes[1] = edge ? net->edges[2 * (size_t)r->j + 1] : r->j;
    return edge ? 2 : 1;
}

static double dot3(const double a[3], const double b[3])
{
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

/* Tangents have NCOL columns, of which a particle uses its nc = 3 n_nodes: only those are
 * cleared and copied (a free sphere on one node uses 3 of 96; clearing all of them was a
 * fifth of the replay's time on a barrier). */
static void zero_cols(double a[3][NCOL], int nc)
{
    for (int k = 0; k < 3; k++) memset(a[k], 0, (size_t)nc * sizeof a[k][0]);
}

/* column c of a 3xNCOL tangent dotted with a vector */
static double col_dot(const double a[3], double d[3][NCOL], int c)
{
    return a[0] * d[0][c] + a[1] * d[1][c] + a[2] * d[2][c];
}

static int local_index(const particle *pt, int32_t node)
{
    for (int k = 0; k < pt->n_nodes; k++)
        if (pt->node[k] == node) return k;
    return -1;
}

/* One contact of one sub-step: the force f on sphere i, its torque tq about the centre and
 * the nodal weight t, with their tangents (columns: the particle's nodes, 3 each). The
 * outgoing history in out. */
static void contact(const dem_sim *s, const dem_net_jacobian *jac, const dem_jac_record *r,
                    const double *end, const dem_jac_state *in, const particle *pt,
                    const motion *mo, int want,
                    double f[3], double tq[3], double df[3][NCOL], double dtq[3][NCOL],
                    double *t_out, double dt_out[NCOL], dem_jac_state *out)
{
    const dem_net *net = &s->model.net;
    const dem_params *prm = &s->model.prm;
    const dem_contact_law *law = dem_contact_law_of(prm->law);
    double frac = jac->frac[r->sub], dts = jac->dt_step, h = jac->h;
    int32_t nodes[2];
    const int edge = record_nodes(net, r, nodes) == 2;
    const int32_t na = nodes[0], nb = nodes[1];
    int nc = 3 * pt->n_nodes, ca = 3 * local_index(pt, na), cb = 3 * local_index(pt, nb);
    double xa[3], xb[3], va[3], vb[3];
    for (int k = 0; k < 3; k++) {
        size_t ka = 3 * (size_t)na + (size_t)k, kb = 3 * (size_t)nb + (size_t)k;
        const double *st = jac->start;
        xa[k] = st[ka] + frac * (end[ka] - st[ka]);
        xb[k] = st[kb] + frac * (end[kb] - st[kb]);
        va[k] = (end[ka] - st[ka]) / dts;
        vb[k] = (end[kb] - st[kb]) / dts;
    }
    /* the particle: recorded state plus its response (zero when frozen) */
    double p[3], vi[3], w[3];
    for (int k = 0; k < 3; k++) {
        p[k] = r->p[k] + mo->dx[k];
        vi[k] = r->v[k] + mo->dv[k];
        w[k] = r->w[k] + mo->dw[k];
    }
    /* closest point (dem_detect_net.c) */
    double q[3], t = 0.0, Dt[NCOL], Dq[3][NCOL];
    memset(Dt, 0, (size_t)nc * sizeof Dt[0]);
    zero_cols(Dq, nc);
    if (edge) {
        dem_closest_on_segment(p, xa, xb, q, &t);
    } else {
        memcpy(q, xa, sizeof q);
    }
    double d[3] = {xb[0] - xa[0], xb[1] - xa[1], xb[2] - xa[2]};
    double ap[3] = {p[0] - xa[0], p[1] - xa[1], p[2] - xa[2]};
    double M = dot3(d, d);
    int interior = edge && t > 0.0 && t < 1.0;
    if (want)
        for (int c = 0; c < nc; c++) {
            double Dxa[3], Dxb[3];
            for (int k = 0; k < 3; k++) {
                Dxa[k] = c == ca + k ? frac : 0.0;
                Dxb[k] = c == cb + k ? frac : 0.0;
            }
            if (edge) {
                double Dd[3], dN = 0.0, dM = 0.0;
                for (int k = 0; k < 3; k++) {
                    Dd[k] = Dxb[k] - Dxa[k];
                    dN += (mo->Dx[k][c] - Dxa[k]) * d[k] + ap[k] * Dd[k];
                    dM += 2.0 * d[k] * Dd[k];
                }
                Dt[c] = interior ? (dN - t * dM) / M : 0.0;
                for (int k = 0; k < 3; k++) Dq[k][c] = Dxa[k] + Dt[c] * d[k] + t * Dd[k];
            } else {
                for (int k = 0; k < 3; k++) Dq[k][c] = Dxa[k];
            }
        }
    double rr[3] = {q[0] - p[0], q[1] - p[1], q[2] - p[2]};
    double dist = sqrt(dot3(rr, rr));
    double n[3], Dn[3][NCOL], Ddist[NCOL], Dr[3][NCOL];
    zero_cols(Dn, nc);
    zero_cols(Dr, nc);
    memset(Ddist, 0, (size_t)nc * sizeof Ddist[0]);
    for (int k = 0; k < 3; k++) n[k] = rr[k] / dist;
    for (int c = 0; c < nc && want; c++) {
        for (int k = 0; k < 3; k++) Dr[k][c] = Dq[k][c] - mo->Dx[k][c];
        Ddist[c] = col_dot(n, Dr, c);
        for (int k = 0; k < 3; k++) Dn[k][c] = (Dr[k][c] - n[k] * Ddist[c]) / dist;
    }
    double overlap = r->reach - dist, Dov[NCOL];
    for (int c = 0; c < nc; c++) Dov[c] = -Ddist[c];
    double lever = r->radius - 0.5 * overlap, Dlever[NCOL];
    for (int c = 0; c < nc; c++) Dlever[c] = -0.5 * Dov[c];
    /* the incoming history (dem_new_record) and the crossed-cable flip (dem_emit_wall_contact) */
    double ft[3], kt_prev, fn_prev, impact_speed, Dft[3][NCOL], Dktp[NCOL];
    double Dv0[NCOL];   /* of impact_speed, when an earlier sub-step of this step set it */
    const double *np;
    int has_prev;
    zero_cols(Dft, nc);
    memset(Dktp, 0, (size_t)nc * sizeof Dktp[0]);
    memset(Dv0, 0, (size_t)nc * sizeof Dv0[0]);
    if (in) {
        memcpy(ft, in->ft, sizeof ft);
        kt_prev = in->kt;
        fn_prev = in->fn;
        impact_speed = in->impact_speed;
        np = in->n;
        has_prev = 1;
        for (int k = 0; k < 3; k++) memcpy(Dft[k], in->dft[k], (size_t)nc * sizeof Dft[k][0]);
        memcpy(Dktp, in->dkt, (size_t)nc * sizeof Dktp[0]);
        memcpy(Dv0, in->dv0, (size_t)nc * sizeof Dv0[0]);
    } else if (r->sub == 0 && r->has_prev) {
        memcpy(ft, r->ft, sizeof ft);
        kt_prev = r->kt_prev;
        fn_prev = r->fn_prev;
        impact_speed = r->impact_speed;
        np = r->n_prev;
        has_prev = 1;
    } else {
        ft[0] = ft[1] = ft[2] = 0.0;
        kt_prev = fn_prev = impact_speed = 0.0;
        np = NULL;
        has_prev = 0;
    }
    if (has_prev && dot3(np, n) < 0.0) {
        overlap = r->reach + dist;
        for (int k = 0; k < 3; k++) n[k] = -n[k];
        double l = r->radius - 0.5 * overlap;
        lever = fmax(0.0, l);
        for (int c = 0; c < nc; c++) {
            Dov[c] = Ddist[c];
            for (int k = 0; k < 3; k++) Dn[k][c] = -Dn[k][c];
            Dlever[c] = l > 0.0 ? -0.5 * Dov[c] : 0.0;
        }
    }
    /* relative velocity (eq. (A.2)): the wall point minus the sphere's surface point */
    double vo[3], Dvo[3][NCOL];
    zero_cols(Dvo, nc);
    for (int k = 0; k < 3; k++) {
        vo[k] = edge ? (1.0 - t) * va[k] + t * vb[k] : va[k];
        for (int c = 0; c < nc && want; c++) {
            double Dva = c == ca + k ? 1.0 / dts : 0.0, Dvb = c == cb + k ? 1.0 / dts : 0.0;
            Dvo[k][c] = edge ? (1.0 - t) * Dva + t * Dvb + Dt[c] * (vb[k] - va[k]) : Dva;
        }
    }
    double ri[3] = {lever * n[0], lever * n[1], lever * n[2]}, wr[3];
    wr[0] = w[1] * ri[2] - w[2] * ri[1];
    wr[1] = w[2] * ri[0] - w[0] * ri[2];
    wr[2] = w[0] * ri[1] - w[1] * ri[0];
    double vc[3], Dvc[3][NCOL], Dri[3][NCOL];
    zero_cols(Dvc, nc);
    zero_cols(Dri, nc);
    for (int k = 0; k < 3; k++) vc[k] = vo[k] - (vi[k] + wr[k]);
    for (int c = 0; c < nc && want; c++) {
        for (int k = 0; k < 3; k++) Dri[k][c] = Dlever[c] * n[k] + lever * Dn[k][c];
        double a1[3] = {mo->Dw[0][c], mo->Dw[1][c], mo->Dw[2][c]};
        double b1[3] = {Dri[0][c], Dri[1][c], Dri[2][c]};
        double Dwr[3] = {a1[1] * ri[2] - a1[2] * ri[1] + w[1] * b1[2] - w[2] * b1[1],
                         a1[2] * ri[0] - a1[0] * ri[2] + w[2] * b1[0] - w[0] * b1[2],
                         a1[0] * ri[1] - a1[1] * ri[0] + w[0] * b1[1] - w[1] * b1[0]};
        for (int k = 0; k < 3; k++) Dvc[k][c] = Dvo[k][c] - mo->Dv[k][c] - Dwr[k];
    }
    /* the values exactly as the DEM computes them */
    double ft_in[3] = {ft[0], ft[1], ft[2]}, ktp_in = kt_prev, fnp_in = fn_prev;
    const double v0_in = impact_speed;
    dem_contact_force(prm, &r->pair, overlap, n, vc, h, ft, &kt_prev, &fn_prev, &impact_speed, f);
    tq[0] = ri[1] * f[2] - ri[2] * f[1];
    tq[1] = ri[2] * f[0] - ri[0] * f[2];
    tq[2] = ri[0] * f[1] - ri[1] * f[0];
    memcpy(out->ft, ft, sizeof ft);
    out->kt = kt_prev;
    out->fn = fn_prev;
    out->impact_speed = impact_speed;
    memcpy(out->n, n, sizeof n);
    *t_out = t;
    if (!want) return;

    /* ---- tangents of dem_contact_force() ---- */
    const dem_pair *pr = &r->pair;
    dem_law_normal L;
    law->normal(prm, pr, overlap, &L);
    double vn = dot3(vc, n), rate = -vn, Dvn[NCOL];
    for (int c = 0; c < nc; c++) Dvn[c] = col_dot(n, Dvc, c) + col_dot(vc, Dn, c);
    /* the Hunt–Crossley dashpot's ξ = hunt_crossley / v0 with v0 the contact's fastest
     * approach so far: held where this sub-step is slower; where this sub-step set it
     * (v0 = δ̇ above the floor) ξ δ̇ = c(ε) and the force is (1 + c) times the elastic one */
    const int hunt_crossley = prm->damping == DEM_DAMPING_HUNT_CROSSLEY;
    const int v0_now = hunt_crossley && rate > DEM_HUNT_CROSSLEY_MIN_SPEED && !(v0_in >= rate);
    const double xi = hunt_crossley ? pr->hunt_crossley / impact_speed : 0.0;
    double fn = hunt_crossley ? L.fn_elastic * (1.0 + xi * rate)
                              : L.fn_elastic + 2.0 * pr->zeta * L.cn_root * rate, Dfn[NCOL];
    int clamped = law->no_tension && fn < 0.0;
    if (clamped) fn = 0.0;
    /* a v0 held from an earlier sub-step of this step depends on u^{n+1} through that
     * sub-step's δ̇ (Dv0): ∂fn/∂v0 = −fn_elastic ξ δ̇ / v0; where this sub-step sets v0 it
     * becomes δ̇ here, Dv0 = Dδ̇ = −Dvn */
    for (int c = 0; c < nc; c++)
        Dfn[c] = clamped ? 0.0
                 : v0_now ? L.kn_tangent * (1.0 + pr->hunt_crossley) * Dov[c]
                 : hunt_crossley ? L.kn_tangent * (1.0 + xi * rate) * Dov[c] - L.fn_elastic * xi * Dvn[c] -
                                       L.fn_elastic * xi * rate * Dv0[c] / impact_speed
                                 : (L.kn_tangent + 2.0 * pr->zeta * L.dcn_root * rate) * Dov[c] -
                                       2.0 * pr->zeta * L.cn_root * Dvn[c];
    double kt = L.kt, Dkt[NCOL], ct = 2.0 * pr->zeta * L.cn_root * pr->kt_kn_root, Dct[NCOL];
    for (int c = 0; c < nc; c++) {
        Dkt[c] = L.dkt * Dov[c];
        Dct[c] = 2.0 * pr->zeta * L.dcn_root * pr->kt_kn_root * Dov[c];
    }
    double vt[3], Dvt[3][NCOL];
    for (int k = 0; k < 3; k++) {
        vt[k] = vc[k] - vn * n[k];
        for (int c = 0; c < nc; c++) Dvt[k][c] = Dvc[k][c] - Dvn[c] * n[k] - vn * Dn[k][c];
    }
    double g[3] = {ft_in[0], ft_in[1], ft_in[2]};
    double old2 = dot3(g, g);
    if (old2 > 0.0) {
        double fdn = dot3(g, n), g1[3], Dg1[3][NCOL];
        for (int k = 0; k < 3; k++) g1[k] = g[k] - fdn * n[k];
        for (int c = 0; c < nc; c++) {
            double Dfdn = col_dot(n, Dft, c) + col_dot(g, Dn, c);
            for (int k = 0; k < 3; k++) Dg1[k][c] = Dft[k][c] - Dfdn * n[k] - fdn * Dn[k][c];
        }
        double new2 = dot3(g1, g1);
        double sc = new2 > 0.0 ? sqrt(old2 / new2) : 0.0, Dsc[NCOL];
        for (int c = 0; c < nc; c++) {
            double Dold2 = 2.0 * col_dot(g, Dft, c), Dnew2 = 2.0 * col_dot(g1, Dg1, c);
            Dsc[c] = new2 > 0.0 ? 0.5 * sc * (Dold2 / old2 - Dnew2 / new2) : 0.0;
        }
        if (fn < fnp_in && ktp_in > 0.0) { /* unloading: times kt / kt_prev */
            double ratio = kt / ktp_in;
            for (int c = 0; c < nc; c++)
                Dsc[c] = Dsc[c] * ratio + sc * (Dkt[c] - ratio * Dktp[c]) / ktp_in;
            sc *= ratio;
        }
        for (int k = 0; k < 3; k++) {
            for (int c = 0; c < nc; c++) Dft[k][c] = Dsc[c] * g1[k] + sc * Dg1[k][c];
            g[k] = sc * g1[k];
        }
    }
    for (int k = 0; k < 3; k++) { /* eq. (A.4) */
        for (int c = 0; c < nc; c++) Dft[k][c] += (Dkt[c] * vt[k] + kt * Dvt[k][c]) * h;
        g[k] += kt * vt[k] * h;
    }
    double tr[3], Dtr[3][NCOL];
    for (int k = 0; k < 3; k++) {
        tr[k] = g[k] + ct * vt[k];
        for (int c = 0; c < nc; c++) Dtr[k][c] = Dft[k][c] + Dct[c] * vt[k] + ct * Dvt[k][c];
    }
    double trial2 = dot3(tr, tr), cap = pr->mu * (fn > 0.0 ? fn : 0.0);
    if (trial2 > cap * cap) { /* Coulomb: the spring slides at the cap */
        double len = sqrt(trial2), sc = trial2 > 0.0 ? cap / len : 0.0, Dcap[NCOL];
        double Dg[3][NCOL];   /* the trial spring's, for the spring limit below */
        for (int k = 0; k < 3; k++) memcpy(Dg[k], Dft[k], (size_t)nc * sizeof Dg[k][0]);
        for (int c = 0; c < nc; c++) {
            Dcap[c] = fn > 0.0 ? pr->mu * Dfn[c] : 0.0;
            double Dlen = trial2 > 0.0 ? col_dot(tr, Dtr, c) / len : 0.0;
            double Dsc = trial2 > 0.0 ? (Dcap[c] - sc * Dlen) / len : 0.0;
            for (int k = 0; k < 3; k++) {
                Dtr[k][c] = Dsc * tr[k] + sc * Dtr[k][c];
                Dft[k][c] = Dtr[k][c] - Dct[c] * vt[k] - ct * Dvt[k][c];
            }
        }
        for (int k = 0; k < 3; k++) tr[k] *= sc;
        /* the spring limit of dem_contact_force(): |ft| <= min(cap, |trial spring|) */
        double s[3] = {tr[0] - ct * vt[0], tr[1] - ct * vt[1], tr[2] - ct * vt[2]};
        double s2 = dot3(s, s), g2 = dot3(g, g), limit2 = fmin(cap * cap, g2);
        if (s2 > limit2) {
            double q = sqrt(limit2 / s2);
            for (int c = 0; c < nc; c++) {
                double Dlimit2 = cap * cap <= g2 ? 2.0 * cap * Dcap[c] : 2.0 * col_dot(g, Dg, c);
                double Ds2 = 2.0 * col_dot(s, Dft, c);
                double Dq = limit2 > 0.0 ? 0.5 * q * (Dlimit2 / limit2 - Ds2 / s2) : 0.0;
                for (int k = 0; k < 3; k++) Dft[k][c] = Dq * s[k] + q * Dft[k][c];
            }
        }
    }
    for (int k = 0; k < 3; k++)
        for (int c = 0; c < nc; c++) df[k][c] = -Dfn[c] * n[k] - fn * Dn[k][c] + Dtr[k][c];
    for (int c = 0; c < nc; c++) { /* torque ri x f */
        dtq[0][c] = Dri[1][c] * f[2] - Dri[2][c] * f[1] + ri[1] * df[2][c] - ri[2] * df[1][c];
        dtq[1][c] = Dri[2][c] * f[0] - Dri[0][c] * f[2] + ri[2] * df[0][c] - ri[0] * df[2][c];
        dtq[2][c] = Dri[0][c] * f[1] - Dri[1][c] * f[0] + ri[0] * df[1][c] - ri[1] * df[0][c];
    }
    for (int c = 0; c < nc; c++) {   /* the next sub-step of this contact reads nc columns */
        for (int k = 0; k < 3; k++) out->dft[k][c] = Dft[k][c];
        out->dkt[c] = Dkt[c];
        out->dv0[c] = v0_now ? -Dvn[c] : Dv0[c];
        dt_out[c] = Dt[c];
    }
}

/* Orders blocks by (i, j). */
typedef struct block {
    int32_t i, j;
    double k[9];
} block;

static int block_cmp(const void *a, const void *b)
{
    const block *x = a, *y = b;
    if (x->i != y->i) return x->i < y->i ? -1 : 1;
    if (x->j != y->j) return x->j < y->j ? -1 : 1;
    return 0;
}

/* The blocks of a replay, summed per (i, j) as they come: an open-addressing table from the
 * pair to its block. Each pair's contributions are added in the order the records produce
 * them, the order the stable sort and merge of all contributions used to sum them in (the
 * same K bit for bit); that sort of one entry per record and node pair was a tenth of the
 * DEM's time on a barrier, its table a few MB. */
typedef struct block_sum {
    block *blocks;
    size_t n, cap;            /* blocks */
    uint32_t *slot;           /* table: block index + 1, 0 = empty */
    size_t table_cap;         /* a power of 2, at least twice n */
} block_sum;

static size_t pair_hash(int32_t i, int32_t j, size_t mask)
{
    uint64_t key = ((uint64_t)(uint32_t)i << 32) | (uint32_t)j;
    key *= 0x9E3779B97F4A7C15ull;
    return (size_t)(key >> 32) & mask;
}

/* The block of (i, j); *created when it is new (its k then unset); NULL when out of
 * memory. */
static block *block_at(block_sum *bs, int32_t i, int32_t j, int *created)
{
    *created = 0;
    if (2 * (bs->n + 1) > bs->table_cap) {
        size_t cap = bs->table_cap ? 2 * bs->table_cap : 64;
        uint32_t *slot = calloc(cap, sizeof *slot);
        if (!slot || bs->n + 1 > UINT32_MAX - 1) {
            free(slot);
            return NULL;
        }
        for (size_t b = 0; b < bs->n; b++) {
            size_t h = pair_hash(bs->blocks[b].i, bs->blocks[b].j, cap - 1);
            while (slot[h]) h = (h + 1) & (cap - 1);
            slot[h] = (uint32_t)(b + 1);
        }
        free(bs->slot);
        bs->slot = slot;
        bs->table_cap = cap;
    }
    size_t h = pair_hash(i, j, bs->table_cap - 1);
    for (; bs->slot[h]; h = (h + 1) & (bs->table_cap - 1)) {
        block *bk = &bs->blocks[bs->slot[h] - 1];
        if (bk->i == i && bk->j == j) return bk;
    }
    if (bs->n == bs->cap) {
        size_t cap = bs->cap ? 2 * bs->cap : 64;
        block *blocks = realloc(bs->blocks, cap * sizeof *blocks);
        if (!blocks) return NULL;
        bs->blocks = blocks;
        bs->cap = cap;
    }
    block *bk = &bs->blocks[bs->n++];
    bs->slot[h] = (uint32_t)bs->n;
    bk->i = i;
    bk->j = j;
    *created = 1;
    return bk;
}

static int rec_cmp(const void *a, const void *b)
{
    const dem_jac_record *const *x = a, *const *y = b;
    if ((*x)->body != (*y)->body) return (*x)->body < (*y)->body ? -1 : 1;
    return (*x)->i < (*y)->i ? -1 : (*x)->i > (*y)->i;
}

/* Whether the n records at rec touch more than DEM_JAC_MAX_NODES distinct nodes. */
static int too_many_nodes(const dem_net *net, const dem_jac_record *const *rec, size_t n)
{
    int32_t seen[DEM_JAC_MAX_NODES];
    int count = 0;
    for (size_t x = 0; x < n; x++) {
        int32_t nodes[2];
        for (int k = 0, m = record_nodes(net, rec[x], nodes); k < m; k++) {
            int known = 0;
            for (int q = 0; q < count && !known; q++) known = seen[q] == nodes[k];
            if (known) continue;
            if (count == DEM_JAC_MAX_NODES) return 1;
            seen[count++] = nodes[k];
        }
    }
    return 0;
}

/* The particles of the records, each with its nodes; slot[x] is record x's particle. A
 * cluster is one particle (a rigid body) unless it touches more than DEM_JAC_MAX_NODES
 * nodes: then each of its spheres is one, frozen. */
static int collect_particles(const dem_sim *s, const dem_net_jacobian *jac, particle **out,
                             size_t *n_out, size_t *slot, nc_error *err)
{
    const dem_net *net = &s->model.net;
    const dem_bodies *bod = &s->model.bod;
    size_t nr = jac->n_rec, np = 0;
    const dem_jac_record **order = malloc((nr + 1) * sizeof *order);
    if (!order) return nc_error_set(err, 1, "dem: out of memory for the interface Jacobian");
    for (size_t x = 0; x < nr; x++) order[x] = &jac->rec[x];
    qsort(order, nr, sizeof *order, rec_cmp);
    size_t distinct = 0;   /* at most one particle struct (tangent columns) per sphere */
    for (size_t x = 0; x < nr; x++) distinct += x == 0 || order[x]->i != order[x - 1]->i;
    particle *pts = calloc(distinct + 1, sizeof *pts);
    if (!pts) {
        free(order);
        return nc_error_set(err, 1, "dem: out of memory for the interface Jacobian");
    }
    for (size_t x = 0, y; x < nr; x = y) {
        const int32_t b = order[x]->body;
        for (y = x; y < nr && order[y]->body == b; y++) {}
        const int whole = bod->is_cluster[b] && !too_many_nodes(net, order + x, y - x);
        for (size_t z = x; z < y; z++) {
            const dem_jac_record *r = order[z];
            const int32_t sphere = whole ? -1 : r->i;
            if (np == 0 || pts[np - 1].body != b || pts[np - 1].sphere != sphere) {
                particle *pt = &pts[np++];
                pt->body = b;
                pt->sphere = sphere;
                pt->cluster = whole;
                pt->respond = jac->particle_response && (whole || !bod->is_cluster[b]);
                if (whole) { /* R I_body⁻¹ Rᵀ at the body's first recorded contact, column
                              * by column as dem_integrate.c maps L to ω */
                    const dem_jac_record *first = order[x];
                    for (size_t q = x + 1; q < y; q++)
                        if (order[q] < first) first = order[q];
                    for (int j = 0; j < 3; j++) {
                        const double unit[3] = {j == 0, j == 1, j == 2};
                        double col[3];
                        dem_cluster_omega(first->quat, bod->inv_inertia_body + 9 * (size_t)b, unit, col);
                        for (int i = 0; i < 3; i++) pt->inv_inertia[3 * i + j] = col[i];
                    }
                }
            }
            particle *pt = &pts[np - 1];
            slot[r - jac->rec] = np - 1;
            int32_t nodes[2];
            int m = record_nodes(net, r, nodes);
            pt->has_edge |= m == 2;
            for (int k = 0; k < m; k++) {
                if (pt->overflow || local_index(pt, nodes[k]) >= 0) continue;
                if (pt->n_nodes == DEM_JAC_MAX_NODES) {
                    /* its force stays exact; its share of K is left out (counted in n_dropped) */
                    pt->overflow = 1;
                    pt->respond = 0;
                    continue;
                }
                pt->node[pt->n_nodes++] = nodes[k];
            }
        }
    }
    free(order);
    /* DEM_JAC_RESPOND_LOCAL: only a particle whose nodes are one node or one edge's two
     * nodes responds (its blocks then stay within one element) */
    for (size_t k = 0; k < np && jac->particle_response == DEM_JAC_RESPOND_LOCAL; k++)
        if (!(pts[k].n_nodes == 1 || (pts[k].n_nodes == 2 && pts[k].has_edge))) pts[k].respond = 0;
    *out = pts;
    *n_out = np;
    return 0;
}

int dem_net_jacobian_replay(const dem_sim *s, dem_net_jacobian *jac, const double *disp_end,
                            double *force_out, int want_K, nc_error *err)
{
    const dem_net *net = &s->model.net;
    size_t nn = net->n_nodes;
    if (jac->n_nodes != nn) return nc_error_set(err, 1, "dem: Jacobian replay without a recorded step");
    /* the base values (f, torque) are taken at the displacement of the solve: the replay
     * with want_K from dem_sim_solve_coupled_jacobian() */
    int base = want_K == 2;
    double *end = malloc(3 * nn * sizeof *end);
    double *force = calloc(3 * nn, sizeof *force);
    double *impulse = calloc(3 * nn, sizeof *impulse);
    /* the nodes a sub-step's contacts load (each at most twice per record) and the sub-step
     * that last added a node to the impulse: the net has thousands of nodes, a sub-step's
     * contacts load a few, and clearing and summing all of them per sub-step was most of
     * the replay's time on the MEL test */
    int32_t *touched = malloc((2 * jac->n_rec + 1) * sizeof *touched);
    long *added_in = malloc((nn + 1) * sizeof *added_in);
    size_t n_touched = 0;
    size_t *slot = malloc((jac->n_rec + 1) * sizeof *slot);
    block_sum sum = {0};
    dem_jac_state *state = malloc((jac->n_rec + 1) * sizeof *state);
    particle *pts = NULL;
    motion *scratch = malloc(sizeof *scratch);   /* a cluster sphere's motion */
    size_t npt = 0;
    int rc = 0;
    if (!end || !force || !impulse || !touched || !added_in || !slot || !state || !scratch) {
        rc = nc_error_set(err, 1, "dem: out of memory for the interface Jacobian");
        goto done;
    }
    if (collect_particles(s, jac, &pts, &npt, slot, err)) {
        rc = -1;
        goto done;
    }
    jac->n_dropped = 0;
    for (size_t k = 0; k < npt; k++) jac->n_dropped += pts[k].overflow;
    for (size_t k = 0; k < 3 * nn; k++) end[k] = net->ref[k] + disp_end[k];
    for (size_t k = 0; k < nn; k++) added_in[k] = -1;
    for (long sub = 0; sub < jac->n_sub; sub++) {
        for (size_t x = 0; x < n_touched; x++)
            memset(force + 3 * (size_t)touched[x], 0, 3 * sizeof *force);
        n_touched = 0;
        double wgt = jac->weight[sub];
        for (size_t x = jac->sub_first[sub]; x < jac->sub_first[sub + 1]; x++) {
            dem_jac_record *r = &jac->rec[x];
            particle *pt = &pts[slot[x]];
            const dem_jac_state *in = r->sub > 0 && r->link >= 0 ? &state[r->link] : NULL;
            double f[3], tq[3], df[3][NCOL], dtq[3][NCOL], t, dt[NCOL];   /* nc columns set
                                                                             when want */
            const int want = want_K && !pt->overflow, nc = 3 * pt->n_nodes;
            const motion *mo = pt->cluster ? sphere_motion(pt, r, nc, want, scratch) : &pt->m;
            contact(s, jac, r, end, in, pt, mo, want, f, tq, df, dtq, &t, dt, &state[x]);
            if (base) {
                memcpy(r->f_base, f, sizeof f);
                memcpy(r->t_base, tq, sizeof tq);
            }
            if (pt->respond && !pt->cluster) { /* the change of the net's force and torque */
                for (int k = 0; k < 3; k++) {
                    pt->sf[k] += f[k] - r->f_base[k];
                    pt->st[k] += tq[k] - r->t_base[k];
                    for (int c = 0; c < nc && want_K; c++) {
                        pt->Dsf[k][c] += df[k][c];
                        pt->Dst[k][c] += dtq[k][c];
                    }
                }
            } else if (pt->respond) { /* a cluster: the torque about its centre of mass, with
                                       * the offset o turned by θ: tq + (o + θ × o) × f */
                const double *o = r->offset;
                double dfv[3] = {f[0] - r->f_base[0], f[1] - r->f_base[1], f[2] - r->f_base[2]};
                double to[3], odf[3], tof[3];
                dem_cross3(pt->dth, o, to);
                dem_cross3(o, dfv, odf);
                dem_cross3(to, f, tof);
                for (int k = 0; k < 3; k++) {
                    pt->sf[k] += dfv[k];
                    pt->st[k] += tq[k] - r->t_base[k] + odf[k] + tof[k];
                }
                for (int c = 0; c < nc && want_K; c++) {
                    double Dfc[3] = {df[0][c], df[1][c], df[2][c]};
                    double Dth[3] = {pt->Dth[0][c], pt->Dth[1][c], pt->Dth[2][c]};
                    double Dto[3], oDf[3], Dtof[3], toDf[3];
                    dem_cross3(Dth, o, Dto);
                    dem_cross3(o, Dfc, oDf);
                    dem_cross3(Dto, f, Dtof);
                    dem_cross3(to, Dfc, toDf);
                    for (int k = 0; k < 3; k++) {
                        pt->Dsf[k][c] += df[k][c];
                        pt->Dst[k][c] += dtq[k][c] + oDf[k] + Dtof[k] + toDf[k];
                    }
                }
            }
            int32_t nodes[2];
            const int nrow = record_nodes(net, r, nodes), edge = nrow == 2;
            const int32_t na = nodes[0], nb = nodes[1];
            if (edge) { /* as the contact pass sums the net reactions */
                for (int d = 0; d < 3; d++) {
                    force[3 * (size_t)na + (size_t)d] -= (1.0 - t) * f[d];
                    force[3 * (size_t)nb + (size_t)d] -= t * f[d];
                }
                touched[n_touched++] = na;
                touched[n_touched++] = nb;
            } else {
                for (int d = 0; d < 3; d++) force[3 * (size_t)r->j + (size_t)d] -= f[d];
                touched[n_touched++] = r->j;
            }
            if (!want_K || wgt == 0.0 || pt->overflow) continue;
            /* F_a = -(1-t) f, F_b = -t f; K = -weight dF; columns: the particle's nodes
             * (frozen: only this contact's nodes carry a derivative) */
            for (int a = 0; a < nrow; a++) {
                double sa = a == 0 ? 1.0 - t : t, sgn = a == 0 ? 1.0 : -1.0;
                for (int b = 0; b < pt->n_nodes; b++) {
                    int32_t node_b = pt->node[b];
                    if (!pt->respond && node_b != na && node_b != nb) continue;
                    int created;
                    block *bk = block_at(&sum, nodes[a], node_b, &created);
                    if (!bk) {
                        rc = nc_error_set(err, 1, "dem: out of memory for the interface Jacobian");
                        goto done;
                    }
                    for (int row = 0; row < 3; row++)
                        for (int c = 0; c < 3; c++) {
                            int col = 3 * b + c;
                            double dF = -sa * df[row][col] + (edge ? sgn * dt[col] * f[row] : 0.0);
                            if (created) bk->k[3 * row + c] = -wgt * dF;
                            else bk->k[3 * row + c] += -wgt * dF;
                        }
                }
            }
        }
        for (size_t x = 0; x < n_touched; x++) {   /* untouched nodes: force 0 */
            const size_t node = (size_t)touched[x];
            if (added_in[node] == sub) continue;
            added_in[node] = sub;
            for (int d = 0; d < 3; d++) impulse[3 * node + d] += jac->h * force[3 * node + d];
        }
        /* the particles' response to the change of the net force (symplectic Euler of
         * dem_integrate.c, velocity first; free spheres and whole clusters) */
        for (size_t x = 0; x < npt; x++) {
            particle *pt = &pts[x];
            if (!pt->respond) continue;
            motion *m = &pt->m;
            double im = s->model.bod.inv_mass[pt->body], ii = s->model.bod.inv_inertia_iso[pt->body];
            double h = jac->h;
            int nc = 3 * pt->n_nodes;
            if (pt->cluster) { /* L += h T, ω = I⁻¹ L, the turn by h ω (world-frame I⁻¹) */
                const double *I = pt->inv_inertia;
                for (int k = 0; k < 3; k++)
                    m->dw[k] += h * (I[3 * k] * pt->st[0] + I[3 * k + 1] * pt->st[1] +
                                     I[3 * k + 2] * pt->st[2]);
                for (int c = 0; c < nc && want_K; c++)
                    for (int k = 0; k < 3; k++) {
                        m->Dw[k][c] += h * (I[3 * k] * pt->Dst[0][c] + I[3 * k + 1] * pt->Dst[1][c] +
                                            I[3 * k + 2] * pt->Dst[2][c]);
                        pt->Dth[k][c] += h * m->Dw[k][c];
                    }
                for (int k = 0; k < 3; k++) {
                    pt->dth[k] += h * m->dw[k];
                    pt->st[k] = 0.0;
                    for (int c = 0; c < nc && want_K; c++) pt->Dst[k][c] = 0.0;
                }
            }
            for (int k = 0; k < 3; k++) {
                m->dv[k] += h * pt->sf[k] * im;
                m->dx[k] += h * m->dv[k];
                if (!pt->cluster) m->dw[k] += h * pt->st[k] * ii;
                pt->sf[k] = pt->st[k] = 0.0;
                for (int c = 0; c < nc && want_K; c++) {
                    m->Dv[k][c] += h * pt->Dsf[k][c] * im;
                    m->Dx[k][c] += h * m->Dv[k][c];
                    if (!pt->cluster) m->Dw[k][c] += h * pt->Dst[k][c] * ii;
                    pt->Dsf[k][c] = pt->Dst[k][c] = 0.0;
                }
            }
        }
    }
    if (force_out) {
        if (jac->force_at_end)
            memcpy(force_out, force, 3 * nn * sizeof *force_out);
        else
            for (size_t k = 0; k < 3 * nn; k++) force_out[k] = impulse[k] / jac->dt_step;
    }
    if (want_K) {
        block *blocks = sum.blocks;
        const size_t m = sum.n;
        if (m > 1) qsort(blocks, m, sizeof *blocks, block_cmp);   /* by (i, j): each pair once */
        size_t cap = jac->cap_blocks;
        if (grow((void **)&jac->nodes, &cap, m, 2 * sizeof *jac->nodes, err)) {
            rc = -1;
            goto done;
        }
        double *K = realloc(jac->K, (cap ? cap : 1) * 9 * sizeof *K);
        if (!K) {
            rc = nc_error_set(err, 1, "dem: out of memory for the interface Jacobian");
            goto done;
        }
        jac->K = K;
        jac->cap_blocks = cap;
        for (size_t b = 0; b < m; b++) {
            jac->nodes[2 * b] = blocks[b].i;
            jac->nodes[2 * b + 1] = blocks[b].j;
            memcpy(jac->K + 9 * b, blocks[b].k, sizeof blocks[b].k);
        }
        jac->n_blocks = m;
    }
done:
    free(end); free(force); free(impulse); free(touched); free(added_in);
    free(slot); free(sum.blocks); free(sum.slot); free(state); free(pts); free(scratch);
    return rc;
}
