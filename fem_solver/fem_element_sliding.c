/* fem_element_sliding — type "sliding_cable": one rope through a chain of nodes (its ends
 * anchored or attached, the nodes between them shackles or post tops it slides through,
 * frictionless). The rope has one axial force along its whole length,
 *   N = EA (L - L0) / L0 + N_pre,   L = sum_i |x_i+1 - x_i|,  L0 = its reference length,
 * N_pre = A S_pre (the set's prestress or pretension), and no compression (N < 0: slack).
 * The internal force on chain node j is N dL/dx_j = N (e_j-1 - e_j), e_i the unit vector of
 * segment i (x_i -> x_i+1): the rope pulls every node along the sum of the unit vectors to
 * its neighbours. The consistent tangent is
 *   K_jk = (EA / L0) g_j g_k^T + N dg_j/dx_k,   g_j = e_j-1 - e_j,
 * dg_j/dx_j = P_j-1 + P_j, dg_j/dx_j-1 = -P_j-1, dg_j/dx_j+1 = -P_j, P_i = (I - e_i e_i^T)/l_i:
 * a dense material part (the force depends on the whole length) and a tridiagonal geometric
 * part. The material part is of rank one: chain_rank_one returns it (k = EA / L0 and g), and
 * the solver keeps it out of its factorised matrix (fem_element.h); with near_blocks_only the
 * response forms only the neighbours' blocks, without it. Strain energy
 * (N_+ = max(N, 0)): L0 (N_+(L)^2 - N_+(L0)^2) / (2 EA). The same law as the sliding cable
 * element of Kratos' CableNetApplication (one strain over the whole rope).
 *
 * Shackle contact (shackle_gap_m = g > 0): consecutive nodes of the chain cannot come closer
 * than g (the shackles' size; a net node cannot slide past its neighbour or into an anchor).
 * A segment shorter than g pushes its two nodes apart with the compression-only penalty
 *   N_c = -k_c (g - l)  (l < g),  k_c = shackle_stiffness_n_per_m, default EA / g,
 * a bar force along the segment: f_s+1 = N_c e_s = -f_s, tangent k_c e e^T + (N_c / l)(I - e e^T)
 * on the segment's blocks, energy k_c (g - l)^2 / 2. It acts whether the rope is taut or slack.
 * Without it a segment can shrink to zero length, where e_s flips and N / l grows without
 * bound, and Newton fails (docs/notes/shackle_contact.md). */
#include "fem_element.h"
#include "fem_model.h"
#include "nc_json.h"

#include <math.h>
#include <string.h>

/* set->param layout: the gap g (m, 0: no contact) and the stiffness k_c (N/m, 0: EA / g) */
enum { SLIDING_GAP, SLIDING_CONTACT_K };

static double contact_stiffness(const fem_element_ctx *c)
{
    const double k = c->param[SLIDING_CONTACT_K];
    return k > 0.0 ? k : c->m->EA[c->first] / c->param[SLIDING_GAP];
}

/* segment s's chord d (node s -> s+1) and length */
static double segment(const fem_element_ctx *c, int s, double d[3])
{
    const fem_model *m = c->m;
    const int e = c->first + s, k = 3 * m->conn[2 * e], l = 3 * m->conn[2 * e + 1];
    for (int i = 0; i < 3; i++) d[i] = m->X[l + i] + c->u[l + i] - m->X[k + i] - c->u[k + i];
    return sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
}

