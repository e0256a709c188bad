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
