/* dem_law_hertz — the inline normal part of the Hertz–Mindlin law for dem_contact_force()
 * (the hot path; its table is in dem_law_hertz.c). Included by dem_contact_hertz.h after
 * dem_pair. */
#ifndef DEM_LAW_HERTZ_H
#define DEM_LAW_HERTZ_H

#include <math.h>

/* Normal force at overlap δ and rate δ̇ (before the no-tension clamp); writes kt and
 * cn_root = sqrt(m* kn') with the tangent stiffness kn' = 2 E* sqrt(R* δ). */
static inline __attribute__((always_inline)) double dem_hertz_normal_force(const dem_pair *pair,
                                                                          double overlap,
                                                                          double overlap_rate,
                                                                          double *kt,
                                                                          double *cn_root)
{
    double root = sqrt(pair->r_star * overlap);
    double kn_tangent = 2.0 * pair->e_star * root;             /* dFn/dδ */
    double fn_elastic = (2.0 / 3.0) * kn_tangent * overlap;    /* 4/3 E* sqrt(R*) δ^1.5 */
    *cn_root = sqrt(pair->m_star * kn_tangent);
    *kt = 8.0 * pair->g_star * root;
    return fn_elastic + 2.0 * pair->zeta * *cn_root * overlap_rate;
}

/* The same spring with the Hunt–Crossley dashpot (damping "hunt_crossley", dem_damping.h):
 * fn = 4/3 E* sqrt(R*) δ^1.5 (1 + ξ δ̇), ξ = hunt_crossley / v0. cn_root as above (the
 * tangential dashpot keeps eq. (A.5)'s form). */
static inline __attribute__((always_inline)) double dem_hertz_hunt_crossley_force(
    const dem_pair *pair, double overlap, double overlap_rate, double impact_speed, double *kt,
    double *cn_root)
{
    double root = sqrt(pair->r_star * overlap);
    double kn_tangent = 2.0 * pair->e_star * root;
    double fn_elastic = (2.0 / 3.0) * kn_tangent * overlap;
    *cn_root = sqrt(pair->m_star * kn_tangent);
    *kt = 8.0 * pair->g_star * root;
    return fn_elastic * (1.0 + pair->hunt_crossley / impact_speed * overlap_rate);
}

#endif
