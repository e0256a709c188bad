/* dem_energy — energies for balances and tests: kinetic (translation and rotation), gravity
 * potential and the elastic energy stored in the contact springs of the current list, and
 * the balance of a coupling step (dem_energy.h). Read only; no effect on the motion. */
#include "dem_energy.h"

#include <math.h>

double dem_sim_kinetic_energy(const dem_sim *s)
{
    double e = 0.0;
    for (size_t b = 0; b < s->model.bod.n; b++) {
        const double *v = s->model.bod.vel + 3 * b, *w = s->model.bod.omega + 3 * b;
        e += 0.5 * s->model.bod.mass[b] * (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
        if (s->model.bod.is_cluster[b]) {
            const double *L = s->model.bod.angmom + 3 * b;
            e += 0.5 * (w[0] * L[0] + w[1] * L[1] + w[2] * L[2]);
        } else {
            e += 0.5 * s->model.bod.inertia_body[9 * b] * (w[0] * w[0] + w[1] * w[1] + w[2] * w[2]);
        }
    }
    return e;
}

double dem_sim_potential_energy(const dem_sim *s)
{
    double e = 0.0;
    const double *g = s->model.prm.gravity;
    for (size_t b = 0; b < s->model.bod.n; b++) {
        const double *x = s->model.bod.pos + 3 * b;
        e -= s->model.bod.mass[b] * (g[0] * x[0] + g[1] * x[1] + g[2] * x[2]);
    }
    return e;
}

double dem_sim_contact_energy(const dem_sim *s)
{
    const dem_contacts *c = &s->contact.list;
    double e = 0.0;
    for (size_t k = 0; k < c->n; k++) {
        size_t i = (size_t)c->i[k];
        dem_pair p;
        switch (c->kind[k]) {
        case DEM_CONTACT_SPHERE: {
            size_t j = (size_t)c->j[k];
            const dem_material *mi = &s->model.materials[s->model.sph.material[i]];
            const dem_material *mj = &s->model.materials[s->model.sph.material[j]];
            p.e_star = dem_effective_modulus(mi->youngs_modulus_pa, mi->poisson_ratio,
                                             mj->youngs_modulus_pa, mj->poisson_ratio);
            p.r_star = s->model.sph.radius[i] * s->model.sph.radius[j] / (s->model.sph.radius[i] + s->model.sph.radius[j]);
            p.mu = 0.5 * (mi->friction + mj->friction);   /* as dem_detect_sphere.c */
            break;
        }
        case DEM_CONTACT_PLANE:
            dem_material_wall_pair(&s->contact, &s->model, i, s->model.planes[c->j[k]].material, &p);
            break;
        case DEM_CONTACT_MESH:
            dem_material_wall_pair(&s->contact, &s->model, i, s->model.meshes[c->aux[k]].material, &p);
            break;
        default:
            dem_net_wall_pair(&s->model, i, &p);
            break;
        }
        double d = c->overlap[k];
        e += dem_contact_law_of(s->model.prm.law)->elastic_energy(&s->model.prm, &p, d);
        /* the tangential spring's force is at most the Coulomb cap mu fn: while sliding the
         * stored ft is the capped total force minus the dashpot part (ft = -c_t v_t for
         * mu = 0), which is not a spring force and may be large on a new, soft contact */
        const double *ft = c->ft + 3 * k;
        double cap = p.mu * fmax(c->fn_prev[k], 0.0);
        double ft2 = fmin(ft[0] * ft[0] + ft[1] * ft[1] + ft[2] * ft[2], cap * cap);
        if (c->kt_prev[k] > 0.0) e += 0.5 * ft2 / c->kt_prev[k];
    }
    return e;
}

double dem_sim_mechanical_energy(const dem_sim *s)
{
    return dem_sim_kinetic_energy(s) + dem_sim_potential_energy(s) + dem_sim_contact_energy(s);
}

void dem_sim_step_energy(const dem_sim *s, double dt_step, double e_start_j, dem_step_energy *out)
{
    const dem_net *net = &s->model.net;
    double work = 0.0;
    if (net->active && dt_step > 0.0)
        for (size_t k = 0; k < 3 * net->n_nodes; k++)
            work -= net->impulse[k] * (net->end[k] - net->start[k]) / dt_step;
    out->kinetic_j = dem_sim_kinetic_energy(s);
    out->gravity_j = dem_sim_potential_energy(s);
    out->contact_j = dem_sim_contact_energy(s);
    out->wall_work_j = work;
    out->dissipated_j = work - (out->kinetic_j + out->gravity_j + out->contact_j - e_start_j);
}
