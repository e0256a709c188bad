/* dem_detect_sphere — sphere–sphere contacts (eq. (13)) of sphere i with its Verlet neighbours
 * j > i (dem_neighbor_list.h), each pair found once; the force goes to both spheres. The hot
 * loop of the solver: the contact data stays in registers (no dem_contact_in record). */
#include "dem_detect.h"

static int present(const dem_sim *s)
{
    (void)s;
    return 1;
}

/* The contacts of sphere i with its neighbours from the q_first-th on (that one touches). */
static __attribute__((noinline)) int contacts_from(const dem_sim *s, dem_emit_ctx *ctx, size_t i,
                                                   double dt, int32_t q_first)
{
    const double *pi = s->model.sph.pos + 3 * i;
    double ri = s->model.sph.radius[i];
    int32_t bi = s->model.sph.body[i];
    int32_t mat_i = s->model.sph.material[i];
    const dem_material *mi = &s->model.materials[mat_i];
    double m_i = s->model.bod.mass[bi];
    const double *v_i = s->model.sph.vel + 3 * i;
    const double *w_i = s->model.bod.omega + 3 * (size_t)bi;
    int shared_i = s->work.shared_sphere[i];
    for (int32_t q = q_first; q < s->nlist.first[i + 1]; q++) {
        size_t j = (size_t)s->nlist.nbr[q];
        const double *pj = s->model.sph.pos + 3 * j;
        double d[3] = {pj[0] - pi[0], pj[1] - pi[1], pj[2] - pi[2]};
        double d2 = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
        double rj = s->model.sph.radius[j];
        double rs = ri + rj;
        if (d2 >= rs * rs || d2 == 0.0) continue; /* eq. (13) */
        double dist = sqrt(d2);
        double overlap = rs - dist; /* eq. (A.1) */
        double inv_dist = 1.0 / dist; /* one division instead of three */
        double n[3] = {d[0] * inv_dist, d[1] * inv_dist, d[2] * inv_dist};
        double lever_i = ri - 0.5 * overlap;
        double lever_j = rj - 0.5 * overlap;
        int32_t bj = s->model.sph.body[j];
        const double *vj = s->model.sph.vel + 3 * j;
        const double *wj = s->model.bod.omega + 3 * (size_t)bj;
        double rj_vec[3] = {-lever_j * n[0], -lever_j * n[1], -lever_j * n[2]};
        double wr[3];
        dem_cross3(wj, rj_vec, wr);
        double v_other[3] = {vj[0] + wr[0], vj[1] + wr[1], vj[2] + wr[2]};
        dem_pair pair;
        int32_t mat_j = s->model.sph.material[j];
        const dem_material *mj = &s->model.materials[mat_j];
        double m_j = s->model.bod.mass[bj];
        if (mat_i == mat_j) { /* common case: no divisions */
            pair.e_star = mi->pair_e_star;
            pair.g_star = mi->pair_g_star;
            pair.kt_kn_root = mi->pair_kt_kn_root;
        } else {
            pair.e_star = dem_effective_modulus(mi->youngs_modulus_pa, mi->poisson_ratio,
                                                mj->youngs_modulus_pa, mj->poisson_ratio);
            pair.g_star = dem_effective_shear(mi->shear_modulus_pa, mi->poisson_ratio,
                                              mj->shear_modulus_pa, mj->poisson_ratio);
            pair.kt_kn_root = dem_contact_law_of(s->model.prm.law)->kt_kn_root(&s->model.prm, pair.e_star,
                                                                                pair.g_star);
        }
        pair.r_star = ri * rj / rs;
        pair.m_star = m_i * m_j / (m_i + m_j);
        pair.zeta = 0.5 * (mi->zeta + mj->zeta);
        pair.hunt_crossley = 0.5 * (mi->hunt_crossley + mj->hunt_crossley);
        pair.mu = 0.5 * (mi->friction + mj->friction);

        double ft[3], kt_prev, fn_prev, impact_speed;
        int32_t p;
        long c = dem_new_record(s, ctx, i, DEM_CONTACT_SPHERE, (int32_t)j, 0, ft, &kt_prev, &fn_prev,
                                &impact_speed, &p);
        if (c < 0) return -1;
        double r_i[3] = {lever_i * n[0], lever_i * n[1], lever_i * n[2]};
        dem_cross3(w_i, r_i, wr);
        double vc[3] = {v_other[0] - (v_i[0] + wr[0]), v_other[1] - (v_i[1] + wr[1]),
                        v_other[2] - (v_i[2] + wr[2])}; /* eq. (A.2) */
        double f[3];
        dem_contact_force(&s->model.prm, &pair, overlap, n, vc, dt, ft, &kt_prev, &fn_prev,
                          &impact_speed, f);
        dem_store_record(ctx->out, (size_t)c, ft, kt_prev, fn_prev, impact_speed, overlap, n);
        double ti[3], tj[3];
        dem_cross3(r_i, f, ti);
        /* force -f at -r_j: torque = (-r_j) x (-f) = r_j x f */
        double r_j[3] = {lever_j * n[0], lever_j * n[1], lever_j * n[2]};
        dem_cross3(r_j, f, tj);
        if (shared_i) {
            if (dem_spill_add(ctx->spill, DEM_CONTACT_SPHERE, (int32_t)i, 0.0, f, ti)) return -1;
        } else {
            double *fi = s->model.sph.force + 3 * i, *tq = s->model.sph.torque + 3 * i;
            fi[0] += f[0];
            fi[1] += f[1];
            fi[2] += f[2];
            tq[0] += ti[0];
            tq[1] += ti[1];
            tq[2] += ti[2];
        }
        if (s->work.shared_sphere[j]) {
            double mf[3] = {-f[0], -f[1], -f[2]}; /* x + (-f) rounds exactly as x - f */
            if (dem_spill_add(ctx->spill, DEM_CONTACT_SPHERE, (int32_t)j, 0.0, mf, tj)) return -1;
        } else {
            double *fj = s->model.sph.force + 3 * j, *tq = s->model.sph.torque + 3 * j;
            fj[0] -= f[0];
            fj[1] -= f[1];
            fj[2] -= f[2];
            tq[0] += tj[0];
            tq[1] += tj[1];
            tq[2] += tj[2];
        }
    }
    return 0;
}

/* Most neighbours do not touch: a lean scan (the test of contacts_from) finds the first one
 * that does, and the contacts are handled out of line, where the registers are free. */
static int detect(const dem_sim *s, dem_emit_ctx *ctx, size_t i, double dt, int *overflow)
{
    (void)overflow; /* no feature list */
    const double *pos = s->model.sph.pos, *radius = s->model.sph.radius;
    const int32_t *nbr = s->nlist.nbr;
    double pi0 = pos[3 * i], pi1 = pos[3 * i + 1], pi2 = pos[3 * i + 2], ri = radius[i];
    for (int32_t q = s->nlist.first[i]; q < s->nlist.first[i + 1]; q++) {
        const double *pj = pos + 3 * (size_t)nbr[q];
        double d[3] = {pj[0] - pi0, pj[1] - pi1, pj[2] - pi2};
        double d2 = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
        double rs = ri + radius[nbr[q]];
        if (d2 >= rs * rs || d2 == 0.0) continue; /* eq. (13) */
        return contacts_from(s, ctx, i, dt, q);
    }
    return 0;
}

const dem_detector dem_detect_sphere = {"sphere", present, detect};
