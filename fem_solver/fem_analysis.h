/* fem_analysis — the nonlinear solver: assembly, Newton-Raphson, static load increments,
 * implicit dynamics (Newmark, generalized-alpha, Bossak) and start-of-step save/restore.
 *
 * Contract: fem_analysis_init() builds the equation numbering (supported dofs are eliminated,
 * so the pattern never changes), the sparse pattern and CHOLMOD's symbolic analysis once.
 * fem_analysis_settle() (static equilibrium by pseudo-time steps) allocates nothing;
 * on failure it leaves the last pseudo step's state, at its own time and step.
 * fem_analysis_static() and fem_analysis_step() allocate nothing; on Newton failure they leave
 * the state as it was before the call and return -1 with a message naming step/time,
 * iterations and residual. The extra nodal force f_coupling (N, per dof) is added to the
 * model's own loads; the coupled driver fills it from the protocol's `force` array.
 * With analysis.coupling_load "step_constant" (default "end_of_step") f_coupling acts over the whole
 * step: the start-of-step acceleration is shifted by M^-1 (f_coupling - the force it was
 * computed with), so the step transfers exactly f_coupling dt of momentum to the structure,
 * the impulse the DEM gave its particles over the same step.
 * An interface linearisation (fem_analysis_set_linearisation) makes the coupling force a
 * function of the solution, F(u, v) = f_coupling - K (u - u^k) - C (v - v^k), solved
 * implicitly; without one everything is as described above.
 */
#ifndef FEM_ANALYSIS_H
#define FEM_ANALYSIS_H

#include <signal.h>

#include "fem_gmres.h"
#include "fem_interface_jacobian.h"
#include "fem_model.h"
#include "fem_sparse.h"

/* nc_error code of a step whose Newton iterations did not converge (a smaller step may). */
#define FEM_ERR_NEWTON 3
/* fem_analysis_settle stopped by its watch's stop flag (a signal) */
#define FEM_ERR_STOPPED 4

typedef struct fem_state {
    double time_s;
    long step;
    double *u, *v, *a;  /* [ndof] displacement (m), velocity (m/s), acceleration (m/s^2) */
    double *fd;         /* [ndof] F_int(u) + C_K v at this state (alpha methods) */
    double *fc;         /* [ndof] coupling force the acceleration a was computed with (N);
                           with a linearisation, F(u, v) at this state */
    int n_history;      /* = model history_count */
    double *element_history; /* [n_history] the element types' history (brake stroke and
                           dissipated energy, ...; fem_element.h), committed at this state:
                           saved, restored and rolled back with u, v, a */
} fem_state;

typedef struct fem_stats {
    int iterations;            /* Newton iterations of the last solve */
    double residual_norm;      /* final residual 2-norm (N) */
    double increment_norm;     /* last increment max-norm (m) */
    int slack_elements;        /* slack cables at the solution */
    long assemblies, factorizations, lu_factorizations, solves, line_search_cuts;
    long pattern_growths;  /* times an interface linearisation added node pairs to the pattern */
    long pcg_solves, pcg_iterations, pcg_failures;
    long gmres_solves, gmres_iterations, gmres_failures; /* Newton steps with the skew part
                                  of an interface linearisation (fem_gmres.h) */
    long ldlt_switch_step;     /* step at which an indefinite matrix turned the "auto"
                                  factorisation to LDL^T (-1: never) */
    long roundoff_converged;   /* solves ended at the rounding floor above the tolerance
                                  (within FEM_ROUNDOFF_TOL_FACTOR of it, or within the
                                  rounding of the interface linearisation's K (u - u^k)) */
    double assembly_s, factor_s, solve_s;  /* accumulated wall time */
} fem_stats;

/* Who watches fem_analysis_settle (all members may be NULL): on_step after each pseudo step
 * (its number from 1, its size h_s, the largest nodal move in it and that node), stop: ends
 * the settling with FEM_ERR_STOPPED when it turns non-zero (a signal). A large barrier takes
 * a minute or more to settle: the caller shows progress and can be stopped. */
