/* fem_element — the seam between the solver and its element types: one table of operations
 * per type (fem_element_<type>.c), found through the registry in fem_element.c.
 *
 * A model's elements (fem_model.conn) are 2-node segments: they are the mesh cells written to
 * the output and exchanged with the coupler. A *member* is what a type's operations work on:
 * one segment for a two-node type (cable, post, brake, ring), or a run of consecutive
 * segments of the same set, each starting at the previous one's end node, for a chain type
 * (sliding cable: one rope through all its nodes). fem_model_finalize() builds the members.
 *
 * Contract of every type:
 *  - forces and tangent are functions of the current displacement u and the member's
 *    *committed* history (the start of the step); they never write history;
 *  - commit() writes the history at a converged state (called once per accepted solve);
 *    the solver keeps all history in one array, fem_state.element_history, so the start-of-
 *    step save/restore and any checkpoint cover it with the state;
 *  - strain_energy() is the recoverable energy of the member (above its reference state)
 *    and dissipated() the energy it has turned into heat up to its committed history; the
 *    work done on a member equals the change of the two (the solver's energy balance);
 *  - mass is the bar mass rho A L0 of each segment (consistent or lumped, eq. (11)).
 */
#ifndef FEM_ELEMENT_H
#define FEM_ELEMENT_H

#include "nc_error.h"

#include <stdio.h>

struct cJSON;
struct fem_model;
struct fem_element_set;

/* What a type's operation sees of one member. */
typedef struct fem_element_ctx {
    const struct fem_model *m;
    const struct fem_element_set *set;
    const double *param;     /* the set's type parameters (fem_set_type.param) */
    int member;              /* member index */
    int first, count;        /* its segments: model elements first .. first + count - 1 */
    const double *u;         /* [3 n_nodes] displacement (m) */
    const double *hist;      /* this member's committed history (NULL when it has none) */
    /* chain_response of a type with chain_rank_one, K wanted: the caller reads only the
     * blocks of neighbouring chain nodes, and they are to hold K_near (the rank-one term left
     * out); the other blocks may hold anything. 0: the whole K. */
    int near_blocks_only;
} fem_element_ctx;

typedef struct fem_element_ops {
    const char *name;        /* the element set's "type" in fem.json */
    int chain;               /* 1: a member is a run of segments; 0: one segment */
    int uses_section;        /* 1: youngs_modulus_pa and the area are required */
    int history_count;       /* doubles of history per member */
    const char *const *keys; /* extra fem.json keys of the set (NULL-terminated), or NULL */
    /* Reads the type's keys into param[FEM_ELEMENT_PARAMS] (and checks them); NULL: no
     * keys of its own. */
    int (*parse)(const struct cJSON *o, const char *where, FILE *warnings, double *param,
                 nc_error *err);
    /* Checks a member of the built model against the set's parameters (c->u and c->hist are
     * NULL: the reference state); NULL: nothing to check. */
    int (*check)(const fem_element_ctx *c, nc_error *err);
    /* Two-node types: force on node l f_l[3] (node k gets -f_l), 3x3 block Kb[9] of the
     * tangent [Kb -Kb; -Kb Kb]; returns the axial force (N); *slack = 1 when it carries
     * nothing. */
    double (*pair_response)(const fem_element_ctx *c, double f_l[3], double Kb[9], int *slack);
    /* Chain types (n = count + 1 nodes, in chain order): internal force f[3n] and tangent
     * K[3n x 3n] (row-major; K may be NULL), the axial force of each segment in axial[count];
     * returns 1 when the member carries no axial force (slack; a sliding rope's shackle
     * contact may still push). */
    int (*chain_response)(const fem_element_ctx *c, double *f, double *K, double *axial);
    /* Chain types whose tangent couples nodes beyond their neighbours only through one
     * rank-one term: K = K_near + k g g^T, K_near coupling each node with itself and its
     * neighbours in the chain. Returns k (N/m; 0 when the term is absent, e.g. slack) and
     * g[3n]. The solver keeps k g g^T out of the factorised matrix (a dense block over the
     * whole member would fill the factor) and adds it in its Krylov iterations
     * (fem_analysis.c). NULL: the member's tangent may couple any two of its nodes, and they
     * all get a place in the matrix. */
    double (*chain_rank_one)(const fem_element_ctx *c, double *g);
    double (*strain_energy)(const fem_element_ctx *c);
    /* History at the converged state u from the committed c->hist into hist_new. */
    void (*commit)(const fem_element_ctx *c, double *hist_new);
    /* Energy dissipated up to the committed history (J); NULL: 0. */
    double (*dissipated)(const fem_element_ctx *c);
    /* Stroke of the member (m) at the committed history (brake: plastic stroke); NULL: 0. */
    double (*stroke)(const fem_element_ctx *c);
} fem_element_ops;

#define FEM_ELEMENT_PARAMS 8   /* per-set parameters of a type (fem_set_type.param) */

/* The registry: type index (fem_set_type.type) -> operations; NULL past the end. */
const fem_element_ops *fem_element_type(int type);
/* Index of the type named `name`, or -1. */
int fem_element_find(const char *name);
/* "cable", "post", ... for messages: the names joined by sep into buf. */
const char *fem_element_names(char *buf, size_t size, const char *sep);

/* Registered types (indices are positions in the registry table). */
#define FEM_TYPE_CABLE 0

/* Bar mass coefficients of eq. (11), shared by every type: *m11 (node with itself) and *m12
 * (node with the other end) of a segment with rho A and L0. */
void fem_element_bar_mass(double rhoA, double L0, int lumped, double *m11, double *m12);

#endif
