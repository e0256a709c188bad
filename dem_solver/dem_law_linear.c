/* dem_law_linear — the linear spring–dashpot law's table: fn = kn δ + 2 ζ sqrt(m* kn) δ̇
 * (the law for which eq. (A.7) is exact), kt = ratio kn (dem.json "linear"); the critical
 * step of the spring between the two lightest bodies limits an automatic dt. Its per-contact
 * force is the linear branch of dem_contact_force() (dem_contact_law.h says why). */
#include "dem_contact_law.h"

#include <math.h>

#include "dem_sim.h"

static int check(const dem_params *prm, const char *source, nc_error *err)
{
    if (!(prm->linear_kn_n_per_m > 0.0))
        return nc_error_set(err, 1, "%s: the linear contact law needs "
                                    "linear.normal_stiffness_n_per_m > 0", source);
    return 0;
}

static double kt_kn_root(const dem_params *prm, double e_star, double g_star)
{
    (void)e_star;
    (void)g_star;
    return sqrt(prm->linear_kt_ratio);
}

static void normal(const dem_params *prm, const dem_pair *pair, double overlap, dem_law_normal *out)
{
    double kn = prm->linear_kn_n_per_m;
    out->kn_tangent = kn;
    out->fn_elastic = kn * overlap;
    out->cn_root = sqrt(pair->m_star * kn);
    out->dcn_root = 0.0;
    out->kt = prm->linear_kt_ratio * kn;
    out->dkt = 0.0;
}

/* stability of the spring between the two lightest bodies: 2 sqrt(m_star / k) */
static double critical_dt(const dem_sim *s)
{
    double crit = INFINITY;
    for (size_t b = 0; b < s->model.bod.n; b++) {
        double t = 2.0 * sqrt(0.5 * s->model.bod.mass[b] / s->model.prm.linear_kn_n_per_m);
        if (t < crit) crit = t;
    }
    return crit;
}

static double contact_time(const dem_sim *s, double v)
{
    (void)s;
    (void)v;
    return INFINITY;
}

static double elastic_energy(const dem_params *prm, const dem_pair *pair, double overlap)
{
    (void)pair;
    return 0.5 * prm->linear_kn_n_per_m * overlap * overlap;
}

const dem_contact_law dem_law_linear = {"linear", DEM_DAMPING_A7, "linear",
                                        "{\"normal_stiffness_n_per_m\": k}", 0, check, kt_kn_root, normal, critical_dt,
                                        contact_time, elastic_energy};