typedef struct fem_settle_watch {
    void (*on_step)(void *ctx, int step, double h_s, double move_m, int node);
    void *ctx;
    const volatile sig_atomic_t *stop;
} fem_settle_watch;

typedef struct fem_analysis {
    const fem_model *m;
    int ndof, neq;
    int *eq;               /* [ndof] equation of each dof, -1 for supported dofs */
    int *dof_of_eq;        /* [neq] */
    int *slot;             /* [36 n_elements] element entry -> matrix value slot */
    fem_sparse K;
    fem_state cur;         /* current (last solved or accepted) state */
    fem_state start;       /* start of the step being solved (for failure rollback) */
    fem_state saved;       /* explicit save (BEGIN_STEP) */
    int has_saved;
    double *f_model;       /* [ndof] point loads + self-weight at full load (N) */
    double *f_coupling;    /* [ndof] extra external force (N) */
    double *r;             /* [ndof] residual */
    double *rhs, *du, *u0; /* [neq] right-hand side, increment, iterate before the step */
    double *w;             /* [ndof] mass-term vector (a_alpha + tau v_alpha) */
    double *cg_r, *cg_z, *cg_p, *cg_q; /* [neq] conjugate-gradient work vectors */
    double *axial;         /* [n_elements] axial force N (N) at the current state */
    double *mass_diag;     /* [neq] diagonal of M on the free equations (Jacobi preconditioner) */
    double *mass_x, *mass_y; /* [ndof] mass-matrix product work vectors */
    double *a_unshifted;   /* [ndof] start-of-step acceleration before the load shift */
    int n_chain_pairs;     /* pattern pseudo-elements of chain members' non-neighbour nodes */
    /* The rank-one terms of chain members' tangents (fem_element.h chain_rank_one), kept out
     * of the factorised matrix: rank-one member r (lr_of_member[b] = r, else -1) has the
     * equations lr_eq[lr_at[r] .. lr_at[r + 1]) of its chain nodes (-1: supported), the
     * stiffness term lr_k[r] g g^T (g in lr_g, the tangent weight c_k included) and the
     * damping term lr_c[r] g_c g_c^T (g_c in lr_gc, frozen with C_K: lr_c_frozen[r] = kappa k,
     * times c_c), both of the last assembly with a matrix. lr_shift (same indexing as
     * lr_eq): what that assembly added to the matrix diagonal of an equation the term alone
     * holds (rank_one_shift in fem_analysis.c), taken back in the tangent's product. */
    int lr_members;
    int *lr_of_member, *lr_eq;
    size_t *lr_at;
    double *lr_g, *lr_gc, *lr_k, *lr_c, *lr_c_frozen, *lr_shift;
    double *chain_f, *chain_v, *chain_K; /* chain member work arrays (3n, 3n, 3n x 3n) */
    /* stiffness-proportional damping C_K = kappa K_T(u_n), frozen over each step (kappa != 0
     * only): per member from damping_K + damping_at[b] (3x3 for a pair element, 3n x 3n for a
     * chain); damping_start [ndof] the damping force the start acceleration stands for (the
     * previous step's C_K times v_n), damping_end [ndof] work space for C_K v_n+1 */
    double *damping_K, *damping_start, *damping_end;
    size_t *damping_at;    /* [n_members + 1] */
    double factor_cm, factor_ck;        /* c_m, c_k of the current factorisation */
    double saved_factor_cm, saved_factor_ck;
    double fixed_load_factor; /* >= 0: the load factor of every step (fem_analysis_settle),
                              else the one load_ramp_s gives the step's time */
    fem_settle_watch settle_watch; /* progress and stop of fem_analysis_settle (zero: none) */
    fem_ijac lin;          /* interface linearisation of the coupling force (lin.active) */
    fem_gmres gmres;       /* work space of the Newton steps with lin's skew part */
    double skew_lk, skew_lc; /* the tangent weights of lin during such a step */
    double last_lw, last_lk, last_lc, last_cm, last_ck; /* the step weights of the last
                              Newton solve (fem_analysis_compliance works at its solution) */
    double last_velocity_per_m; /* dv/du at the end of the last dynamic step: gamma/(beta dt) */
    long lin_serial;       /* counts set/clear calls: which linearisation a factor holds */
    int n_pairs, cap_pairs;/* node pairs in the pattern that share no element: added when a
                              linearisation couples them (a particle touching several
                              elements), so the pattern only grows */
    int *pairs;            /* [2 n_pairs] */
    long factor_lin, saved_factor_lin;
    int factor_mode;       /* the pattern's factorisation (fem_sparse_build's mode): the
                              model's, until an "auto" factor turns to LDL^T for good */
    fem_stats stats;
} fem_analysis;

