/* dem_integrate — symplectic Euler for rigid bodies (eqs. (16), (17)): velocity first, then
 * position; free spheres rotate with a scalar inertia, clusters carry their angular momentum
 * in the world frame and a unit quaternion. Also the rigid-body kinematics of the spheres.
 */
#ifndef DEM_INTEGRATE_H
#define DEM_INTEGRATE_H

#include "dem_sim.h"

/* Advances every body by dt: sums its spheres' contact forces and torques (about the centre
 * of mass) into s->model.bod.force/torque, integrates with gravity, moves its spheres and records
 * the largest sphere displacement since the neighbour list was built (s->nlist.max_disp2). One
 * parallel loop over bodies (a single barrier per step). */
void dem_integrate_bodies(dem_sim *s, double dt);
/* Exact ballistic motion over dt without contacts: x += v dt + ½ g dt², v += g dt; clusters
 * turn torque-free with rot_substeps quaternion steps. Moves the spheres. */
void dem_free_flight(dem_sim *s, double dt, long rot_substeps);
/* Sphere centres and velocities from their bodies. */
void dem_update_spheres(dem_sim *s);

/* Quaternion functions (w, x, y, z). */
void dem_quat_rotate(const double q[4], const double v[3], double out[3]);
void dem_quat_to_matrix(const double q[4], double r[9]);
/* ω = R I⁻¹ Rᵀ L for a cluster. */
void dem_cluster_omega(const double q[4], const double inv_inertia_body[9], const double L[3],
                       double omega[3]);

#endif
