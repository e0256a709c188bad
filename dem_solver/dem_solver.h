/* dem_solver — the DEM simulation object and its time stepping.
 *
 * Contract: dem_sim_init() zeroes a dem_sim; dem_config_load() (dem_config.h) or the
 * dem_sim_add_* functions fill it; dem_sim_prepare() checks it (no initial overlaps), computes
 * masses, damping ratios and the time step and allocates all step storage. After that,
 * dem_sim_step() advances by one explicit step without allocating (except rare capacity growth
 * of the contact list). For coupling: dem_sim_set_interface() builds the net wall from the
 * interface mesh, dem_sim_begin_step()/dem_sim_restore() save and restore the complete state,
 * dem_sim_solve_coupled() sub-steps through one coupling step and returns time-averaged nodal
 * forces. Results are deterministic: the same state and input give bit-identical results for
 * any number of OpenMP threads.
 */
#ifndef DEM_SOLVER_H
#define DEM_SOLVER_H

#include "dem_model.h"
#include "dem_neighbor_grid.h"
#include "nc_error.h"

/* Saved state of a coupling step (everything that evolves). */
typedef struct dem_snapshot {
    int valid;
    double time_s;
    long step;
    double *body_pos, *body_vel, *body_omega, *body_angmom, *body_quat;
    double *sph_pos, *sph_vel;
    dem_contacts contacts;
    int32_t *contact_first;
    double *net_cur, *net_vel;
    size_t net_nodes;      /* allocated size of net_cur / net_vel */
} dem_snapshot;

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
    double r_max, r_min;
} dem_model;

typedef struct dem_contact_state {
    dem_contacts list, prev;
    int32_t *first, *prev_first;
    struct dem_pair *wall_pairs;
} dem_contact_state;

typedef struct dem_thread_work {
    int n_buffers;
    dem_contacts *buffers;
    dem_spills *spills;
    int *overflow;
    size_t *range_first;
    uint8_t *shared_sphere;
} dem_thread_work;

typedef struct dem_neighbor_list {
    dem_cell_grid grid;
    double skin_m;
    int rebuild;
    int32_t *first;
    int32_t *nbr;
    size_t cap;
    struct dem_nbr_part {
        int32_t *a;
        size_t cap;
    } *part;
    double *pos_at_build;
    double max_disp2;
    long n_builds;
} dem_neighbor_list;

typedef struct dem_sim {
    dem_model model;
    dem_contact_state contact;
    dem_thread_work work;
    dem_neighbor_list nlist;
    int prepared;
    double time_s;
    long step;
    double *wall_force;
    size_t n_walls;
    dem_snapshot snap;
} dem_sim;

/* Result values of a coupled solve. */
typedef struct dem_coupled_info {
    int near_interface;   /* 1 if a particle is within net.near_distance_m of the net */
    double min_gap_m;     /* smallest particle surface – net distance (1e30 if none near) */
    long contacts;        /* particle–net contacts at the end of the step */
    long substeps;
} dem_coupled_info;

void dem_sim_init(dem_sim *s);
void dem_sim_free(dem_sim *s);

/* Adds a material; returns its index or -1. */
int dem_sim_add_material(dem_sim *s, const dem_material *m, nc_error *err);
/* Adds a free sphere (a body with one sphere). */
int dem_sim_add_sphere(dem_sim *s, const double pos[3], double radius, int material,
                       const double vel[3], const double omega[3], nc_error *err);
/* Adds a rigid cluster of n spheres (world positions at t = 0); mass, centre of mass and
 * inertia tensor are computed from the spheres (overlapping volume counted twice). */
int dem_sim_add_cluster(dem_sim *s, size_t n, const double *pos, const double *radius,
                        int material, const double vel[3], const double omega[3],
                        nc_error *err);
int dem_sim_add_plane(dem_sim *s, const double point[3], const double normal[3],
                      const double velocity[3], int material, nc_error *err);

/* Checks the model, derives masses/damping/time step, allocates step storage. */
int dem_sim_prepare(dem_sim *s, nc_error *err);
/* Critical time step estimate (s) and the step the solver would choose with dt "auto". */
double dem_sim_critical_dt(const dem_sim *s);

/* One explicit step of size dt with every wall at its current position. */
int dem_sim_step(dem_sim *s, double dt, nc_error *err);

/* Coupling: the interface mesh (n nodes, coords 3n reference positions, m edges 2m node
 * indices). Fails naming the bad entry. */
int dem_sim_set_interface(dem_sim *s, size_t n_nodes, const int32_t *node_ids,
                          const double *coords, size_t n_edges, const int32_t *edges,
                          nc_error *err);
/* Saves the start-of-step state (BEGIN_STEP). */
int dem_sim_begin_step(dem_sim *s, nc_error *err);
/* Restores the state saved by the last dem_sim_begin_step(). */
int dem_sim_restore(dem_sim *s, nc_error *err);
/* Runs one coupling step of length dt_step: the net moves linearly from its start-of-step
 * position to ref + disp_end (velocity (end - start) / dt_step), each sub-step seeing it at
 * the sub-step's end; force_out (3n) receives the time-averaged force of the particles on the
 * nodes (impulse / dt_step), or with net.force_at_end (net_wall.coupling_force
 * "end_of_step") the force of the last sub-step, wall at its end position. vel_end is checked and stored only. With prm.free_flight a step in
 * which nothing can touch is one exact ballistic step (info->substeps = 1). */
int dem_sim_solve_coupled(dem_sim *s, double dt_step, const double *disp_end,
                          const double *vel_end, double *force_out, dem_coupled_info *info,
                          nc_error *err);
/* Gap information with the net at its current position. */
void dem_sim_net_gap(const dem_sim *s, dem_coupled_info *info);

/* Diagnostics used by tests and output. */
double dem_sim_kinetic_energy(const dem_sim *s);
double dem_sim_potential_energy(const dem_sim *s); /* gravity, relative to the origin */

#endif
