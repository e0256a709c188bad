/* nc_lapack — the LAPACK routines the solvers call, declared once (Debian's liblapack-dev
 * ships the library without a C header; linked with -llapack).
 *
 * dgesv_: solves A X = B for a general n x n A (column-major, overwritten by its LU
 * factors; ipiv [n] the pivots) and nrhs right-hand sides B (overwritten by X); *info 0 on
 * success, > 0 when A is singular. */
#ifndef NC_LAPACK_H
#define NC_LAPACK_H

void dgesv_(const int *n, const int *nrhs, double *a, const int *lda, int *ipiv, double *b,
            const int *ldb, int *info);

#endif
