/* fem_linearisation_psd — the positive semi-definite part of the symmetric part of an
 * interface linearisation given as 3x3 node blocks (the DEM's K = −dF/du and C = −dF/du̇).
 *
 * Why: a rock pressing a net node has a tangent that is negative across the contact normal
 * (the force f on a point pushed by a convex surface of radius R turns with the point:
 * −f/R (I − n nᵀ)), and friction and the rock's own response add more; measured on
 * cases/steel_net, (K + Kᵀ)/2 had a negative eigenvalue in two of three contact iterations,
 * down to −0.19 × its largest. Added to the structure's tangent, that makes the FEM's Newton
 * iteration indefinite and it fails inside a coupling iteration (docs/notes/interface_jacobian.md).
 * Clipping the negative eigenvalues keeps the structure's problem well posed; the coupled
 * solution does not change (the linearised correction vanishes where the interface
 * iteration converges), the interface iteration corrects what the clipped part misses. Where
 * the negative part is real and the structure carries it (a sphere across a prestressed
 * cable) clipping costs interface iterations (cases/rest_position 5.3 → 7.8 per contact
 * step), so fem_coupled.c uses the projection only to retry a step whose Newton iteration
 * failed with the full linearisation.
 *
 * Contract: blocks (b of them) map the motion of node nodes[2k+1] to the force on node
 * nodes[2k], row-major; C may be NULL. fem_psd_project() groups the nodes into connected
 * components of the block graph, and for each component of at most FEM_PSD_MAX_NODES nodes
 * replaces (K + Kᵀ)/2 (and (C + Cᵀ)/2) by its projection V max(Λ, 0) Vᵀ (LAPACK dsyev).
 * The result is a list of full blocks, (i, j) and (j, i) both present, one per node pair of a
 * component (pairs that had no block may appear: the projection fills the component in).
 * A larger component keeps its symmetric part unprojected and is counted. State lives in
 * the struct; zero-initialise it, free with fem_psd_free(). */
#ifndef FEM_LINEARISATION_PSD_H
#define FEM_LINEARISATION_PSD_H

#include <stddef.h>
#include "nc_error.h"

#define FEM_PSD_MAX_NODES 64

typedef struct fem_psd {
    size_t n_blocks, cap_blocks;
    int *nodes;            /* [2 n_blocks] (force node, motion node) */
    double *K, *C;         /* [9 n_blocks] */
    int has_damping;
    /* statistics of all calls */
    long components, clipped_eigenvalues, large_components;
    long last_clipped;            /* negative eigenvalues clipped by the last call */
    double most_negative_ratio;   /* smallest λ_min / λ_max seen (0 when none negative) */
    /* work space */
    size_t cap_nodes, cap_dense;
    int *node_list, *parent;
    double *dense_k, *dense_c, *eig, *work, *vec;
} fem_psd;

/* 0, or -1 with err (out of memory, LAPACK failure). */
int fem_psd_project(fem_psd *p, size_t b, const int *nodes, const double *K, const double *C,
                    nc_error *err);
void fem_psd_free(fem_psd *p);

#endif
