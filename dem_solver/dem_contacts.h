/* dem_contacts — finding every contact of a step and computing its force.
 *
 * Per step: the previous contact list becomes the history, spheres are sorted into the cell
 * grid, and each thread handles a fixed contiguous range of spheres, finding their contacts
 * with higher-numbered spheres, planes, mesh features and net edges/nodes and computing the
 * forces with the history of the same contact key, summing them onto spheres as it goes (walls,
 * net nodes and spheres shared between ranges through per-thread lists summed afterwards in
 * range order). The per-thread contact lists are concatenated in range order and every force
 * sum runs in contact order, so results do not depend on the thread count. Mesh and net
 * features shared by several triangles/edges are counted once.
 */
#ifndef DEM_CONTACTS_H
#define DEM_CONTACTS_H

#include "dem_solver.h"

int dem_contacts_reserve(dem_contacts *c, size_t need, nc_error *err);
void dem_contacts_free(dem_contacts *c);
/* dst = src (dst grows as needed). */
int dem_contacts_copy(dem_contacts *dst, const dem_contacts *src, nc_error *err);

/* Tabulates the pair properties of every sphere material against every wall material (called
 * by dem_sim_prepare once the materials are complete). */
int dem_contacts_prepare(dem_sim *s, nc_error *err);

/* Finds contacts at the current positions, computes forces for step dt and sums them into
 * s->model.sph.force/torque (per sphere), s->model.net.force and s->wall_force. */
int dem_compute_contacts(dem_sim *s, double dt, nc_error *err);

/* Number of sphere pairs (of different bodies) whose surfaces are closer than `gap`. */
int dem_contacts_close_pairs(dem_sim *s, double gap, long *count, nc_error *err);

/* Energy stored in the contact springs of the current list (normal Hertz or linear spring plus
 * tangential spring |ft|²/(2 kt)), for energy balances. */
double dem_contacts_elastic_energy(const dem_sim *s);

#endif
