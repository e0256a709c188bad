/* cpl_contact_search — the point along an interface step at which contact backtracking
 * solves the DEM again (cpl_contact_search.h). */
#include "cpl_contact_search.h"

#include <math.h>

void cpl_contact_search_begin(cpl_contact_search *s, double phi0, double slope0,
                              double phi_target)
{
    *s = (cpl_contact_search){0};
    s->target = phi_target;
    s->t_contact = 0.0;
    s->phi_contact = phi0;
    s->slope_contact = slope0;
    s->t_past = 1.0;
    s->t_best = -1.0;
    s->phi_best = NAN;
}

/* The power law φ = c (t₀ − t)^p through two points with contact and their slopes, solved for
 * φ_T; NAN where the points do not fit one (a slope that does not fall, p ≤ 0, t₀ before the
 * second point). φ/|φ'| = (t₀ − t)/p for such a law. */
static double power_law_target(double t1, double phi1, double slope1, double t2, double phi2,
                               double slope2, double target)
{
    if (!(slope1 < 0.0 && slope2 < 0.0 && phi1 > 0.0 && phi2 > 0.0 && t2 > t1)) return NAN;
    const double l1 = phi1 / -slope1, l2 = phi2 / -slope2;
    if (!(l1 > l2)) return NAN;
    const double p = (t2 - t1) / (l1 - l2);
    const double t0 = t2 + p * l2;
    if (!(p > 0.0 && isfinite(t0))) return NAN;
    return t0 - (t0 - t2) * pow(target / phi2, 1.0 / p);
}

/* Halfway without a target or a fit, or after two points past the end in a row; else the
 * fit's point for φ_T, or, after one point past the end, for a force nearer the last one
 * (the fit's end lies a little beyond the true one where the law steepens towards it). */
double cpl_contact_search_next(const cpl_contact_search *s)
{
    const double mid = 0.5 * (s->t_contact + s->t_past);
    if (!(s->target > 0.0) || !s->have_before || s->fit_missed > 1) return mid;
    const double aim = s->fit_missed
                           ? fmax(s->target, CPL_CONTACT_SEARCH_AFTER_MISS * s->phi_contact)
                           : s->target;
    const double t = power_law_target(s->t_before, s->phi_before, s->slope_before,
                                      s->t_contact, s->phi_contact, s->slope_contact, aim);
    /* inside the bracket, and not so close to its ends that rounding makes it one of them */
    const double margin = 1e-12 * (1.0 + s->t_past);
    return t > s->t_contact + margin && t < s->t_past - margin ? t : mid;
}

/* log-distance from the target: how far a force is from it, either way */
static double miss(double phi, double target)
{
    return fabs(log(phi / target));
}

int cpl_contact_search_add(cpl_contact_search *s, double t, int contact, double phi,
                           double slope)
{
    const int has_target = s->target > 0.0;
    if (contact && (!has_target || (phi > 0.0 && (s->t_best < 0.0 ||
                                                  miss(phi, s->target) <
                                                      miss(s->phi_best, s->target))))) {
        s->t_best = t;
        s->phi_best = phi;
    }
    if (!contact) {
        s->fit_missed = s->have_before ? s->fit_missed + 1 : 0;
        if (t < s->t_past) s->t_past = t;
        return 0;
    }
    if (!has_target) return s->done = 1;
    if (phi >= CPL_CONTACT_SEARCH_BELOW * s->target &&
        phi <= CPL_CONTACT_SEARCH_ABOVE * s->target)
        return s->done = 1;
    if (phi < CPL_CONTACT_SEARCH_BELOW * s->target) {
        if (t < s->t_past) s->t_past = t;
        return 0;
    }
    s->fit_missed = 0;
    if (t > s->t_contact) {
        s->t_before = s->t_contact;
        s->phi_before = s->phi_contact;
        s->slope_before = s->slope_contact;
        s->have_before = 1;
        s->t_contact = t;
        s->phi_contact = phi;
        s->slope_contact = slope;
    }
    return 0;
}