/* adds the shackle contact's force and tangent (see the top of this file) */
static void add_contact(const fem_element_ctx *c, double *f, double *K)
{
    const double gap = c->param[SLIDING_GAP];
    if (!(gap > 0.0)) return;
    const double kc = contact_stiffness(c);
    const int dim = 3 * (c->count + 1);
    for (int s = 0; s < c->count; s++) {
        double d[3], len = segment(c, s, d);
        if (len >= gap || !(len > 0.0)) continue;
        const double Nc = -kc * (gap - len);
        for (int i = 0; i < 3; i++) {
            f[3 * s + i] -= Nc * d[i] / len;
            f[3 * (s + 1) + i] += Nc * d[i] / len;
        }
        if (!K) continue;
        for (int i = 0; i < 3; i++)
            for (int j = 0; j < 3; j++) {
                double ee = d[i] * d[j] / (len * len);
                double B = kc * ee + Nc / len * ((i == j) - ee);
                K[(3 * s + i) * dim + 3 * s + j] += B;
                K[(3 * (s + 1) + i) * dim + 3 * (s + 1) + j] += B;
                K[(3 * s + i) * dim + 3 * (s + 1) + j] -= B;
                K[(3 * (s + 1) + i) * dim + 3 * s + j] -= B;
            }
    }
}

/* rope length L, reference L0 and force N (not clipped) of the member */
static double rope_force(const fem_element_ctx *c, double *L, double *L0)
{
    const fem_model *m = c->m;
    double len = 0.0, ref = 0.0, d[3];
    for (int s = 0; s < c->count; s++) {
        len += segment(c, s, d);
        ref += m->L0[c->first + s];
    }
    *L = len;
    *L0 = ref;
    const int e0 = c->first;
    return m->EA[e0] * (len - ref) / ref + m->AS[e0];
}

/* g_j = e_j-1 - e_j of every chain node into g[3n] */
static void rope_direction(const fem_element_ctx *c, double *g)
{
    memset(g, 0, 3 * (size_t)(c->count + 1) * sizeof *g);
    for (int s = 0; s < c->count; s++) {
        double d[3], len = segment(c, s, d);
        for (int i = 0; i < 3; i++) {
            g[3 * s + i] -= d[i] / len;         /* node s: -e_s */
            g[3 * (s + 1) + i] += d[i] / len;   /* node s+1: +e_s */
        }
    }
}

/* the rope's force N g_j and tangent (see the top of this file) into zeroed f and K */
static void rope_response(const fem_element_ctx *c, double N, double L0, double *f, double *K)
{
    const int ns = c->count, dim = 3 * (ns + 1);
    const double k_ax = c->m->EA[c->first] / L0;
    rope_direction(c, f);   /* g, scaled by N at the end */
    /* geometric part N P_s on the blocks (s, s), (s+1, s+1), -N P_s on (s, s+1) */
    for (int s = 0; s < ns && K; s++) {
        double d[3], len = segment(c, s, d), l2 = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
        for (int i = 0; i < 3; i++)
            for (int j = 0; j < 3; j++) {
                double P = ((i == j) - d[i] * d[j] / l2) * N / len;
                K[(3 * s + i) * dim + 3 * s + j] += P;
                K[(3 * (s + 1) + i) * dim + 3 * (s + 1) + j] += P;
                K[(3 * s + i) * dim + 3 * (s + 1) + j] -= P;
                K[(3 * (s + 1) + i) * dim + 3 * s + j] -= P;
            }
    }
    if (K && !c->near_blocks_only)
        for (int a = 0; a < dim; a++)
            for (int b = 0; b < dim; b++) K[a * dim + b] += k_ax * f[a] * f[b];
    for (int a = 0; a < dim; a++) f[a] *= N;
}

static int sliding_response(const fem_element_ctx *c, double *f, double *K, double *axial)
{
    const int dim = 3 * (c->count + 1);
    double L, L0;
    double N = rope_force(c, &L, &L0);
    int slack = N < 0.0;
    if (slack) N = 0.0;
    for (int s = 0; s < c->count; s++) axial[s] = N;
    memset(f, 0, (size_t)dim * sizeof *f);
    if (K && c->near_blocks_only)   /* the blocks (j, j-1 .. j+1) of every node j */
        for (int row = 0; row < dim; row++) {
            const int j = row / 3, lo = 3 * (j > 0 ? j - 1 : 0);
            const int hi = 3 * (j < c->count ? j + 2 : j + 1);
            memset(K + (size_t)row * dim + lo, 0, (size_t)(hi - lo) * sizeof *K);
        }
    else if (K)
        memset(K, 0, (size_t)dim * (size_t)dim * sizeof *K);
    if (!slack) rope_response(c, N, L0, f, K);
    add_contact(c, f, K);
    return slack;
}

