/* dem_damping — ζ from ε by eq. (A.7) and by the Hertz fit eqs. (A.8)–(A.10). */
#include "dem_damping.h"

#include <math.h>

static double clamp_restitution(double e)
{
    if (!(e >= 0.001)) return 0.001; /* also catches NaN */
    if (e > 1.0) return 1.0;
    return e;
}

double dem_zeta_a7(double restitution)
{
    double e = clamp_restitution(restitution);
    if (e > 0.999) return 0.0;
    double l = log(e);
    return -l / sqrt(M_PI * M_PI + l * l); /* eq. (A.7) */
}

double dem_zeta_fit(double restitution)
{
    static const double h[10] = {-6.918798, -16.41105, 146.8049, -796.4559, 2928.711,
                                 -7206.864, 11494.29,  -11342.18, 6276.757, -1489.915};
    double e = clamp_restitution(restitution);
    if (e > 0.999) return 0.0;
    /* eq. (A.10), nested Horner form: Λ = ε (h1 + ε (h2 + ... + ε h10)) */
    double lambda = 0.0;
    for (int k = 9; k >= 0; k--) lambda = e * (h[k] + lambda);
    double denom = 1.0 - (1.0 + e) * (1.0 + e) * exp(lambda); /* eqs. (A.8)–(A.9) */
    if (denom <= 0.0) return 0.0;
    double z2 = 1.0 / denom - 1.0;
    return z2 > 0.0 ? sqrt(z2) : 0.0;
}

/* ε c(ε) at ε = 0.05, 0.10, ..., 1.00, where c is the dimensionless dashpot ξ v0 whose
 * impact rebounds with ε: the root of ε(c) = −X'(end) of X'' = −X^1.5 (1 + c X'), X(0) = 0,
 * X'(0) = 1, the force clamped at zero (integrated to 1e-11, roots to 1e-12). ε c is smooth
 * and tends to 1 for small ε (the clamp ends the contact early). */
static const double hunt_crossley_ec[20] = {
    0.99999998, 0.99981594, 0.99631975, 0.98383334, 0.96020151, 0.92612459, 0.88318220,
    0.83299926, 0.77700159, 0.71637527, 0.65208777, 0.58492303, 0.51551559, 0.44437980,
    0.37193349, 0.29851696, 0.22440800, 0.14983375, 0.07498028, 0.00000000};

double dem_hunt_crossley_factor(double restitution)
{
    double e = clamp_restitution(restitution);
    if (e <= 0.05) return 1.0 / e;
    double x = e / 0.05 - 1.0;   /* table index, 0 at ε = 0.05 */
    int k = (int)x;
    if (k >= 19) return 0.0;
    double w = x - k, ec = (1.0 - w) * hunt_crossley_ec[k] + w * hunt_crossley_ec[k + 1];
    return ec / e;
}
