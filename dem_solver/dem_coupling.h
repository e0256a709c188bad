/* dem_coupling — the DEM side of the partitioned coupling: the net wall, the saved state of a
 * coupling step and the sub-stepping through one coupling step.
 *
 * Contract: dem_sim_set_interface() builds the net wall from the FEM interface mesh (after
 * dem_sim_prepare); dem_sim_begin_step() saves everything that evolves and dem_sim_restore()
 * puts it back, so that a repeated coupling step (strong coupling) gives bit-identical results;
 * dem_sim_solve_coupled() moves the net linearly from its start-of-step position to the FEM's
 * end-of-step position over DEM sub-steps and returns the nodal forces of the particles on the
 * net. Algorithm 1's larger step: with prm.free_flight, a coupling step in which nothing can
 * touch is one exact ballistic step. dem_sim_solve_coupled_jacobian() (dem_net_jacobian.h) is
 * the same step that also returns the derivative of that force with respect to the received
 * end-of-step displacement.
 */
#ifndef DEM_COUPLING_H
#define DEM_COUPLING_H

#include <stddef.h>
#include <stdint.h>

#include "dem_contact_list.h"
#include "nc_error.h"

typedef struct dem_sim dem_sim;

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

/* Result values of a coupled solve. */
typedef struct dem_coupled_info {
    int near_interface;   /* 1 if a particle is within net.near_distance_m of the net */
    double min_gap_m;     /* smallest particle surface – net distance, exact up to
                           * near_distance_m (1e30 if none near) */
    long contacts;        /* particle–net contacts at the end of the step */
    long substeps;
} dem_coupled_info;

/* Allocates the body and sphere parts of a snapshot (the net part comes with the interface). */
int dem_snapshot_alloc(dem_snapshot *p, size_t n_bodies, size_t n_spheres, nc_error *err);
void dem_snapshot_free(dem_snapshot *p);

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
 * "end_of_step") the force of the last sub-step, wall at its end position. vel_end is checked
 * and stored only. With prm.free_flight a step in which nothing can touch is one exact
 * ballistic step (info->substeps = 1). */
int dem_sim_solve_coupled(dem_sim *s, double dt_step, const double *disp_end,
                          const double *vel_end, double *force_out, dem_coupled_info *info,
                          nc_error *err);
/* Gap information with the net at its current position. */
void dem_sim_net_gap(const dem_sim *s, dem_coupled_info *info);
/* A fresh run's start: an error naming the particle when a sphere lies deeper in the net than
 * DEM_START_NET_OVERLAP of its radius (a rock placed inside the net by mistake is thrown out
 * by a contact force of its whole overlap: the run creates gigajoules). Touching, and the
 * small overlap of a contact at rest, are allowed. */
#define DEM_START_NET_OVERLAP 0.05
int dem_sim_check_net_start(const dem_sim *s, nc_error *err);

#endif
