/* fem_model — the cable-net model the FEM solver works on: nodes, 2-node elements, element
 * properties, supports, loads, interface and monitor selections, analysis settings.
 *
 * A model is filled by fem_input.c (from fem.json) or by hand (tests, benchmarks), then
 * fem_model_finalize() checks it and derives the per-element arrays used by the hot loops
 * (reference length, E·A, A·S_pre, ρ·A, cable flag), the members the element types work on
 * (fem_element.h) with their history offsets, and the interface/monitor lists.
 * All arrays are flat (structure of arrays), node i has dofs 3i, 3i+1, 3i+2 (x, y, z).
 */
#ifndef FEM_MODEL_H
#define FEM_MODEL_H

#include "fem_element.h"
#include "nc_error.h"

#define FEM_NAME_MAX 64

typedef enum { FEM_CABLE = 0, FEM_TRUSS = 1 } fem_behaviour;
typedef enum { FEM_STATIC = 0, FEM_DYNAMIC = 1 } fem_analysis_type;
typedef enum { FEM_NEWMARK = 0, FEM_GENERALIZED_ALPHA = 1, FEM_BOSSAK = 2 } fem_integrator;

typedef struct fem_element_set {
    char name[FEM_NAME_MAX];
    double youngs_modulus_pa;   /* E */
    double area_m2;             /* A */
    double density_kg_m3;       /* rho */
    double prestress_pa;        /* S_pre (2nd Piola-Kirchhoff prestress) */
    fem_behaviour behaviour;    /* cable: no compression; truss: keeps compression */
    double breaking_load_n;     /* minimum breaking force, reported and checked (0: not given) */
} fem_element_set;

/* The element type of a set (fem_element.h), kept beside fem_element_set so sets built by
 * hand stay cables: zeroed = type 0, "cable". */
typedef struct fem_set_type {
    int type;                          /* registry index */
    double param[FEM_ELEMENT_PARAMS];  /* the type's own parameters (its parse operation) */
} fem_set_type;

typedef struct fem_node_set {
    char name[FEM_NAME_MAX];
    int count;
    int *nodes;
} fem_node_set;

typedef struct fem_settings {
    fem_analysis_type type;
    fem_integrator integrator;
    double beta, gamma;          /* Newmark parameters (derived for alpha methods) */
    double alpha_m, alpha_f;     /* generalized-alpha weights (0, 0 = Newmark) */
    double rho_inf;              /* spectral radius at infinity (generalized-alpha) */
    double alpha_b;              /* Bossak alpha (<= 0) */
    double dt_s, end_time_s;     /* dynamic step and end time */
    double load_ramp_s;          /* dynamic: loads ramp linearly from 0 over this time (0 = step) */
    int load_steps;              /* static: number of load increments */
    int initial_static;          /* dynamic: start at rest in static equilibrium under the
                                    loads at t = 0 (1), or at the reference state (0) */
    int max_iterations;          /* Newton iterations per step / load increment */
    double residual_tol_n;       /* absolute residual norm tolerance [N] */
    double relative_tol;         /* residual tolerance relative to the force scale */
    double displacement_tol_m;   /* max-norm of the last Newton increment [m] */
    int output_interval;         /* write full output every this many steps */
    int factorization;           /* 0 auto, 1 LDL^T (simplicial), 2 LL^T (supernodal) */
    int modified_newton;         /* 1: keep the factorisation while iterations contract */
    double contraction;          /* residual ratio below which a kept factorisation is fine */
    int coupling_load_constant;  /* 1: the coupling force acts over the whole step (its
                                    impulse is F dt); 0: it is a load at t_n+1 only */
    int fail_on_overload;        /* 1: an axial force above a set's breaking_load_n makes the
                                    program's exit status non-zero (it is always reported) */
} fem_settings;

typedef struct fem_model {
    char source[512];            /* input file name, for messages */

    int n_nodes;
    double *X;                   /* reference coordinates [3 n_nodes] (m) */
    int n_elements;
    int *conn;                   /* [2 n_elements] node indices */
    int *element_set;            /* [n_elements] index into sets */
    int n_sets;
    fem_element_set *sets;
    fem_set_type *set_types;     /* [n_sets] (fem_model_add_set zeroes: cable) */
    int n_node_sets;
    fem_node_set *node_sets;     /* named node sets ("boundary", gmsh physical groups, ...) */

    unsigned char *fixed;        /* [3 n_nodes] 1 = dof prescribed (support) */
    double *u_prescribed;        /* [3 n_nodes] prescribed value at full load (m) */
    double *f_point;             /* [3 n_nodes] point loads at full load (N) */
    int self_weight;             /* 1: element weights rho A L g are added */
    double gravity[3];           /* m/s^2 */
    double tau_per_s;            /* Rayleigh mass factor (C = tau M + kappa K) */
    double kappa_s;              /* Rayleigh stiffness factor */
    int lumped_mass;             /* 1 lumped, 0 consistent (eq. (11)) */

    int n_interface_sets;        /* interface element sets (0 = default: cable sets) */
    int *interface_sets;
    int n_monitor;
    int *monitor_nodes;
    fem_settings settings;

    /* derived by fem_model_finalize */
    double *L0;                  /* [n_elements] reference length */
    double *EA;                  /* E A */
    double *AS;                  /* A S_pre */
    double *rhoA;                /* rho A */
    unsigned char *is_cable;     /* cable behaviour (posts: 0) */
    /* members (fem_element.h): member b covers elements member_first[b] ..
     * member_first[b+1] - 1; a two-node type has one element per member, a chain type the
     * run of its set's consecutive elements that continue at the previous end node */
    int n_members;
    int *member_first;           /* [n_members + 1] */
    int *member_of;              /* [n_elements] member of each element */
    int max_chain_nodes;         /* nodes of the longest member */
    int history_count;           /* length of fem_state.element_history */
    int *history_offset;         /* [n_members] first history value of each member */
    int n_iface_nodes;
    int *iface_nodes;            /* model node index of each interface node */
    int n_iface_elements;
    int *iface_conn;             /* [2 n_iface_elements] indices into iface_nodes */
} fem_model;

void fem_settings_default(fem_settings *s);
/* Zeroes the model and sets defaults (gravity 0,0,-9.81; settings defaults). */
void fem_model_init(fem_model *m, const char *source);
/* Allocates node/element arrays (zeroed); one element set must be added by the caller. */
int fem_model_alloc(fem_model *m, int n_nodes, int n_elements, nc_error *err);
/* Adds an element set; returns its index or -1. */
int fem_model_add_set(fem_model *m, const fem_element_set *set, nc_error *err);
int fem_model_add_node_set(fem_model *m, const char *name, const int *nodes, int count,
                           nc_error *err);
const fem_node_set *fem_model_find_node_set(const fem_model *m, const char *name);
int fem_model_find_set(const fem_model *m, const char *name);
/* Fills a regular net: count1 x count2 nodes at origin + i/(count1-1) edge1 + j/(count2-1)
 * edge2 (node i + count1 j), elements along both directions, all in `set`; defines the node
 * sets boundary, corners, center (odd counts), edge1_start/end, edge2_start/end. */
int fem_model_generate_net(fem_model *m, const double origin[3], const double edge1[3],
                           const double edge2[3], int count1, int count2, int set,
                           nc_error *err);
/* Checks the model and derives per-element arrays, interface and monitor lists. */
int fem_model_finalize(fem_model *m, nc_error *err);
void fem_model_free(fem_model *m);

#endif
