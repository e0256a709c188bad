/* dem_contact_hertz — effective pair moduli of the contact law; the force law itself is the
 * inline dem_contact_force() in dem_contact_hertz.h (called once per contact and step). */
#include "dem_contact_hertz.h"

#include <math.h>

double dem_effective_modulus(double e1, double nu1, double e2, double nu2)
{
    return 1.0 / ((1.0 - nu1 * nu1) / e1 + (1.0 - nu2 * nu2) / e2);
}

double dem_effective_shear(double g1, double nu1, double g2, double nu2)
{
    return 1.0 / ((2.0 - nu1) / g1 + (2.0 - nu2) / g2);
}