int fem_analysis_init(fem_analysis *s, const fem_model *m, nc_error *err);
void fem_analysis_free(fem_analysis *s);

/* Static equilibrium under load factor lambda (loads and prescribed displacements scaled),
 * starting Newton from the current displacement. Velocity/acceleration are left at 0. */
int fem_analysis_static(fem_analysis *s, double lambda, nc_error *err);
/* Static equilibrium under load factor lambda by pseudo-transient continuation, from the
 * current state: implicit dynamic steps from rest (v = a = 0 before each) with a pseudo step
 * that doubles after each converged step (from analysis.dt_s) and is quartered after a
 * failed one, until a step of 1e4 s moves no node by more than displacement_tol_m. The mass
 * term keeps each step's matrix regular where a static Newton meets nodes held only by slack
 * cables. On success the state is at rest, its time and step as before the call;
 * *iterations, *steps: the Newton iterations and pseudo steps it took, failed ones included.
 * Needs a model with mass at every free dof a load moves. Its Newton iterations take a step
 * whose residual is up to 3 times the last (slack cables: a non-monotone line search, the
 * dynamic steps keep the monotone one). s->settle_watch sees each pseudo
 * step and can stop it (FEM_ERR_STOPPED; the time and step as before the call). */
int fem_analysis_settle(fem_analysis *s, double lambda, int *iterations, int *steps,
                        nc_error *err);
/* A dynamic run's start at rest in static equilibrium under its loads at t = 0 (self-weight,
 * point loads, prestress, prescribed displacements), from the current state
 * (analysis.initial_state "static"): fem_analysis_settle at the load factor of t = 0.
 * Call before fem_analysis_initial_acceleration, which then finds a_0 = 0 to the Newton
 * tolerance. */
int fem_analysis_initial_equilibrium(fem_analysis *s, int *iterations, int *steps,
                                     nc_error *err);
/* Sets a_0 from M a_0 = F_ext(t) - F_int(u) - C v (call once before dynamic steps). */
int fem_analysis_initial_acceleration(fem_analysis *s, nc_error *err);
/* One implicit dynamic step of dt_s from the current state. */
int fem_analysis_step(fem_analysis *s, double dt_s, nc_error *err);
/* The same with Newton started from u_guess [ndof] on the free dofs (NULL: from the
 * start-of-step displacement): a coupled step solved again with a corrected interface force
 * starts from its previous solution. */
int fem_analysis_step_from(fem_analysis *s, double dt_s, const double *u_guess, nc_error *err);
/* Load factor of the model loads at time t (load_ramp_s). */
double fem_analysis_load_factor(const fem_analysis *s, double time_s);

/* The structure's interface compliance at the last solved dynamic step: S = du/dF over the
 * n dofs `dofs` (full dof indices), the tangent of the step at its solution without the
 * interface linearisation (removed from the solved matrix by the Woodbury identity), times
 * the coupling force's weight in the step. S: [n x n] row-major; rows/columns of supported
 * dofs are zero. With S_rows (else NULL), also how the n_rows dofs row_dofs answer a force on
 * `dofs`: [n_rows x n] row-major, from the same solves. The matrix is factorised afresh (the
 * kept factorisation is then that one). */
