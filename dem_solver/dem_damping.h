/* dem_damping — damping ratio ζ from the coefficient of restitution ε.
 *
 * eq. (A.7) is exact for the linear spring–dashpot; eqs. (A.8)–(A.10) is the fit for the Hertz law with
 * a dashpot c = 2 ζ sqrt(m* k) whose k is the Hertz TANGENT stiffness 2 E* sqrt(R* δ)
 * (dem_contact_hertz.c uses exactly that; tests/dem_solver/test_contact checks the rebound).
 */
#ifndef DEM_DAMPING_H
#define DEM_DAMPING_H

/* eq. (A.7): ζ = -ln ε / sqrt(π² + ln² ε); ε clamped to [0.001, 1]. */
double dem_zeta_a7(double restitution);
/* eqs. (A.8)–(A.10); ε clamped to [0.001, 1], ζ = 0 for ε > 0.999. */
double dem_zeta_fit(double restitution);
/* The Hunt–Crossley dashpot (damping "hunt_crossley"): fn = 4/3 E* sqrt(R*) δ^1.5 (1 + ξ δ̇)
 * with ξ = c(ε) / v0, v0 the contact's normal approach speed when it began. c(ε) is the exact
 * inverse of the restitution of a Hunt–Crossley impact (a table computed once by integrating
 * the dimensionless impact, dem_damping.c), so the impact rebounds with ε whatever v0; the
 * closed form 8 (1 − ε) / (5 ε) of Flores et al. (Nonlinear Dyn. 2011) is close to it near
 * ε = 1 and 30 % too large at ε = 0.2 (a bounce at 0.156 instead of 0.2).
 * Unlike eq. (A.5)'s dashpot 2 ζ sqrt(m* kn') δ̇, whose coefficient grows like δ^(1/4) from
 * zero overlap, the damping force vanishes like δ^1.5 at the first touch: the normal force is
 * continuous there, which a partitioned iteration needs (docs/notes/contact_backtracking.md).
 * Returns c(ε), ε clamped to [0.001, 1]. */
double dem_hunt_crossley_factor(double restitution);
/* The impact speed v0 of a contact that begins slower than this (m/s): a resting contact's
 * ξ stays bounded. */
#define DEM_HUNT_CROSSLEY_MIN_SPEED 0.1

#endif
