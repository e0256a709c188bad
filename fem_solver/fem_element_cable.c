/* fem_element_cable — internal force, tangent and mass of the cable/truss element
 * (eqs. (8)–(11); see fem_element_cable.h for the block layout). */
#include "fem_element_cable.h"

#include <math.h>

double fem_cable_response(const double d[3], double L0, double EA, double AS_pre, int is_cable,
                          double f_l[3], double Kb[9], int *slack)
{
    double l2 = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
    double L2 = L0 * L0;
    double green = (l2 - L2) / (2.0 * L2);            /* Green-Lagrange strain */
    double AS_tot = EA * green + AS_pre;               /* A (E_mod E + S_pre), eq. (10) */
    if (is_cable && AS_tot < 0.0) {
        /* slack cable: carries nothing, contributes nothing */
        f_l[0] = f_l[1] = f_l[2] = 0.0;
        for (int i = 0; i < 9; i++) Kb[i] = 0.0;
        if (slack) *slack = 1;
        return 0.0;
    }
    if (slack) *slack = 0;
    double s = AS_tot / L0;                            /* eq. (8) */
    double mat = EA / (L2 * L0);                       /* eq. (9), material part */
    for (int i = 0; i < 3; i++) {
        f_l[i] = s * d[i];
        for (int j = 0; j < 3; j++) Kb[3 * i + j] = mat * d[i] * d[j];
        Kb[4 * i] += s;                                /* geometric part */
    }
    return AS_tot * sqrt(l2) / L0;
}

void fem_cable_mass(double rhoA, double L0, int lumped, double *m11, double *m12)
{
    double m = rhoA * L0;
    if (lumped) {
        *m11 = 0.5 * m;
        *m12 = 0.0;
    } else {
        *m11 = m / 3.0;                                /* eq. (11): rho A L / 6 * 2 */
        *m12 = m / 6.0;
    }
}
