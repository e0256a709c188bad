/* dem_contact_hertz — the contact force law of one contact (Appendix A, eq. (A.5), Table 3).
 *
 * Hertz–Mindlin: Fn = 4/3 E* sqrt(R*) δ^1.5 + cn δ̇, cn = 2 ζ sqrt(m* kn') with the tangent
 * stiffness kn' = 2 E* sqrt(R* δ) (the stiffness the fit eqs. (A.8)–(A.10) was made for), clamped to
 * Fn >= 0 (no tension). Tangential: incremental spring kt = 8 G* sqrt(R* δ) with history,
 * rescaled by kt/kt_prev while unloading, dashpot ct = 2 ζ sqrt(m* kt), Coulomb cap μ Fn on
 * spring + dashpot; sliding leaves the spring at most at the cap and at most at its own
 * loaded value. With damping "hunt_crossley" v0 is the contact's fastest approach so far.
 * Linear: Fn = kn δ + 2 ζ sqrt(m* kn) δ̇ (the classic spring–dashpot for which eq. (A.7) is exact;
 * the dashpot may pull slightly at the end of the contact, as eq. (A.7) assumes), kt = ratio kn.
 * The normal part of each law is an inline function of its header (dem_law_hertz.h,
 * dem_law_linear.h); everything else about a law is in its table (dem_contact_law.h).
 */
#ifndef DEM_CONTACT_HERTZ_H
#define DEM_CONTACT_HERTZ_H

#include <math.h>

#include "dem_damping.h"
#include "dem_model.h"

/* Effective properties of a contact pair. */
typedef struct dem_pair {
    double e_star;  /* Pa */
    double g_star;  /* Pa */
    double r_star;  /* m */
    double m_star;  /* kg */
    double zeta;    /* damping ratio */
    double hunt_crossley; /* c(ε) = ξ v0 of the Hunt–Crossley dashpot (dem_damping.h) */
    double mu;      /* friction coefficient */
    double kt_kn_root; /* sqrt(kt / kn') = sqrt(4 G* / E*) (Hertz), sqrt(ratio) (linear) */
} dem_pair;

#include "dem_law_hertz.h"
#include "dem_law_linear.h"

/* 1/E* = (1-ν1²)/E1 + (1-ν2²)/E2 ; 1/G* = (2-ν1)/G1 + (2-ν2)/G2. */
double dem_effective_modulus(double e1, double nu1, double e2, double nu2);
double dem_effective_shear(double g1, double nu1, double g2, double nu2);

/* Force on sphere i for overlap δ > 0 along the unit normal n (from i towards the other body),
 * vc = velocity of the other body's contact point minus sphere i's (eq. (A.2)), time step dt.
 * ft (3, elastic tangential force on i), kt_prev, fn_prev are the contact's history, updated.
 * Writes the total force on i to f_i and returns the normal force magnitude.
 * Always inlined: it runs once per contact and step, and a call would pass the small vectors
 * through memory (store-forwarding stalls when they are read back as pairs). */