int fem_analysis_compliance(fem_analysis *s, int n, const int *dofs, double *S, int n_rows,
                            const int *row_dofs, double *S_rows, nc_error *err);

/* Save/restore the state and the factorisation kept by modified Newton (fem_sparse.h), so
 * a step solved again after a restore repeats the same operations bit for bit. */
int fem_analysis_save(fem_analysis *s, nc_error *err);
int fem_analysis_restore(fem_analysis *s, nc_error *err);

/* Interface linearisation (interface-Jacobian coupling) for the following solves, until
 * cleared or set again: the coupling force becomes
 *   F(u, v) = F^k - K (u - u^k) - C (v - v^k),   F^k = f_coupling (filled as without it),
 * u_ref = u^k, v_ref = v^k: [ndof] full dof vectors (only the dofs of block columns are
 * read); blocks: n_blocks 3x3 blocks, block b couples block_nodes[2b] (force node i) to
 * block_nodes[2b+1] (motion node j), K_blocks/C_blocks [9 n_blocks] row-major (N/m, N s/m;
 * C_blocks NULL = 0); repeated (i, j) are summed. A pair (i, j) of nodes that share no
 * element is added to the matrix pattern (once; the factorisations then start afresh, also
 * the saved one); nodes outside the model are rejected with an error naming the block.
 * Everything is copied. Where F is evaluated:
 *  - dynamics (Newmark, generalized-alpha, Bossak): at the end-of-step state u_n+1, v_n+1
 *    and with full weight, exactly where f_coupling acts (F_ext at t_n+1 for every method),
 *    so the step tangent gains K + gamma/(beta dt) C. With coupling_load "step_constant"
 *    the start-of-step acceleration is shifted by F^k as before; the correction
 *    -K (u - u^k) - C (v - v^k) acts as an end-of-step load.
 *  - statics: F = F^k - K (u - u^k) (no velocity), tangent gains K.
 *  - initial acceleration: F(u_0, v_0) (the matrix is M).
 * At u = u^k, v = v^k (a converged coupling iteration) F = F^k, the plain result. The
 * matrix holds the symmetric part of K, C (the residual is exact). cur.fc holds F at the
 * solution. A skew part of K or C (an unsymmetric linearisation) stays in the residual and
 * enters each Newton step through GMRES preconditioned by the factorisation of the symmetric
 * matrix (fem_gmres.h), so Newton keeps its exact tangent. Returns 0, or -1 (err says why;
 * the linearisation is then cleared). */
int fem_analysis_set_linearisation(fem_analysis *s, const double *u_ref, const double *v_ref,
                                   int n_blocks, const int *block_nodes, const double *K_blocks,
                                   const double *C_blocks, nc_error *err);
/* Rebuilds the matrix pattern with exactly these extra node pairs [2 n_pairs] (those of a
 * checkpoint, in their order): the same pairs give the same pattern, the same ordering and
 * so the same factorisations. Every factorisation is dropped (fem_sparse_refactor). */
int fem_analysis_set_pattern_pairs(fem_analysis *s, int n_pairs, const int *pairs, nc_error *err);
/* Back to the plain coupling force f_coupling. */
void fem_analysis_clear_linearisation(fem_analysis *s);
/* Diagnostic (tangent checks): the residual of a dynamic step of dt_s from the current state
 * at the end-of-step displacement u_end [ndof] (supported dofs take their prescribed
 * values) into r [ndof] (meaningful on free dofs), leaving the step tangent (-dr/du on the
 * free equations) in s->K's values. The state is left as it was. */
int fem_analysis_step_residual(fem_analysis *s, double dt_s, const double *u_end, double *r,
                               nc_error *err);
