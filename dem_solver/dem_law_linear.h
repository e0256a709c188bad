/* dem_law_linear — the inline normal part of the linear spring–dashpot law for
 * dem_contact_force() (the hot path; its table is in dem_law_linear.c). Included by
 * dem_contact_hertz.h after dem_pair. */
#ifndef DEM_LAW_LINEAR_H
#define DEM_LAW_LINEAR_H

#include <math.h>

#include "dem_model.h"

/* Normal force kn δ + 2 ζ sqrt(m* kn) δ̇ (before the no-tension clamp); writes kt = ratio kn
 * and cn_root = sqrt(m* kn). */
static inline __attribute__((always_inline)) double dem_linear_normal_force(const dem_params *prm,
                                                                           const dem_pair *pair,
                                                                           double overlap,
                                                                           double overlap_rate,
                                                                           double *kt,
                                                                           double *cn_root)
{
    double kn = prm->linear_kn_n_per_m;
    *cn_root = sqrt(pair->m_star * kn);
    *kt = prm->linear_kt_ratio * kn;
    return kn * overlap + 2.0 * pair->zeta * *cn_root * overlap_rate;
}

#endif
