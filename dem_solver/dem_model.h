/* dem_model — the model of a DEM simulation: parameters, materials, spheres, rigid bodies and
 * walls (planes, STL meshes, the coupled net), and the storage functions of that data.
 *
 * Everything is flat structure-of-arrays storage in one dem_model, part of a dem_sim (dem_sim.h
 * has the functions that build and step it). Every sphere belongs to exactly one rigid body: a free sphere is
 * a body with one sphere at offset 0, a cluster is a body with several spheres whose body-frame
 * offsets are fixed. Vectors are stored as 3 consecutive doubles (x[3*i+0..2]).
 * Units: SI everywhere (m, s, kg, N, Pa).
 */
#ifndef DEM_MODEL_H
#define DEM_MODEL_H

#include <stddef.h>
#include <stdint.h>

#include "nc_error.h"

typedef enum { DEM_LAW_HERTZ_MINDLIN = 0, DEM_LAW_LINEAR = 1 } dem_law;
typedef enum { DEM_DAMPING_FIT = 0, DEM_DAMPING_A7 = 1, DEM_DAMPING_HUNT_CROSSLEY = 2 } dem_damping_formula;

typedef struct dem_material {
    char name[64];
    double youngs_modulus_pa;
    double poisson_ratio;
    double density_kg_m3;
    double restitution;   /* coefficient of restitution ε (eq. (A.6)) */
    double friction;      /* Coulomb friction coefficient μ */
    double shear_modulus_pa; /* G = E / (2 (1 + ν)) */
    double zeta;             /* damping ratio from ε by eq. (A.7) or eqs. (A.8)–(A.10) */
    double hunt_crossley;    /* Hunt–Crossley c(ε) = ξ v0 (dem_damping.h) */
    double pair_e_star;      /* E* and G* of a contact between two spheres of this material */
    double pair_g_star;
    double pair_kt_kn_root;  /* sqrt(kt / kn') of such a contact */
} dem_material;

/* Global parameters read from dem.json. */
typedef struct dem_params {
    double gravity[3];            /* m/s² */
    double dt_s;                  /* DEM time step actually used */
    int dt_auto;                  /* 1: dt_s from the critical step estimate */
    double dt_safety;             /* fraction of the critical step used when auto */
    double end_time_s;            /* standalone run length */
    double output_interval_s;     /* standalone output interval (0: every step) */
    dem_law law;
    dem_damping_formula damping;
    double linear_kn_n_per_m;     /* linear law: normal stiffness */
    double linear_kt_ratio;       /* linear law: kt = ratio * kn */
    int threads;                  /* OpenMP threads (0: library default) */
    int free_flight;              /* coupled: one ballistic step when nothing can touch */
} dem_params;

/* Spheres: the collision primitives. Spheres of a body are contiguous. */
typedef struct dem_spheres {
    size_t n, cap;
    int32_t *id;          /* user-visible id (0..n-1 unless given) */
    int32_t *body;        /* owning body */
    int32_t *material;    /* index into materials */
    double *radius;       /* m */
    double *offset;       /* 3n: centre in the body frame (0 for free spheres) */
    double *pos;          /* 3n: centre, world frame */
    double *vel;          /* 3n: centre velocity, world frame */
    double *force;        /* 3n: contact force summed per sphere (scratch of a step) */
    double *torque;       /* 3n: contact torque about the sphere centre (scratch) */
} dem_spheres;

/* Rigid bodies (free spheres and clusters). */
typedef struct dem_bodies {
    size_t n, cap;
    int32_t *first_sphere, *n_spheres;
    int32_t *is_cluster;
    double *mass, *inv_mass;
    double *inv_inertia_body; /* 9n: inverse inertia tensor in the body frame, row-major */
    double *inertia_body;     /* 9n */
    double *inv_inertia_iso;  /* n: 1/I of a free sphere (the diagonal of inv_inertia_body, kept
                                 compact for the integration loop); 0 for clusters */
    double *pos;              /* 3n: centre of mass */
    double *vel;              /* 3n */
    double *omega;            /* 3n: angular velocity, world frame */
    double *angmom;           /* 3n: angular momentum about the COM, world frame (clusters) */
    double *quat;             /* 4n: orientation (w, x, y, z), body -> world */
    double *force;            /* 3n: total contact force of the step (scratch) */
    double *torque;           /* 3n: total contact torque about the COM (scratch) */
} dem_bodies;

/* An infinite one-sided plane: particles live on the side the normal points to. */
typedef struct dem_plane {
    double point0[3];     /* point at t = 0 */
    double point[3];      /* current point = point0 + velocity t */
    double normal[3], velocity[3];
    int material;
} dem_plane;

struct dem_item_grid;

