/* fem_element_cable — internal force, tangent and mass of the cable/truss element
 * (eqs. (8)–(11); see fem_element_cable.h for the block layout) and its table of
 * operations, type "cable" (fem_element.h): behaviour "cable" goes slack in compression,
 * "truss" keeps it. The post type (fem_element_post.c) reuses this response. */
#include "fem_element_cable.h"
#include "fem_element.h"
#include "fem_model.h"

#include <math.h>

double fem_cable_response(const double d[3], double L0, double EA, double AS_pre, int is_cable,
                          double f_l[3], double Kb[9], int *slack)
{
    double l2 = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
    double L2 = L0 * L0;
    double green = (l2 - L2) / (2.0 * L2);            /* Green-Lagrange strain */
    double AS_tot = EA * green + AS_pre;               /* A (E_mod E + S_pre), eq. (10) */
    if (is_cable && AS_tot < 0.0) {
        /* slack cable: carries nothing, contributes nothing */
        f_l[0] = f_l[1] = f_l[2] = 0.0;
        for (int i = 0; i < 9; i++) Kb[i] = 0.0;
        if (slack) *slack = 1;
        return 0.0;
    }
    if (slack) *slack = 0;
    double s = AS_tot / L0;                            /* eq. (8) */
    double mat = EA / (L2 * L0);                       /* eq. (9), material part */
    for (int i = 0; i < 3; i++) {
        f_l[i] = s * d[i];
        for (int j = 0; j < 3; j++) Kb[3 * i + j] = mat * d[i] * d[j];
        Kb[4 * i] += s;                                /* geometric part */
    }
    return AS_tot * sqrt(l2) / L0;
}

void fem_cable_mass(double rhoA, double L0, int lumped, double *m11, double *m12)
{
    fem_element_bar_mass(rhoA, L0, lumped, m11, m12);
}

void fem_cable_chord(const fem_element_ctx *c, double d[3])
{
    const fem_model *m = c->m;
    const int k = 3 * m->conn[2 * c->first], l = 3 * m->conn[2 * c->first + 1];
    /* the same operation order as everywhere (X + u per end), so results do not depend on
     * which caller evaluates an element */
    for (int i = 0; i < 3; i++) d[i] = m->X[l + i] + c->u[l + i] - m->X[k + i] - c->u[k + i];
}

double fem_cable_energy(const fem_model *m, int e, double l2)
{
    double L2 = m->L0[e] * m->L0[e];
    double AS_tot = m->EA[e] * (l2 - L2) / (2.0 * L2) + m->AS[e];
    if (m->is_cable[e] && AS_tot < 0) AS_tot = 0;
    /* W = A L int S dE = L ((A S_tot)^2 - (A S_pre)^2) / (2 E A) */
    return m->EA[e] > 0 ? m->L0[e] * (AS_tot * AS_tot - m->AS[e] * m->AS[e]) / (2.0 * m->EA[e]) : 0.0;
}

static double cable_pair(const fem_element_ctx *c, double f_l[3], double Kb[9], int *slack)
{
    const fem_model *m = c->m;
    const int e = c->first;
    double d[3];
    fem_cable_chord(c, d);
    return fem_cable_response(d, m->L0[e], m->EA[e], m->AS[e], m->is_cable[e], f_l, Kb, slack);
}

double fem_cable_member_energy(const fem_element_ctx *c)
{
    double d[3];
    fem_cable_chord(c, d);
    return fem_cable_energy(c->m, c->first, d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
}

const fem_element_ops fem_element_cable_ops = {
    .name = "cable",
    .uses_section = 1,
    .pair_response = cable_pair,
    .strain_energy = fem_cable_member_energy,
};
