/* fem_element_ring — type "ring": the connection between two neighbouring contact points of
 * a ring net, two nodes, with the two-phase force–elongation law of a steel-wire ring pulled
 * across (delta = l - L0, the elongation of the node distance):
 *   bending phase   F = k_b delta                              0 <= delta <= delta_m
 *   membrane phase  F = k_b delta_m + k_m (delta - delta_m)    delta > delta_m
 * with a low bending stiffness k_b while the ring bends out of its circle into an elongated
 * shape, and the high membrane stiffness k_m of the wire bundle once it is stretched straight
 * (delta_m, the elongation at which the ring is fully elongated). No compression (a ring
 * pushed together carries nothing) and no history: it unloads along the same curve (the
 * rings' plastic deformation is not modelled). This is the ring model of Kratos
 * CableNetApplication's ring elements (a bending spring until the ring is taut, then the
 * tensile stiffness of its circumference) reduced to one pair of contact points. */
#include "fem_element_ring.h"
#include "fem_element.h"
#include "fem_element_cable.h"
#include "fem_model.h"
#include "nc_json.h"

#include <math.h>

double fem_ring_force(const double *p, double delta, double *kt)
{
    if (delta < 0.0) {
        *kt = 0.0;
        return 0.0;
    }
    if (delta <= p[FEM_RING_DM]) {
        *kt = p[FEM_RING_KB];
        return p[FEM_RING_KB] * delta;
    }
    *kt = p[FEM_RING_KM];
    return p[FEM_RING_KB] * p[FEM_RING_DM] + p[FEM_RING_KM] * (delta - p[FEM_RING_DM]);
}

static double ring_pair(const fem_element_ctx *c, double f_l[3], double Kb[9], int *slack)
{
    double d[3], kt;
    fem_cable_chord(c, d);
    double l = sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
    double F = fem_ring_force(c->param, l - c->m->L0[c->first], &kt);
    double g = F / l, mat = (kt - g) / (l * l);
    for (int i = 0; i < 3; i++) {
        f_l[i] = g * d[i];
        for (int j = 0; j < 3; j++) Kb[3 * i + j] = mat * d[i] * d[j];
        Kb[4 * i] += g;
    }
    if (slack) *slack = kt == 0.0;
    return F;
}

static double ring_energy(const fem_element_ctx *c)
{
    const double *p = c->param;
    double d[3];
    fem_cable_chord(c, d);
    double delta = sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]) - c->m->L0[c->first];
    if (delta <= 0.0) return 0.0;
    if (delta <= p[FEM_RING_DM]) return 0.5 * p[FEM_RING_KB] * delta * delta;
    double e = delta - p[FEM_RING_DM];
    return 0.5 * p[FEM_RING_KB] * p[FEM_RING_DM] * p[FEM_RING_DM] + p[FEM_RING_KB] * p[FEM_RING_DM] * e + 0.5 * p[FEM_RING_KM] * e * e;
}

static const char *const ring_keys[] = {"bending_stiffness_n_per_m", "membrane_stiffness_n_per_m",
                                        "membrane_elongation_m", NULL};

static int ring_parse(const struct cJSON *o, const char *w, FILE *warnings, double *p, nc_error *err)
{
    (void)warnings;
    if (nc_json_positive(o, w, "bending_stiffness_n_per_m", &p[FEM_RING_KB], err) ||
        nc_json_positive(o, w, "membrane_stiffness_n_per_m", &p[FEM_RING_KM], err) ||
        nc_json_positive(o, w, "membrane_elongation_m", &p[FEM_RING_DM], err))
        return -1;
    if (p[FEM_RING_KM] < p[FEM_RING_KB])
        return nc_error_set(err, 1, "%s.membrane_stiffness_n_per_m: %g N/m is below the bending stiffness %g N/m "
                                    "(a stretched ring is stiffer than a bending one)", w, p[FEM_RING_KM], p[FEM_RING_KB]);
    return 0;
}

const fem_element_ops fem_element_ring_ops = {
    .name = "ring",
    .keys = ring_keys,
    .parse = ring_parse,
    .pair_response = ring_pair,
    .strain_energy = ring_energy,
};
