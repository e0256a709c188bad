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
 * part. Strain energy (N_+ = max(N, 0)): L0 (N_+(L)^2 - N_+(L0)^2) / (2 EA). The same law as
 * the sliding cable element of Kratos' CableNetApplication (one strain over the whole rope). */
#include "fem_element.h"
#include "fem_model.h"

#include <math.h>
#include <string.h>

/* rope length L, reference L0 and force N (not clipped) of the member */
static double rope_force(const fem_element_ctx *c, double *L, double *L0)
{
    const fem_model *m = c->m;
    double len = 0.0, ref = 0.0;
    for (int s = 0; s < c->count; s++) {
        const int e = c->first + s, k = 3 * m->conn[2 * e], l = 3 * m->conn[2 * e + 1];
        double l2 = 0.0;
        for (int i = 0; i < 3; i++) {
            double d = m->X[l + i] + c->u[l + i] - m->X[k + i] - c->u[k + i];
            l2 += d * d;
        }
        len += sqrt(l2);
        ref += m->L0[e];
    }
    *L = len;
    *L0 = ref;
    const int e0 = c->first;
    return m->EA[e0] * (len - ref) / ref + m->AS[e0];
}

static int sliding_response(const fem_element_ctx *c, double *f, double *K, double *axial)
{
    const fem_model *m = c->m;
    const int ns = c->count, n = ns + 1, dim = 3 * n;
    double L, L0;
    double N = rope_force(c, &L, &L0);
    int slack = N < 0.0;
    if (slack) N = 0.0;
    for (int s = 0; s < ns; s++) axial[s] = N;
    memset(f, 0, (size_t)dim * sizeof *f);
    if (K) memset(K, 0, (size_t)dim * (size_t)dim * sizeof *K);
    if (slack) return 1;
    const double k_ax = m->EA[c->first] / L0;
    /* g_j = e_j-1 - e_j accumulated in f (scaled by N at the end) */
    for (int s = 0; s < ns; s++) {
        const int e = c->first + s, k = 3 * m->conn[2 * e], l = 3 * m->conn[2 * e + 1];
        double d[3], l2 = 0.0;
        for (int i = 0; i < 3; i++) {
            d[i] = m->X[l + i] + c->u[l + i] - m->X[k + i] - c->u[k + i];
            l2 += d[i] * d[i];
        }
        double len = sqrt(l2);
        for (int i = 0; i < 3; i++) {
            double ei = d[i] / len;
            f[3 * s + i] -= ei;           /* node s: -e_s */
            f[3 * (s + 1) + i] += ei;     /* node s+1: +e_s */
        }
        if (K) {
            /* geometric part N P_s on the blocks (s, s), (s+1, s+1), -N P_s on (s, s+1) */
            for (int i = 0; i < 3; i++)
                for (int j = 0; j < 3; j++) {
                    double P = ((i == j) - d[i] * d[j] / l2) * N / len;
                    K[(3 * s + i) * dim + 3 * s + j] += P;
                    K[(3 * (s + 1) + i) * dim + 3 * (s + 1) + j] += P;
                    K[(3 * s + i) * dim + 3 * (s + 1) + j] -= P;
                    K[(3 * (s + 1) + i) * dim + 3 * s + j] -= P;
                }
        }
    }
    if (K)
        for (int a = 0; a < dim; a++)
            for (int b = 0; b < dim; b++) K[a * dim + b] += k_ax * f[a] * f[b];
    for (int a = 0; a < dim; a++) f[a] *= N;
    return 0;
}

static double sliding_energy(const fem_element_ctx *c)
{
    const fem_model *m = c->m;
    double L, L0;
    double N = fmax(rope_force(c, &L, &L0), 0.0), Np = fmax(m->AS[c->first], 0.0);
    double EA = m->EA[c->first];
    return EA > 0.0 ? L0 * (N * N - Np * Np) / (2.0 * EA) : 0.0;
}

const fem_element_ops fem_element_sliding_cable_ops = {
    .name = "sliding_cable",
    .chain = 1,
    .uses_section = 1,
    .chain_response = sliding_response,
    .strain_energy = sliding_energy,
};