/* A rigid triangle mesh (STL), translating with a prescribed velocity. Vertices are welded so
 * that shared edges and vertices are single features (counted once). */
typedef struct dem_mesh {
    char path[512];
    size_t n_vertices, n_triangles, n_edges;
    double *vertices;      /* 3 per vertex, mesh frame (world at t = 0) */
    int32_t *tri;          /* 3 vertex indices per triangle */
    int32_t *tri_edges;    /* 3 edge indices per triangle: (v0,v1), (v1,v2), (v2,v0) */
    int32_t *edges;        /* 2 vertex indices per edge */
    double velocity[3];    /* m/s */
    double offset[3];      /* current translation = velocity * t */
    int material;
    struct dem_item_grid *grid; /* triangles in the mesh frame, built once */
} dem_mesh;

/* The coupled net wall: the FEM interface mesh of nodes and 2-node line elements. */
typedef struct dem_net {
    int active;
    size_t n_nodes, n_edges;
    int32_t *node_ids;     /* FEM ids (for output only) */
    int32_t *edges;        /* 2 node indices per edge */
    int32_t *strand;       /* 2 per edge: the rope each end belongs to at its node
                              (dem_net_strands.h), the key of a node contact */
    double *ref;           /* 3n reference coordinates */
    double *start;         /* 3n position at the start of the coupling step */
    double *end;           /* 3n position at the end of the step (from the FEM) */
    double *end_vel;       /* 3n FEM velocity at the end of the step */
    double *cur;           /* 3n current position during sub-steps */
    double *vel;           /* 3n current velocity used for contacts */
    double *force;         /* 3n nodal contact force of the current sub-step (on the net) */
    double *impulse;       /* 3n accumulated nodal force * dt over the step */
    /* wall material */
    double youngs_modulus_pa, poisson_ratio, friction, shear_modulus_pa;
    double restitution;    /* < 0: use the particle's damping */
    double zeta;
    double hunt_crossley;
    double cable_radius_m; /* contact when the centre is within R + cable radius */
    double near_distance_m;/* "near_interface" threshold on the surface gap */
    int force_at_end;      /* coupled reply: 0 the time-averaged force of the step (impulse/dt),
                              1 the force of the last sub-step (wall at its end position) */
    int wall_at_middle;    /* 1: in each sub-step the wall is where it is at the middle of the
                              sub-step; 0: at its end */
    double *box_lo, *box_hi; /* 3 per edge: each edge's box over the step's motion, as in
                                the grid (detection skips edges whose box is out of reach) */
    struct dem_item_grid *grid; /* the edges' boxes at their current position, or over the
                                   whole coupling step during its sub-steps (dem_coupling.c) */
} dem_net;

/* Mass properties given for a cluster (dem.json `mass_kg`, `center_of_mass`, `inertia_kg_m2`)
 * instead of the spheres' sum, which counts overlapping volume twice and cannot describe a
 * polyhedron that the spheres only approximate. */
typedef struct dem_mass_override {
    int32_t body;          /* a cluster body */
    int full;              /* 1: mass, centre and inertia given; 0: mass only (the spheres'
                              centre of mass, their inertia scaled by mass_kg / their mass) */
    double mass_kg;
    double com[3];         /* centre of mass, world frame at t = 0 (m) */
    double inertia[9];     /* about com, world frame at t = 0 = body frame, row-major (kg m²) */
} dem_mass_override;

/* The model: what dem_config_load() or the dem_sim_add_* builders fill in, completed by
 * dem_sim_prepare() (material shear moduli and damping ratios, body masses, r_max/r_min). */
typedef struct dem_model {
    char source[512];              /* input file name, for messages */
    dem_params prm;
    size_t n_materials;
    dem_material *materials;
    dem_spheres sph;
    dem_bodies bod;
    size_t n_planes;
    dem_plane *planes;
    size_t n_meshes;
    dem_mesh *meshes;
    dem_net net;
    double r_max, r_min;           /* largest and smallest sphere radius (m), from prepare */
    size_t n_mass_overrides;       /* given cluster mass properties, applied by prepare */
    dem_mass_override *mass_overrides;
} dem_model;

/* Default parameters and wall material (everything else zero). */
void dem_model_init(dem_model *m);
/* Frees everything the model owns and zeroes it. */
void dem_model_free(dem_model *m);
/* Grows the sphere / body arrays to hold at least `need` entries. */
int dem_model_reserve_spheres(dem_model *m, size_t need, nc_error *err);
int dem_model_reserve_bodies(dem_model *m, size_t need, nc_error *err);
/* Frees the net's arrays and grid and marks it inactive (the wall material stays). */
void dem_net_free(dem_net *n);

#endif
