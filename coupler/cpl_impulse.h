/* cpl_impulse — the interface's momentum balance: what the particles' contact forces gave the
 * structure against what the structure solved with.
 *
 * With the interface Jacobian the FEM solves with the DEM's force F plus its linearisation
 * about the DEM's input, F − K (u_out − u_in) − C (u̇_out − u̇_in) (coupler/README.md
 * "Interface Jacobian"), while the particles felt F alone. The difference is momentum the
 * interface lost (or made): over an accepted step
 *   missed = Σ_nodes [K (u_out − u_in) + C (u̇_out − u̇_in)] Δt      (N s, a vector)
 * against what the particles gave, given = Σ_nodes F Δt. A converged strong step has
 * u_out ≈ u_in, so its share is of the order of the tolerance. A weak step is one exchange:
 * where the contact is stiff against the structure's nodes (a heavy rock on a light net) the
 * structure moves away from the rock's input position within the step and the linearisation
 * takes back most of the force: the rock bounces off a net that hardly deflects, the contact
 * damping dissipates what the net should have taken, and the energy guard, which looks for
 * energy created, sees none.
 *
 * The guard fires when, at the end of the run, |Σ missed| > tol_rel · Σ |given| over the
 * accepted steps (Σ |given|: the sum of each step's |Σ_nodes F| Δt, so that impulses in
 * opposite directions do not cancel in the scale) and Σ |given| is above tol_abs_ns. The step
 * after which the sums first crossed the limit is kept, to say from when.
 */
#ifndef CPL_IMPULSE_H
#define CPL_IMPULSE_H

#include <stddef.h>

typedef struct cpl_impulse_settings {
    double tol_rel;      /* share of the interface impulse the structure may miss (0.05) */
    double tol_abs_ns;   /* no verdict below this interface impulse, N s (1e-6) */
} cpl_impulse_settings;

typedef struct cpl_impulse {
    cpl_impulse_settings s;
    double given_ns[3];      /* Σ over the accepted steps of Σ_nodes F Δt */
    double given_abs_ns;     /* Σ over the accepted steps of |Σ_nodes F Δt| */
    double missed_ns[3];     /* Σ over the accepted steps of Σ_nodes correction Δt */
    long first_step;         /* the first accepted step after which the sums were above the
                                limit, -1: none */
    double first_time_s;     /* its end time */
} cpl_impulse;

void cpl_impulse_settings_default(cpl_impulse_settings *s);
void cpl_impulse_init(cpl_impulse *m, const cpl_impulse_settings *s);
/* One accepted step of length dt_s ending at end_time_s: force (3 n_nodes, the DEM's
 * step-averaged nodal forces on the structure) and correction (the same layout: what the
 * structure's force differed by, K (u_out − u_in) + C (u̇_out − u̇_in); NULL: none, the
 * plain exchange or no FEM solve). */
void cpl_impulse_step(cpl_impulse *m, long step, double end_time_s, double dt_s,
                      const double *force, const double *correction, size_t n_nodes);
/* |Σ missed| / Σ |given| (0 before any interface impulse). */
double cpl_impulse_missed_share(const cpl_impulse *m);
/* The share the run would have with one more step as cpl_impulse_step takes it (0 while the
 * sums stay without interface impulse); *own (may be NULL): that step's own share,
 * |Σ_nodes correction| / |Σ_nodes force| (0 when both are zero, INFINITY with no force). */
double cpl_impulse_share_after(const cpl_impulse *m, double dt_s, const double *force,
                               const double *correction, size_t n_nodes, double *own);
/* 1 when the sums are above the limit now (the verdict at the end of a run). */
int cpl_impulse_fired(const cpl_impulse *m);

#endif
