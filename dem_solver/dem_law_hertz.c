/* dem_law_hertz — the Hertz–Mindlin contact law's table (Appendix A, eq. (A.5)):
 * fn = 4/3 E* sqrt(R*) δ^1.5 + 2 ζ sqrt(m* kn') δ̇ with the tangent stiffness
 * kn' = 2 E* sqrt(R* δ), kt = 8 G* sqrt(R* δ); the Rayleigh-wave critical step and the Hertz
 * contact time limit an automatic dt. Its per-contact force is the Hertz branch of
 * dem_contact_force() (dem_contact_law.h says why it is not called through this table). */
#include "dem_contact_law.h"

#include <math.h>

#include "dem_sim.h"

static int check(const dem_params *prm, const char *source, nc_error *err)
{
    (void)prm;
    (void)source;
    (void)err;
    return 0;
}

static double kt_kn_root(const dem_params *prm, double e_star, double g_star)
{
    (void)prm;
    return sqrt(4.0 * g_star / e_star);
}

static void normal(const dem_params *prm, const dem_pair *pair, double overlap, dem_law_normal *out)
{
    (void)prm;
    double root = sqrt(pair->r_star * overlap);
    out->kn_tangent = 2.0 * pair->e_star * root;
    out->fn_elastic = (2.0 / 3.0) * out->kn_tangent * overlap;
    out->cn_root = sqrt(pair->m_star * out->kn_tangent);
    double dkn = root > 0.0 ? pair->e_star * pair->r_star / root : 0.0; /* d kn' / dδ */
    out->dcn_root = out->cn_root > 0.0 ? 0.5 * pair->m_star * dkn / out->cn_root : 0.0;
    out->kt = 8.0 * pair->g_star * root;
    out->dkt = root > 0.0 ? 4.0 * pair->g_star * pair->r_star / root : 0.0;
}

/* Rayleigh wave time step: π R sqrt(ρ/G) / (0.1631 ν + 0.8766) */
static double critical_dt(const dem_sim *s)
{
    double crit = INFINITY;
    for (size_t i = 0; i < s->model.sph.n; i++) {
        const dem_material *m = &s->model.materials[s->model.sph.material[i]];
        double t = M_PI * s->model.sph.radius[i] * sqrt(m->density_kg_m3 / m->shear_modulus_pa) /
                   (0.1631 * m->poisson_ratio + 0.8766);
        if (t < crit) crit = t;
    }
    return crit;
}

/* Hertz contact duration t_c = 2.87 (m*² / (R* E*² v))^(1/5) for the lightest, smallest
 * sphere against the stiffest partner at the impact speed v. */
static double contact_time(const dem_sim *s, double v)
{
    double tc = INFINITY;
    for (size_t i = 0; i < s->model.sph.n; i++) {
        const dem_material *m = &s->model.materials[s->model.sph.material[i]];
        double e_max = dem_effective_modulus(m->youngs_modulus_pa, m->poisson_ratio,
                                             m->youngs_modulus_pa, m->poisson_ratio);
        for (size_t k = 0; k < s->model.n_materials; k++) {
            const dem_material *w = &s->model.materials[k];
            double e = dem_effective_modulus(m->youngs_modulus_pa, m->poisson_ratio,
                                             w->youngs_modulus_pa, w->poisson_ratio);
            if (e > e_max) e_max = e;
        }
        if (s->model.net.youngs_modulus_pa > 0.0) {
            double e = dem_effective_modulus(m->youngs_modulus_pa, m->poisson_ratio,
                                             s->model.net.youngs_modulus_pa, s->model.net.poisson_ratio);
            if (e > e_max) e_max = e;
        }
        double mstar = 0.5 * s->model.bod.mass[s->model.sph.body[i]], r = 0.5 * s->model.sph.radius[i];
        double t = 2.87 * pow(mstar * mstar / (r * e_max * e_max * v), 0.2);
        if (t < tc) tc = t;
    }
    return tc;
}

/* ∫ 4/3 E* sqrt(R*) δ^1.5 dδ */
static double elastic_energy(const dem_params *prm, const dem_pair *pair, double overlap)
{
    (void)prm;
    return 8.0 / 15.0 * pair->e_star * sqrt(pair->r_star) * pow(overlap, 2.5);
}

const dem_contact_law dem_law_hertz = {"hertz_mindlin", DEM_DAMPING_FIT, NULL, NULL, 1, check, kt_kn_root, normal,
                                       critical_dt, contact_time, elastic_energy};