/* y [neq] = the tangent of the last assembly times x [neq] on the free equations: the
 * matrix's values plus the rank-one terms kept out of it (sliding ropes); without the skew
 * part of an interface linearisation, which the matrix holds only symmetrically. */
void fem_analysis_tangent_apply(const fem_analysis *s, const double *x, double *y);

/* Recomputes s->axial and stats.slack_elements at the current state. */
void fem_analysis_update_axial(fem_analysis *s);
/* The force balance of every dof at the current state into f [ndof] (N):
 *   f = F_int(u) + C_K v + M (a + tau v) - lambda f_model - f_coupling,
 * C_K = kappa K_T(u_n) of the last step (see fem_analysis.c),
 * which is what a support takes on a prescribed dof (0 on free dofs at equilibrium). */
void fem_analysis_node_balance(const fem_analysis *s, double lambda, double *f);
/* Per element (mesh segment) at the current committed history: the member's stroke (m;
 * brake: plastic stroke) into stroke and its dissipated energy (J) into dissipated, 0 for
 * types without (either pointer may be NULL). Returns 1 when the model has such types. */
int fem_analysis_element_history_output(const fem_analysis *s, double *stroke, double *dissipated);
/* Total mechanical energy: kinetic (1/2 v^T M v) + strain energy of the elements. */
double fem_analysis_energy(const fem_analysis *s, double *kinetic, double *strain);

/* The energy balance of the step just solved, from `start` to `cur` (J):
 *   load_work     = 1/2 (lambda_n + lambda_n+1) f_model · Δu (self-weight, point loads);
 *   coupling_work = ((1 - gamma) fc_n + gamma fc_n+1) · Δu, the weights the velocity update
 *                   v_n+1 - v_n = dt ((1 - gamma) a_n + gamma a_n+1) gives the start and end
 *                   force (the trapezoid for Newmark); fc_n the coupling force the start-of-
 *                   step acceleration stands for (start.fc; f_coupling with "step_constant");
 *   rayleigh      = Δt v_m^T tau M v_m, v_m = (v_n + v_n+1) / 2, + ((1 - gamma) fk_n + gamma
 *                   C_K v_n+1) · Δu, C_K = kappa K_T(u_n) of the step and fk_n the damping
 *                   force a_n stands for (the previous step's C_K v_n);
 *   element_dissipation = Δ of the energy the elements dissipate (a brake's plastic work,
 *                   fem_element.h), from the history at the start and the end;
 *   numerical     = load_work + coupling_work - Δ(kinetic + strain) - rayleigh
 *                   - element_dissipation, the balance.
 * Work sums run over the free dofs (reactions of prescribed displacements are left out).
 * For Newmark beta = 1/4, gamma = 1/2 on a linear system every term is exact and numerical
 * vanishes to round-off (the trapezoidal rule conserves the discrete energy); the alpha
 * methods' (and the geometric nonlinearity's) energy error shows up in numerical, and for
 * them the split between coupling_work and numerical is a convention.
 * load_potential = -lambda_n+1 f_model · u_n+1; load_input = load_work + Δ load_potential,
 * the work of the loads beyond their potential (0 for constant loads; a ramp's share).
 * inertia = 0 (quasi-static coupling): no kinetic energy, no Rayleigh term, load factor 1
 * (the caller keeps cur.fc = f_coupling).
 * Returns -1 when no step was solved (cur.time_s <= start.time_s). */
typedef struct fem_step_energy {
    double kinetic_j, strain_j, load_potential_j;   /* at the end of the step */
    double load_work_j, load_input_j, coupling_work_j, rayleigh_j, numerical_j;   /* of the step */
    double element_dissipation_j;   /* of the step: plastic work of the elements (brakes) */
    double element_dissipated_j;    /* the elements' dissipated energy up to the end of the step */
} fem_step_energy;
int fem_analysis_step_energy(const fem_analysis *s, int inertia, fem_step_energy *e);

#endif
