/* cpl_contact_search — where along an interface step that lost its contact the coupler's
 * contact backtracking solves the DEM again (coupler.json "contact_backtracking",
 * docs/notes/contact_backtracking.md).
 *
 * The step runs from the last iterate with contact (t = 0) to the structure's Newton answer
 * (t = 1), where the DEM found no contact. Along it φ(t) is the DEM's resultant interface
 * force projected on the one at t = 0 (φ(0) > 0), and the target φ_T is what the
 * linearisation about t = 0 predicted at t = 1: the force the structure balanced there. For a
 * contact much stiffer than the structure is compliant the coupled step's solution has
 * φ ≈ φ_T, and it is never larger (the note derives both), so a point with φ(t) ≈ φ_T is
 * near the solution, and one with φ(t) below φ_T lies on the side from which the structure's
 * next Newton step does not overshoot the contact's end again.
 *
 * The halving the loop did before went halfway back until a point touched: at a damped
 * contact's end, where φ(t) ~ (t₀ − t)^p with p ≈ 0.3, that point keeps about half of the
 * force that is too much, and the iteration crept towards its solution at 0.5–0.7 per
 * iteration (13–17 iterations). The search instead brackets the contact's end [t_contact,
 * t_past] and fits φ = c (t₀ − t)^p through the last two points with contact, using the slope
 * dφ/dt the DEM's linearisation gives at each (for a power law φ/|φ'| = (t₀ − t)/p is linear in
 * t, which gives p and t₀), and solves the fit for φ_T; where the fit fails, leaves the
 * bracket or has twice in a row landed past the end, it bisects. A point is accepted once its force is within [φ_T/4, 5/4 φ_T]; without
 * a target (φ_T ≤ 0: the linearisation predicted the contact's end, but the try has seen that
 * the contact-free answer collides) the first point with contact is, as by halving.
 *
 * Pure arithmetic: the loop evaluates the DEM at the t the search proposes and adds the
 * result. */
#ifndef CPL_CONTACT_SEARCH_H
#define CPL_CONTACT_SEARCH_H

/* accepted band around the target φ_T */
#define CPL_CONTACT_SEARCH_BELOW 0.25
#define CPL_CONTACT_SEARCH_ABOVE 1.25
/* after a fitted point past the contact's end the next one aims at this share of the last
 * force with contact (φ_T if that is larger) */
#define CPL_CONTACT_SEARCH_AFTER_MISS 0.5

typedef struct cpl_contact_search {
    double target;                       /* φ_T; ≤ 0: none */
    double t_contact, phi_contact, slope_contact;   /* the furthest point with contact and
                                                       φ above the band (t = 0 at first) */
    double t_before, phi_before, slope_before;      /* the one with contact before it */
    int have_before;
    double t_past;                       /* the nearest point beyond the band: no contact,
                                            or φ below it (1 at first) */
    double t_best, phi_best;             /* the point to end at: contact, φ nearest φ_T */
    int fit_missed;                      /* points without contact since the last one above
                                            the band, once a fit exists */
    int done;                            /* a point within the band was found */
} cpl_contact_search;

/* Starts a search: φ(0) = phi0 > 0 with slope dφ/dt slope0 there (NAN: unknown), no contact
 * at t = 1, target phi_target. */
void cpl_contact_search_begin(cpl_contact_search *s, double phi0, double slope0,
                              double phi_target);

/* The next t to evaluate, within (t_contact, t_past). */
double cpl_contact_search_next(const cpl_contact_search *s);

/* Adds the evaluation at t: contact (any nonzero force), φ and its slope dφ/dt (NAN: unknown).
 * Returns 1 when the search is done (a point in the band; without a target, the first point
 * with contact), else 0. */
int cpl_contact_search_add(cpl_contact_search *s, double t, int contact, double phi,
                           double slope);

#endif
