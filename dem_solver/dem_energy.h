/* dem_energy — the energy balance of a coupling step (dem_energy.c; the single energies are
 * declared in dem_sim.h).
 *
 * Over a coupling step from state 0 to state 1:
 *   E = kinetic + gravity potential (relative to the origin) + contact elastic energy;
 *   wall_work = the work the net wall did on the particles: the wall moves with the constant
 *       velocity (end - start) / dt over the step, so the sum over the sub-steps of
 *       -(nodal force on the net) · (nodal velocity) · h is -impulse · (end - start) / dt,
 *       exact for the forces the sub-steps applied (a contact point on an edge moves with the
 *       same interpolation that distributes its force to the nodes);
 *   dissipated = wall_work - (E1 - E0): the balance, so it holds the contact dashpots,
 *       friction and the DEM integrator's own energy error. Not tracked contact by contact.
 * Planes and meshes that move are not counted (no coupled case has one): with one, the
 * balance misses their work and `dissipated` absorbs it.
 */
#ifndef DEM_ENERGY_H
#define DEM_ENERGY_H

#include "dem_sim.h"

typedef struct dem_step_energy {
    double kinetic_j, gravity_j, contact_j;   /* at the end of the step */
    double wall_work_j;                       /* net wall on the particles, over the step */
    double dissipated_j;                      /* over the step (the balance) */
} dem_step_energy;

/* Kinetic + gravity potential + contact elastic energy of the current state. */
double dem_sim_mechanical_energy(const dem_sim *s);
/* The balance of the coupled step of length dt_step just solved (dem_sim_solve_coupled),
 * whose start state had the mechanical energy e_start_j. */
void dem_sim_step_energy(const dem_sim *s, double dt_step, double e_start_j, dem_step_energy *out);

#endif