static inline __attribute__((always_inline)) double dem_contact_force(const dem_params *prm, const dem_pair *pair,
                                       double overlap, const double n[3], const double vc[3],
                                       double dt, double ft[3], double *kt_prev,
                                       double *fn_prev, double *impact_speed, double f_i[3])
{
    double vn = vc[0] * n[0] + vc[1] * n[1] + vc[2] * n[2];
    double overlap_rate = -vn; /* > 0 while approaching (eq. (A.3)) */
    double fn, kt, cn_root; /* cn_root = sqrt(m* kn') */
    /* compile-time dispatch on the law (dem_contact_law.h): each branch is inlined */
    if (prm->law == DEM_LAW_HERTZ_MINDLIN) {
        if (prm->damping == DEM_DAMPING_HUNT_CROSSLEY) {
            /* v0: the fastest approach of this contact so far (the first touch of a single
             * impact; a contact that began as a graze and is then struck takes the strike's
             * speed), so the force is at most (1 + c(ε)) times the elastic force */
            double v0 = fmax(overlap_rate, DEM_HUNT_CROSSLEY_MIN_SPEED);
            if (!(*impact_speed >= v0)) *impact_speed = v0;
            fn = dem_hertz_hunt_crossley_force(pair, overlap, overlap_rate, *impact_speed, &kt,
                                               &cn_root);
        } else {
            fn = dem_hertz_normal_force(pair, overlap, overlap_rate, &kt, &cn_root);
        }
        if (fn < 0.0) fn = 0.0; /* no tension */
    } else {
        fn = dem_linear_normal_force(prm, pair, overlap, overlap_rate, &kt, &cn_root);
    }
    double ct = 2.0 * pair->zeta * cn_root * pair->kt_kn_root; /* 2 ζ sqrt(m* kt) */
    /* written out per component (no loops): the vectors then stay in registers */
    double vt0 = vc[0] - vn * n[0], vt1 = vc[1] - vn * n[1], vt2 = vc[2] - vn * n[2];
    double ft0 = ft[0], ft1 = ft[1], ft2 = ft[2];

    double old2 = ft0 * ft0 + ft1 * ft1 + ft2 * ft2;
    if (old2 > 0.0) {
        /* keep the history in the current tangent plane (the contact frame turns) */
        double fdn = ft0 * n[0] + ft1 * n[1] + ft2 * n[2];
        ft0 -= fdn * n[0];
        ft1 -= fdn * n[1];
        ft2 -= fdn * n[2];
        double new2 = ft0 * ft0 + ft1 * ft1 + ft2 * ft2;
        double s = new2 > 0.0 ? sqrt(old2 / new2) : 0.0;
        /* eq. (A.5): unloading scales the stored force with the stiffness ratio */
        if (fn < *fn_prev && *kt_prev > 0.0) s *= kt / *kt_prev;
        ft0 *= s;
        ft1 *= s;
        ft2 *= s;
    }
    /* eq. (A.4): Δs = v_t dt */
    ft0 += kt * vt0 * dt;
    ft1 += kt * vt1 * dt;
    ft2 += kt * vt2 * dt;

    double spring_trial2 = ft0 * ft0 + ft1 * ft1 + ft2 * ft2;
    double tr0 = ft0 + ct * vt0, tr1 = ft1 + ct * vt1, tr2 = ft2 + ct * vt2;
    double trial2 = tr0 * tr0 + tr1 * tr1 + tr2 * tr2;
    double cap = pair->mu * (fn > 0.0 ? fn : 0.0);
    if (trial2 > cap * cap) { /* Coulomb: slide, keep the spring at the cap */
        double s = trial2 > 0.0 ? cap / sqrt(trial2) : 0.0;
        tr0 *= s;
        tr1 *= s;
        tr2 *= s;
        ft0 = tr0 - ct * vt0;
        ft1 = tr1 - ct * vt1;
        ft2 = tr2 - ct * vt2;
        /* sliding never stretches the spring: it holds at most the Coulomb force and at
         * most what its own increments k_t v_t dt loaded. On a new contact the dashpot part
         * ct v_t may exceed the cap many times, and a spring left at cap - ct v_t, or raised
         * with a fast-growing cap, would push back once the sliding stops (energy from
         * nowhere) */
        double spring2 = ft0 * ft0 + ft1 * ft1 + ft2 * ft2;
        double limit2 = fmin(cap * cap, spring_trial2);
        if (spring2 > limit2) {
            double q = sqrt(limit2 / spring2);
            ft0 *= q;
            ft1 *= q;
            ft2 *= q;
        }
    }
    ft[0] = ft0;
    ft[1] = ft1;
    ft[2] = ft2;
    f_i[0] = -fn * n[0] + tr0;
    f_i[1] = -fn * n[1] + tr1;
    f_i[2] = -fn * n[2] + tr2;
    *kt_prev = kt;
    *fn_prev = fn;
    return fn;
}

#endif
