/* cpl_relax_aitken — Aitken Δ² dynamic relaxation, eq. (34), one α per block. Internal to
 * cpl_relax; exposed for unit tests. */
#ifndef CPL_RELAX_AITKEN_H
#define CPL_RELAX_AITKEN_H

#include <stddef.h>
#include "nc_error.h"

typedef struct cpl_aitken {
    size_t n, n_blocks, block;   /* block = n / n_blocks */
    double alpha0, first_cap, alpha_min, alpha_max;
    double *alpha;               /* [n_blocks] α of the last iteration */
    double *r_prev;              /* [n] residual of the previous iteration in this step */
    int have_prev;               /* r_prev valid (not the first iteration of the step) */
    int have_alpha;              /* α of a previous step exists */
} cpl_aitken;

int cpl_aitken_init(cpl_aitken *a, size_t n, size_t n_blocks, double alpha0, double first_cap,
                    double alpha_min, double alpha_max, nc_error *err);
void cpl_aitken_free(cpl_aitken *a);
void cpl_aitken_begin_step(cpl_aitken *a);
/* One relaxation: x_next = x_in + α_b (x_out − x_in) per block; returns α of block 0. */
double cpl_aitken_update(cpl_aitken *a, const double *x_in, const double *x_out,
                         double *x_next);

#endif
