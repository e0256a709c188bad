/* nc_plausible — the wide engineering ranges outside which an input is reported as
 * implausible (a warning naming file and field; dem_solver/README.md and
 * fem_solver/README.md list them), and the one warning writer the readers share. */
#ifndef NC_PLAUSIBLE_H
#define NC_PLAUSIBLE_H

#include <stdio.h>

#define NC_PLAUSIBLE_DENSITY_MIN 100.0       /* kg/m3: any solid material */
#define NC_PLAUSIBLE_DENSITY_MAX 25000.0
#define NC_PLAUSIBLE_MODULUS_MIN_PA 1e5      /* Young's modulus */
#define NC_PLAUSIBLE_MODULUS_MAX_PA 1e12

/* One line "warning: <text>" to sink (NULL: dropped). */
void nc_warn(FILE *sink, const char *format, ...) __attribute__((format(printf, 2, 3)));

#endif
