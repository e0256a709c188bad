/* cpl_compliance_line — points on the structure's linear answer at the interface.
 *
 * The FEM's compliance (cpl_compliance, protocol/README.md §3.4) says how the end-of-step
 * displacement of the structure answers a change dF of the interface force on the compliance
 * nodes N: S (3|N| x 3|N|) on N itself, S_interface (n3 x 3|N|) on every interface dof. With a
 * point (u, F) the structure balances, every (u + S_interface dF, F + dF) is one too, as far as
 * the structure is linear over the move. The coupler uses this to
 *  - move the interface nodes the DEM does not move (off N) with the DEM's answer, so that an
 *    iteration's residual measures what the linear model missed (cpl_compliance_answer);
 *  - begin the DEM's search at the point of the structure's answer under the last step's force
 *    nearest a kinematic guess of N's position (cpl_compliance_force_for).
 * Pure functions: no I/O, no state.
 */
#ifndef CPL_COMPLIANCE_LINE_H
#define CPL_COMPLIANCE_LINE_H

#include <stddef.h>
#include <stdint.h>

#include "cpl_loop.h"
#include "nc_error.h"

/* du [n3] = S_interface dF, dF [3|N|] in the order of c->nodes (N, direction). Needs
 * c->has_interface. */
void cpl_compliance_answer(const cpl_compliance *c, const double *dF, double *du);

/* dF [3|N|] with S dF = du_nodes [3|N|] on N, where a supported dof (a zero diagonal of S: the
 * structure does not move there) gets dF 0 and is left out of the system. 0, or -1 with err
 * when S is singular on the rest or memory runs out. */
int cpl_compliance_force_for(const cpl_compliance *c, const double *du_nodes, double *dF,
                             nc_error *err);

#endif
