/* fem_sparse — the symmetric system matrix of the FEM in a fixed sparse pattern, and its
 * factorisation with SuiteSparse.
 *
 * The pattern (upper triangle, compressed sparse columns, over the free equations only) is
 * built once from the element connectivity together with a map from each element's 6x6
 * entries to value slots, so assembling is a scatter without search. CHOLMOD analyses the
 * pattern once (fill-reducing ordering, symbolic factor) and refactorises numerically every
 * Newton iteration. A matrix that is not positive definite (a truss in compression, the
 * negative part of a contact linearisation) stops a supernodal LL^T: with mode "auto" the
 * factor then becomes a simplicial LDL^T for good (switched_to_ldlt), which takes an
 * indefinite matrix unless a pivot is zero; LL^T by request, or an LDL^T that meets a zero
 * pivot, falls back to UMFPACK LU (several times slower, and not kept across a restore). A
 * singular matrix is reported with the failing equation in *bad_eq so the caller can name
 * the node.
 */
#ifndef FEM_SPARSE_H
#define FEM_SPARSE_H

#include <cholmod.h>
#include "nc_error.h"

/* nc_error code of a matrix that cannot be factorised: singular (a dof nothing holds) or
 * with a non-finite entry. */
#define FEM_ERR_SINGULAR 2

typedef struct fem_sparse {
    int n;                    /* number of equations */
    int nnz;                  /* stored entries (upper triangle incl. diagonal) */
    int *colptr, *rowind;     /* pattern, owned by A */
    double *x;                /* values, owned by A */
    int *diag;                /* [n] slot of each diagonal entry */
    cholmod_common c;
    int started;
    cholmod_sparse *A;
    cholmod_factor *L;
    cholmod_dense *B, *X, *Y, *E;
    int have_factor;          /* the last numeric factorisation succeeded */
    cholmod_factor *L_saved;  /* copy of L made by fem_sparse_save_factor */
    int saved_valid;
    int factor_is_saved;      /* L is L_saved bit for bit (no factorisation since the last
                                 save or restore): both then skip their copy */
    double *factor_x;         /* [nnz] the values L (or the LU) was computed from, and ... */
    double *saved_factor_x;   /* ... those of L_saved: a checkpoint stores them, since the
                                 same values on the same pattern give the same factors */
    int auto_mode;            /* mode 0: a supernodal factor may become simplicial LDL^T */
    int switched_to_ldlt;     /* it did (fem_sparse_factorize) */
    /* LU fallback */
    int use_lu;               /* the last factorisation is LU */
    int lu_count;             /* how many times LU was used */
    int full_nnz;
    int *full_colptr, *full_rowind, *full_from; /* full pattern and its source slot */
    double *full_x;
    void *symbolic, *numeric;
} fem_sparse;

/* elem_eq: [6 n_elem] equation number of each element dof (-1 = not an unknown).
 * slot_map (output, caller allocated): [36 n_elem] value slot of entry (a, b) of the
 * element matrix (row-major), -1 when the entry is not stored (lower triangle, fixed dof). */
/* mode: 0 = let CHOLMOD choose (simplicial LDL^T for small/sparse factors, supernodal
 * LL^T for large ones; a supernodal one that meets an indefinite matrix becomes simplicial
 * LDL^T), 1 = simplicial LDL^T, 2 = supernodal LL^T. LDL^T without pivoting accepts an
 * indefinite matrix as long as no pivot is zero; LL^T stops at the first non-positive pivot,
 * and then UMFPACK LU takes over. */
int fem_sparse_build(fem_sparse *s, int n, int n_elem, const int *elem_eq, int *slot_map,
                     int mode, nc_error *err);
/* Factorises the current values. On a singular matrix returns -1 with *bad_eq >= 0. */
int fem_sparse_factorize(fem_sparse *s, int *bad_eq, nc_error *err);
/* Solves A x = b with the last factorisation (b and x may alias). */
int fem_sparse_solve(fem_sparse *s, const double *b, double *x, nc_error *err);
/* y = A x with the current values (the symmetric matrix stored as its upper triangle). */
void fem_sparse_matvec(const fem_sparse *s, const double *x, double *y);
/* Keeps a copy of the current factorisation / puts it back (so that a step repeated after
 * a restore starts from the same factorisation). An LU factorisation is not kept: after
 * restoring, no factorisation is available. */
int fem_sparse_save_factor(fem_sparse *s, nc_error *err);
int fem_sparse_restore_factor(fem_sparse *s, nc_error *err);
/* Puts back a recorded factorisation state (a checkpoint's): saved_values (NULL: no saved
 * factorisation) are factorised and kept as the saved one, then values (NULL: no current
 * factorisation) as the current one. The same values on the same pattern give the same
 * factors bit for bit, so the run continues as if it had never stopped. */
int fem_sparse_refactor(fem_sparse *s, const double *values, const double *saved_values,
                        nc_error *err);
void fem_sparse_free(fem_sparse *s);

#endif
