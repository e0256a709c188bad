/* dem_net_proximity — the net nodes a particle in contact with the net may reach within the
 * next coupling step, named in the Jacobian by zero blocks (the "proximity" of a SOLVE,
 * protocol/README.md §3.4; docs/notes/interface_jacobian.md item 9).
 *
 * Why: the coupler asks the structure for its compliance at the nodes of the DEM's Jacobian,
 * and the DEM solves its next step with that compliance (dem_compliance.h). A node the rock
 * reaches only in that step is then held where the coupler put it, and the DEM's model of
 * the structure misses the node's give: on terrain_curtain at 5x its step the DEM answered
 * 17-53 kN with the newly touched nodes held, and the next iteration 70-250 kN.
 *
 * Contract: for every sphere of a body that has a net contact in the records of the last
 * solve (jac->rec), every net edge whose closest point to the sphere's centre (at the end of
 * the step) lies within its reach (radius + cable radius) plus
 * DEM_PROXIMITY_STEPS (|v_sphere| + max |v_node|) dt_s names its two nodes (v_node: the
 * edge's nodes' wall velocity over the step). Each named node that is in no block of jac
 * yet gets a zero block (i, i) appended, at most max_nodes of them, the nearest to a
 * particle's surface first (a cap on the compliance's size: the DEM's search works on a dense
 * matrix of 3 rows per node, the FEM solves 3 times per node), in the order found when all
 * fit. Nothing else changes: the blocks already there, their order, the force. With no net
 * contact in the records nothing is added (a free flight's first touch is the kinematic
 * guess's, as without compliance).
 * *added (may be NULL): the blocks appended. Cost: one pass over the edges per sphere of a
 * body in contact. Returns 0, or -1 when out of memory (err).
 */
#ifndef DEM_NET_PROXIMITY_H
#define DEM_NET_PROXIMITY_H

#include <stddef.h>

#include "dem_net_jacobian.h"
#include "dem_sim.h"
#include "nc_error.h"

/* the relative travel covered, in coupling steps: the next step's, with a step's margin */
#define DEM_PROXIMITY_STEPS 2.0
/* the nodes a solve names at most (terrain_curtain at 5x its step: about 30) */
#define DEM_PROXIMITY_MAX_NODES 256

int dem_net_jacobian_add_proximity(const dem_sim *s, dem_net_jacobian *jac, double dt_s,
                                   size_t max_nodes, size_t *added, nc_error *err);

#endif