/* the material part (EA / L0) g g^T of the tangent, the only one coupling nodes that are
 * not neighbours */
static double sliding_rank_one(const fem_element_ctx *c, double *g)
{
    double L, L0;
    if (rope_force(c, &L, &L0) < 0.0) return 0.0;   /* slack */
    rope_direction(c, g);
    return c->m->EA[c->first] / L0;
}

static double sliding_energy(const fem_element_ctx *c)
{
    const fem_model *m = c->m;
    double L, L0;
    double N = fmax(rope_force(c, &L, &L0), 0.0), Np = fmax(m->AS[c->first], 0.0);
    double EA = m->EA[c->first];
    double energy = EA > 0.0 ? L0 * (N * N - Np * Np) / (2.0 * EA) : 0.0;
    const double gap = c->param[SLIDING_GAP];
    if (gap > 0.0) {
        const double kc = contact_stiffness(c);
        for (int s = 0; s < c->count; s++) {
            double d[3], len = segment(c, s, d);
            if (len < gap) energy += 0.5 * kc * (gap - len) * (gap - len);
        }
    }
    return energy;
}

static const char *const sliding_keys[] = {"shackle_gap_m", "shackle_stiffness_n_per_m", NULL};

static int sliding_parse(const struct cJSON *o, const char *w, FILE *warnings, double *p,
                         nc_error *err)
{
    (void)warnings;
    const int stiffness_given = cJSON_GetObjectItemCaseSensitive(o, "shackle_stiffness_n_per_m") != NULL;
    if (nc_json_number_range_opt(o, w, "shackle_gap_m", 0.0, 0.0, INFINITY, &p[SLIDING_GAP], err) ||
        (stiffness_given &&
         nc_json_positive(o, w, "shackle_stiffness_n_per_m", &p[SLIDING_CONTACT_K], err)))
        return -1;
    if (stiffness_given && !(p[SLIDING_GAP] > 0.0))
        return nc_error_set(err, 1, "%s.shackle_stiffness_n_per_m: given without shackle_gap_m "
                                    "(the contact acts below the gap; give both)", w);
    return 0;
}

/* A segment shorter than the gap at rest would push its nodes apart from the start; the
 * contact's stiffness must be a usable number (EA / g overflows for a tiny gap). */
static int sliding_check(const fem_element_ctx *c, nc_error *err)
{
    const fem_model *m = c->m;
    const double gap = c->param[SLIDING_GAP];
    const double kc = gap > 0.0 ? contact_stiffness(c) : 1.0;
    if (!(isfinite(kc) && kc > 0.0))
        return nc_error_set(err, 1, "%s: sliding_cable set \"%s\": the shackle contact's stiffness "
                                    "(%g N/m) is not a positive finite number (give "
                                    "shackle_stiffness_n_per_m, or a larger shackle_gap_m)",
                            m->source, c->set->name, kc);
    for (int s = 0; s < c->count; s++) {
        const int e = c->first + s;
        if (m->L0[e] < gap)
            return nc_error_set(err, 1, "%s: elements[%d] (nodes %d-%d of sliding_cable set \"%s\") "
                                        "is %g m long at rest, shorter than the set's shackle_gap_m %g m",
                                m->source, e, m->conn[2 * e], m->conn[2 * e + 1], c->set->name,
                                m->L0[e], gap);
    }
    return 0;
}

const fem_element_ops fem_element_sliding_cable_ops = {
    .name = "sliding_cable",
    .chain = 1,
    .uses_section = 1,
    .keys = sliding_keys,
    .parse = sliding_parse,
    .check = sliding_check,
    .chain_response = sliding_response,
    .chain_rank_one = sliding_rank_one,
    .strain_energy = sliding_energy,
};
