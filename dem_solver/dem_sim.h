/* dem_sim — the DEM simulation object: its parts, building it, preparing it, stepping it.
 *
 * Contract: dem_sim_init() zeroes a dem_sim and sets the default parameters;
 * dem_config_load() (dem_config.h) or the dem_sim_add_* functions fill its model;
 * dem_sim_prepare() (dem_prepare.c) checks it (no initial overlaps), computes masses, damping
 * ratios and the time step and allocates all step storage. After that, dem_sim_step() advances
 * by one explicit step without allocating (except rare capacity growth of the contact list).
 * Coupling (the net wall, save/restore, sub-stepping) is in dem_coupling.h, energies for
 * balances in dem_energy.c. Results are deterministic: the same state and input give
 * bit-identical results for any number of OpenMP threads.
 *
 * A dem_sim is made of named parts, each owned by one module: the model (dem_model.h), the
 * contact state (dem_contact_list.h), the per-thread work buffers of the contact pass
 * (dem_contact_pass.h), the Verlet neighbour list (dem_neighbor_list.h) and the snapshot of a
 * coupling step (dem_coupling.h).
 */
#ifndef DEM_SIM_H
#define DEM_SIM_H

#include "dem_contact_list.h"
#include "dem_contact_pass.h"
#include "dem_coupling.h"
#include "dem_model.h"
#include "dem_neighbor_list.h"
#include "nc_error.h"

/* Loops over fewer items than this run on one thread, outside any OpenMP region: a region
 * costs more than such a loop, even one that its if() clause keeps on one thread (libgomp
 * still starts and ends a team: a few µs and futex calls, thousands per coupling step of a
 * small model; without them rest_position's coupler wall time is 17 % shorter). */
#define DEM_PARALLEL_MIN 512
/* Most OpenMP threads (contact buffers) a simulation uses. */
#define DEM_MAX_BUFFERS 256

struct dem_sim {
    dem_model model;
    dem_contact_state contact;
    dem_thread_work work;
    dem_neighbor_list nlist;
    dem_snapshot snap;
    int prepared;
    double time_s;
    long step;
    double *wall_force;            /* 3 per wall: planes, then meshes, then the net: force on
                                      the wall in the last step (N) */
    size_t n_walls;
};

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
/* Gives cluster `body` its true mass properties instead of the spheres' sum (applied by
 * dem_sim_prepare): mass_kg > 0 and either com and inertia (about com, in the world frame at
 * t = 0, which is the body frame; checked by dem_inertia_check) or both NULL (mass only: the
 * spheres' centre of mass, their inertia scaled by mass_kg / their mass). Setting a body again
 * replaces its values. Free spheres are refused (their mass is radius and density). */
int dem_sim_set_cluster_mass(dem_sim *s, size_t body, double mass_kg, const double com[3],
                             const double inertia[9], nc_error *err);
/* Checks an inertia tensor (row-major 3×3): finite, symmetric to 1e-9 of its largest entry,
 * positive definite (smallest principal moment > 1e-9 of the largest) and physical (each
 * principal moment at most the sum of the other two). principal (may be NULL) gets the
 * principal moments in ascending order. The message names no field; callers prefix it. */
int dem_inertia_check(const double inertia[9], double principal[3], nc_error *err);
int dem_sim_add_plane(dem_sim *s, const double point[3], const double normal[3],
                      const double velocity[3], int material, nc_error *err);

/* Checks the model, derives masses/damping/time step, allocates step storage. */
int dem_sim_prepare(dem_sim *s, nc_error *err);
/* Critical time step estimate (s) and the step the solver would choose with dt "auto". */
double dem_sim_critical_dt(const dem_sim *s);

/* One explicit step of size dt with every wall at its current position. */
int dem_sim_step(dem_sim *s, double dt, nc_error *err);
/* The two halves of dem_sim_step(): the walls placed and the contact pass (forces, contact
 * list), then the integration of the bodies. Between them the particles are still at the
 * state the forces were computed from (the interface Jacobian records it there). */
int dem_sim_step_forces(dem_sim *s, double dt, nc_error *err);
void dem_sim_step_advance(dem_sim *s, double dt);

/* Diagnostics used by tests and output (dem_energy.c). */
double dem_sim_kinetic_energy(const dem_sim *s);
double dem_sim_potential_energy(const dem_sim *s); /* gravity, relative to the origin */
/* Energy stored in the contact springs of the current list (normal Hertz or linear spring plus
 * tangential spring |ft|²/(2 kt)), for energy balances. */
double dem_sim_contact_energy(const dem_sim *s);

#endif
