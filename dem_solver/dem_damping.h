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

#endif
