/* dem_compliance — a coupled step solved with the structure's compliance at the nodes the
 * rock touches (the structure's side of a two-sided interface Jacobian;
 * docs/notes/interface_jacobian.md "The structure's compliance in the DEM").
 *
 * Contract: the coupler sends, with a SOLVE, the structure's compliance S = du/dF over some
 * interface nodes N (3|N| x 3|N|, m/N, from the FEM's last solve of the same Δt) and the
 * force F_ref the structure balanced at the received end-of-step displacement u_in. The
 * step is then solved for the force F on N with
 *     F = F_dem(u_e),   u_e = u_in + S (F - F_ref) on N (u_in elsewhere),
 * F_dem the step-averaged force of dem_sim_solve_coupled_jacobian: the wall ends where the
 * structure, linearised, would put it under the force the particles give it. Newton's method
 * with the step's own K (J = I + K_NN S), each evaluation a full coupled step from the
 * restored start-of-step state; a step that goes past the root along its direction (a
 * contact gained) brackets it and searches it, the bracket's point with the mismatch along
 * the direction gone the next base (twice at most even when |F - F_dem| is larger there),
 * one that makes |F - F_dem| grow without that is halved (dem_compliance.c); at most
 * DEM_COMPLIANCE_MAX_EVALUATIONS evaluations, the last of them back at the best one when the
 * search ended elsewhere. A search that stops short
 * returns its best evaluation, still an exact evaluation of the step at the u_e it reports,
 * which is all the coupler uses. The particles end as that evaluation left them (the wall at
 * u_e). Returned: force_out = F_dem(u_e), jac = K at u_e and wall_end_disp = u_e: the
 * coupler takes u_e as the iteration's interface position (the DEM chose where its wall
 * ends; the structure's answer is compared with that).
 * Without compliance nodes it is dem_sim_solve_coupled_jacobian.
 */
#ifndef DEM_COMPLIANCE_H
#define DEM_COMPLIANCE_H

#include <stddef.h>
#include <stdint.h>

#include "dem_coupling.h"
#include "dem_net_jacobian.h"
#include "nc_error.h"

/* Most searches take 1-7. A rock sliding through a net, its contacts changing from sub-step
 * to sub-step, needs more: on angled_net at restitution 0.1 and 5x its step, 34 of 136
 * searches stopped unsolved at 12 (0.006-790 N of mismatch left), and their coupling
 * iterations stalled; with 60, 12 of 140 reach the limit and the others take up to 50
 * (docs/notes/interface_jacobian.md items 11 and 12). */
#define DEM_COMPLIANCE_MAX_EVALUATIONS 60
/* a step halved below this share of Newton's without lowering the mismatch becomes the base
 * all the same */
#define DEM_COMPLIANCE_SMALLEST_STEP 0.1
/* past the root along a Newton direction: a point of the bracket that leaves at most this
 * share of the base's mismatch along it (and a smaller mismatch) is the next base */
#define DEM_COMPLIANCE_SHARE_LEFT 0.25
/* ... and with a larger mismatch, at most this many times in one solve (a contact the
 * base's K did not have; docs/notes/interface_jacobian.md item 9) */
#define DEM_COMPLIANCE_UPHILL_BASES 2
/* |F - F_dem| below this times the largest nodal force (or 1e-3 N): solved */
#define DEM_COMPLIANCE_TOLERANCE 1e-9

typedef struct dem_compliance {
    size_t n_nodes;             /* |N| */
    const int32_t *nodes;       /* [n_nodes] interface node indices */
    const double *S;            /* [3 n_nodes x 3 n_nodes] row-major, m/N */
    const double *force_ref;    /* [3 n] over all interface nodes, N */
} dem_compliance;

typedef struct dem_compliance_stats {
    int evaluations;            /* coupled steps run */
    double first_mismatch_n;    /* |F - F_dem| of the first one (N) */
    double last_mismatch_n;     /* ... and of the one returned (above the tolerance: not solved) */
} dem_compliance_stats;

int dem_sim_solve_with_compliance(dem_sim *s, double dt_step, const double *disp_end,
                                  const double *vel_end, const dem_compliance *cmp,
                                  double *force_out, double *wall_end_disp,
                                  dem_coupled_info *info, dem_net_jacobian *jac,
                                  dem_compliance_stats *st, nc_error *err);

#endif
