/* fem_interface_jacobian — a linearisation of the coupling force about a reference state,
 * so the FEM can solve with the contact as an implicit spring-dashpot (interface-Jacobian,
 * Robin-type partitioned coupling; docs/notes/damped_contact.md says why: the interface map of
 * a heavy rock on a light cable node has a gain of 25-50, which plain Dirichlet-Neumann
 * iterations hardly contract).
 *
 * Contract: the force on the structure is
 *   F(u, v) = F^k + dF,   dF = -K (u - u^k) - C (v - v^k),
 * with K = -dF/du and C = -dF/dv given as 3x3 blocks between model nodes: block (i, j) maps
 * the displacement/velocity of node j to the force on node i (row-major, row = force
 * direction of node i, column = motion direction of node j). Repeated (i, j) blocks are
 * summed, so a contact detector can append one block set per contact. u^k, v^k are full
 * dof vectors (3 n_nodes). fem_ijac_set() copies everything and maps every block entry to
 * its value slot in the FEM's pattern once; afterwards fem_ijac_force() and
 * fem_ijac_scatter() allocate nothing. Entries on supported dofs act in the residual (the
 * supports' motion is known) but have no matrix entry. A block between two free nodes
 * without a slot in the pattern is rejected: fem_analysis_set_linearisation() first grows
 * the pattern by such pairs (a rock touching several elements couples their nodes through
 * its own motion).
 * The matrix receives the symmetric part (K + K^T)/2 (the pattern is a symmetric upper
 * triangle) and the residual the full K; fem_ijac_skew_apply() gives the rest of the tangent,
 * the skew part (K - K^T)/2, which the Newton step adds through GMRES (fem_gmres.h) when
 * has_skew says there is one.
 */
#ifndef FEM_INTERFACE_JACOBIAN_H
#define FEM_INTERFACE_JACOBIAN_H

#include "fem_sparse.h"

typedef struct fem_ijac {
    int active;              /* 1 while a linearisation is set */
    int ndof;
    int n_blocks, cap_blocks;
    int *nodes;              /* [2 n_blocks] (i, j) */
    double *K, *C;           /* [9 n_blocks] N/m and N s/m */
    int *slot;               /* [9 n_blocks] value slot of entry (r, c), -1: no matrix entry */
    int *row_eq, *col_eq;    /* [9 n_blocks] equations of entry (r, c) (-1: a supported dof) */
    int has_skew;            /* K or C has a skew part on the free equations */
    double *slot_sum;        /* [cap_slots] work space of the skew check, kept zero */
    int cap_slots;
    double *weight;          /* [9 n_blocks] share of the entry in its slot (1 or 1/2) */
    double *u_ref, *v_ref;   /* [ndof] reference displacement (m) and velocity (m/s) */
    double *df;              /* [ndof] dF at the last evaluation (N) */
    double force_scale_n;    /* size of the terms of dF before they cancel (N): part of the
                                Newton force scale, as a stiff contact's K (u - u^k) rounds
                                at that size however small dF is */
} fem_ijac;

/* Sets the linearisation; returns 0, or -1 with err naming the offending block (then the
 * linearisation is cleared). eq: [ndof] equation of each dof (-1 supported), A: the pattern.
 * C_blocks may be NULL (no damping term). */
int fem_ijac_set(fem_ijac *j, int ndof, const int *eq, const fem_sparse *A, const double *u_ref,
                 const double *v_ref, int n_blocks, const int *block_nodes,
                 const double *K_blocks, const double *C_blocks, nc_error *err);
/* 1 when every free-dof entry of the block (ni, nj) has a slot in A's pattern. */
int fem_ijac_pair_stored(const fem_sparse *A, const int *eq, int ni, int nj);
/* Back to no linearisation (keeps the memory for the next set). */
void fem_ijac_clear(fem_ijac *j);
/* j->df = -K (u - u^k) - C (v - v^k) on all dofs; v == NULL leaves the damping term out
 * (statics). */
void fem_ijac_force(fem_ijac *j, const double *u, const double *v);
/* x[slot] += sym(c_k K + c_c C), the tangent -d(dF)/du with dv/du = c_c. */
void fem_ijac_scatter(const fem_ijac *j, double c_k, double c_c, double *x);
/* y[eq] += skew(c_k K + c_c C) x[eq] on the free equations: the part of the tangent that
 * fem_ijac_scatter leaves out (nothing when has_skew is 0). */
void fem_ijac_skew_apply(const fem_ijac *j, double c_k, double c_c, const double *x, double *y);
/* How far one ulp of each displacement in K (u - u^k) moves the free equations' residual
 * (N, 2-norm): |c_k K + c_c C| (|u| + |u^k|) eps, block row by block row, the size below which no
 * increment can bring the linearised force (a contact's dashpot at a graze: 1e13-1e16 N/m). */
double fem_ijac_rounding_n(const fem_ijac *j, double c_k, double c_c, const double *u);
void fem_ijac_free(fem_ijac *j);

#endif
