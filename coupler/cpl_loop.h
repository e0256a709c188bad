/* cpl_loop — the coupling loops of the paper, written against an abstract participant
 * interface so they run with in-process test participants or with remote ones.
 *
 *   weak   (algorithms 1, 5): per step one exchange: DEM solve with the current interface
 *          u, u̇ -> forces -> FEM solve -> u, u̇ -> accept.
 *   strong (algorithms 2, 3, 6, 7): per step Gauss–Seidel iterations k = 1, 2, ...; the
 *          solvers restore their start-of-step state for k > 1; residual, eqs. (28)–(30),
 *          r = max(r_u, r_u̇), eq. (35), or r_F, eq. (36), convergence, eq. (27),
 *          relaxation, eqs. (31)–(34), of u, u̇ (algorithm 2) or of F (algorithm 3); then
 *          ACCEPT_STEP.
 * Efficiency options of algorithm 1: a larger step while the DEM reports no particle near
 * the interface; no FEM solve while the contact force is zero (only valid when the
 * structure is otherwise unloaded and at rest). With that option the FEM's step begins at its
 * first SOLVE of the step: a skipped step sends it nothing (no BEGIN_STEP / ACCEPT_STEP), and
 * its next BEGIN_STEP carries the later time.
 * Always: an iteration whose FEM input (the DEM's force, without a linearisation) equals that
 * of the FEM's last solve in the try is not sent to the FEM; its last answer stands (the
 * protocol's same input, same reply), counted in cpl_timing.fem_repeats_skipped.
 * Step rejection: a strong step that does not converge in max_iterations (or whose iteration
 * diverges, or, with reject_slow, cannot converge in time at its recent rate: CPL_SLOW_*), or
 * in which a participant's solve fails with CPL_ERR_STEP_FAILED, is rejected:
 * the relaxation history is dropped and the step is begun again at the same start time
 * (the participants restore their start-of-step state on the repeated BEGIN_STEP) with the
 * largest Δt·2^-k below the rejected step, as long as that is >= dt_min. After grow_after
 * converged steps in a row (and on the grid of the larger step) a reduced Δt doubles again,
 * never above the nominal Δt. At dt_min a step that still does not converge is accepted or
 * stops the run (on_max_iterations); a failed solve there ends the run.
 * Contact backtracking (contact_backtracking > 0, strong, relaxed u, u̇): an iterate whose
 * DEM answer lost the contact of the last iterate with contact, whose linearisation still
 * predicted force there (or after the try's contact-free answer was seen to collide), is
 * moved back along the step towards that one to where the lost contact's force meets the
 * prediction (cpl_contact_search.h), with at most contact_backtracking more DEM solves
 * (docs/notes/contact_backtracking.md).
 * Convergence with the interface Jacobian also needs the impulse guard's share, with the step
 * accepted, or the step's own share within half of impulse_tolerance (force_mismatch in
 * cpl_loop.c).
 * Jacobian check (jacobian_check > 0, strong, with the Jacobian): on every such step each
 * iteration's linearisation is compared with two more DEM solves of the step along the step
 * the iteration took (cpl_jacobian_check.h); the DEM's own solve of the next iteration comes
 * after them, so the results are the same as without the check.
 * Energy balance: every accepted step feeds the energies both participants reported with
 * their last solve to the energy guard (cpl_energy.h); its record goes with the step record.
 * Impulse balance: every accepted step adds the DEM's interface impulse and, with the
 * interface Jacobian, what the structure's linearised force differed by (cpl_impulse.h).
 * The loop itself never prints: it reports every iteration, rejection and step to an
 * observer.
 */
#ifndef CPL_LOOP_H
#define CPL_LOOP_H

#include <signal.h>
#include <stddef.h>
#include <stdint.h>
#include "cpl_checkpoint.h"
#include "cpl_energy.h"
#include "cpl_impulse.h"
#include "cpl_jacobian_check.h"
#include "cpl_relax.h"
#include "nc_error.h"

/* An interface linearisation of the DEM's force (interface-Jacobian coupling): 3x3 blocks
 * between interface nodes, block b maps the motion of node nodes[2b+1] to the force on node
 * nodes[2b] (row-major), protocol/README.md §3.1. */
typedef struct cpl_jacobian {
    size_t n_blocks, capacity;
    int32_t *nodes;         /* [2 n_blocks] (force node, motion node) */
    double *stiffness;      /* [9 n_blocks] K = -dF/du, N/m */
    double *damping;        /* [9 n_blocks] C = -dF/du̇, N s/m (valid when has_damping) */
    int has_damping;
} cpl_jacobian;

/* Copies n blocks into j (damping may be NULL: C = 0); 0 or -1 (out of memory). */
int cpl_jacobian_set(cpl_jacobian *j, size_t n, const int32_t *nodes, const double *stiffness,
                     const double *damping, nc_error *err);
void cpl_jacobian_free(cpl_jacobian *j);
/* out = −(K du + C dv) (n × 3 each; C only when j has damping): the change of the force the
 * linearisation predicts for a change (du, dv) of the interface motion. */
void cpl_jacobian_apply(const cpl_jacobian *j, const double *du, const double *dv, size_t n3,
                        double *out);

/* The structure's interface compliance S = du/dF over the interface nodes its last
 * linearisation touched, as the FEM returned it (protocol/README.md §3.4), the force the
 * structure balanced at the DEM's next input, and where the DEM's wall then ended. */
typedef struct cpl_compliance {
    size_t n_nodes, cap;
    int32_t *nodes;         /* [n_nodes] interface indices */
    double *S;              /* [3 n_nodes x 3 n_nodes] m/N */
    size_t n3;              /* interface dofs (set with force_ref) */
    double *S_interface;    /* [n3 x 3 n_nodes] m/N: how every interface dof answers forces
                               on the nodes, when has_interface */
    int has_interface;
    double dt_s;            /* the step it belongs to */
    double velocity_per_m;  /* the structure's dv/du at the step's end (gamma / (beta dt)) */
    int valid;
    double *force_ref;      /* [n3] */
    double *u_wall;         /* [n3] where the DEM's wall ended in the last DEM solve */
    int wall_valid;
} cpl_compliance;

/* Room for n_nodes nodes (kept when there is; S_interface for c->n3 dofs), n_nodes set; 0 or
 * -1 (out of memory). */
int cpl_compliance_reserve(cpl_compliance *c, size_t n_nodes, nc_error *err);

/* What a participant is asked to do: step, iteration (1-based; 0 outside solve), the
 * start time and size of the step; with interface-Jacobian coupling, what to linearise. */
typedef struct cpl_call {
    long step;
    int iteration;
    double time_s;
    double dt_s;
    cpl_jacobian *jacobian_out;         /* DEM solve: fill with the linearisation of the
                                           returned force (NULL: not wanted) */
    const cpl_jacobian *jacobian_in;    /* FEM solve: solve with the force linearised about
                                           jacobian_u, jacobian_v (NULL: constant force) */
    const double *jacobian_u, *jacobian_v;   /* n × 3: where the DEM evaluated the force */
    cpl_compliance *compliance_out;          /* FEM solve: fill with its compliance; DEM
                                                solve: with where its wall ended (NULL: not
                                                used) */
    const cpl_compliance *compliance_in;     /* DEM solve: solve with it (NULL: not used) */
    int proximity;                           /* DEM solve with jacobian_out: name also the
                                                nodes a particle in contact may reach in the
                                                next step (zero blocks; compliance_proximity,
                                                set per iteration while the try solves with
                                                the compliance) */
} cpl_call;

/* Extra information a participant returns with a solve. */
typedef struct cpl_solve_info {
    int near_interface;     /* DEM: 1 if a particle is near the interface (1 when unknown) */
    double min_gap_m;       /* DEM: smallest particle-interface gap (INFINITY when unknown) */
    double contacts;        /* DEM: number of contacts at the end of the step */
    double solver_time_s;   /* time the participant spent computing, NAN when not reported */
    cpl_energy_report energy;   /* its energies (cpl_energy.h); valid = 0 when not reported */
    double jacobian_dropped;    /* DEM: particles its linearisation left out (0 when unknown) */
} cpl_solve_info;

/* The commands the loop may send to both participants at once (cpl_participant.post). */
typedef enum { CPL_COMMAND_BEGIN_STEP = 0, CPL_COMMAND_ACCEPT_STEP } cpl_command;

/* A participant: `ctx` is passed back to every function; all return 0 / -1 (+ err). */
typedef struct cpl_participant {
    const char *name;       /* "fem", "dem": used in messages */
    void *ctx;
    int (*begin_step)(void *ctx, const cpl_call *call, nc_error *err);
    /* FEM: in0 = force -> out0 = displacement, out1 = velocity.
     * DEM: in0 = displacement, in1 = velocity (end of step) -> out0 = force.
     * All n × 3; out1/in1 unused are NULL. The FEM may leave info untouched. */
    int (*solve)(void *ctx, const cpl_call *call, const double *in0, const double *in1,
                 double *out0, double *out1, cpl_solve_info *info, nc_error *err);
    int (*accept)(void *ctx, const cpl_call *call, nc_error *err);
    int can_jacobian;       /* DEM: can return the linearisation; FEM: can solve with it */
    /* checkpoint/resume (protocol/README.md §3.3; NULL: the participant cannot): save the
     * complete state under `name` durably, between steps (call->step = steps accepted,
     * call->time_s = time reached); continue from the checkpoint `name` before the first
     * step. */
    int (*checkpoint)(void *ctx, const cpl_call *call, const char *name, nc_error *err);
    int (*resume)(void *ctx, const cpl_call *call, const char *name, nc_error *err);
    /* optional, both or neither: begin_step or accept in two halves, `post` sending the
     * command and `await` taking its answer, so that the loop sends it to both participants
     * before it waits for either and their round trips overlap. NULL: the loop calls
     * begin_step and accept. */
    int (*post)(void *ctx, cpl_command command, const cpl_call *call, nc_error *err);
    int (*await)(void *ctx, nc_error *err);
    int can_compliance;     /* FEM: can return its interface compliance; DEM: can solve with
                               it (capability "compliance", protocol/README.md §3.4) */
} cpl_participant;

typedef enum { CPL_SCHEME_WEAK = 0, CPL_SCHEME_STRONG } cpl_scheme;
typedef enum { CPL_RELAXED_DISPLACEMENT_VELOCITY = 0, CPL_RELAXED_FORCE } cpl_relaxed_quantity;
typedef enum { CPL_MAXIT_ACCEPT = 0, CPL_MAXIT_STOP } cpl_maxit_policy;
typedef enum { CPL_PREDICT_CONSTANT = 0, CPL_PREDICT_LINEAR, CPL_PREDICT_QUADRATIC } cpl_predictor;

typedef struct cpl_loop_settings {
    cpl_scheme scheme;
    double start_time_s;
    double end_time_s;
    double dt_s;                    /* nominal step */
    double tol_abs;                 /* ε of eq. (27) on the scaled residual norm */
    double tol_rel;                 /* optional relative tolerance (0 = off) */
    double work_tol;                /* displacement_velocity: r_u̇ may stay above tol_abs when
                                       the interface work mismatch the iterate would leave in
                                       the step (the DEM's force over its input motion against
                                       the linearised force the structure solved with over its
                                       answer; cpl_loop.c work_ratio) is at most work_tol x
                                       the input energy (0 = off: eq. (35)) */
    double newton_estimate;         /* displacement_velocity with the interface Jacobian: r_u̇
                                       may stay above tol_abs when the iterate's input was the
                                       FEM's previous answer (α = 1), the residual contracted
                                       by θ = r_u̇ / r_u̇_prev <= newton_estimate, and the error
                                       estimate of the FEM's answer θ / (1 − θ) r_u̇ meets the
                                       tolerance (0 = off) */
    int max_iterations;             /* per step (strong) */
    cpl_maxit_policy on_max_iterations;
    cpl_relaxed_quantity relaxed;
    cpl_relax_settings relax;
    cpl_predictor predictor;        /* first guess of the step's end-of-step u (quadratic) */
    int far_step;                   /* efficiency option (i): enlarge Δt when not near */
    double far_step_factor;         /* the paper used 100 */
    int skip_fem_without_contact;   /* efficiency option (ii) */
    double contact_force_threshold_n; /* |F| <= this counts as no contact force */
    long max_steps;                 /* stop after this many steps (0 = until end time) */
    double dt_min_s;                /* step rejection: smallest retry Δt (<= 0: dt_s / 64;
                                       >= dt_s: no retries) */
    int grow_after;                 /* converged steps in a row before a reduced Δt doubles */
    int reject_slow;                /* strong: reject a try early when at its recent rate it
                                       cannot reach the tolerance by max_iterations, if a
                                       smaller Δt is left (default 1; CPL_SLOW_* below) */
    cpl_energy_settings energy;     /* the energy guard (cpl_energy.h) */
    int stop_on_energy_growth;      /* 1: the run stops (CPL_ERR_ENERGY_GROWTH) at the first
                                       step at which the guard fires, once that step is
                                       accepted and recorded */
    cpl_impulse_settings impulse;   /* the interface's momentum balance (cpl_impulse.h) */
    int interface_jacobian;         /* use the DEM's linearisation in the FEM's solves when
                                       both participants can (default 1) */
    int interface_compliance;       /* with the interface Jacobian, also the structure's
                                       compliance in the DEM's solves when both can
                                       (default 0; docs/notes/interface_jacobian.md) */
    int structure_predictor;        /* with the compliance, a try after a step with
                                       contact begins with the structure's answer under the
                                       last step's force (default 1) */
    int compliance_proximity;       /* with the compliance, also at the nodes a particle in
                                       contact may reach within the next step (default 1) */
    int verify_restore;             /* strong: send each participant's first solve with a
                                       non-zero answer twice with the same input and require
                                       identical results (default 1) */
    int contact_backtracking;       /* strong: at most this many DEM solves back towards
                                       the last iterate with contact when an iterate loses
                                       it (0: off) */
    double checkpoint_interval_s;   /* simulated time between checkpoints (0: none); taken
                                       only when both participants can */
    int jacobian_check_interval;    /* strong, relaxed u, u̇, with the Jacobian: on every
                                       step whose index is a multiple of this, the
                                       linearisation of each iteration that is followed by
                                       another is checked against central differences of the
                                       DEM's step (cpl_jacobian_check.h; 2 extra DEM solves
                                       per check; 0: off) */
} cpl_loop_settings;

/* The early rejection of a slow try (reject_slow): from iteration CPL_SLOW_FIRST on, the
 * residual's rate over the last CPL_SLOW_WINDOW iterations (geometric mean, at most 1),
 * carried on to max_iterations, must bring it below CPL_SLOW_MARGIN times the tolerance.
 * The window spans three periods of the three-iteration cycles Aitken falls into on a rock
 * resting in a net (cases/terrain_net); the values come from replaying that case's recorded
 * iterations (docs/notes/interface_jacobian.md). */
#define CPL_SLOW_FIRST 12
#define CPL_SLOW_WINDOW 9
#define CPL_SLOW_MARGIN 10.0

/* dt_min of settings whose dt_min_s is unset: six halvings (coupler/README.md says why). */
#define CPL_DT_MIN_DIVISOR 64.0
double cpl_loop_settings_dt_min(const cpl_loop_settings *s);

void cpl_loop_settings_default(cpl_loop_settings *s);
/* 1 when interface_jacobian is on and the scheme can use it (not strong with relaxed forces). */
int cpl_loop_settings_jacobian_applies(const cpl_loop_settings *s);
/* Checks ranges and consistency; `where` names the source (e.g. "coupler.json"). */
int cpl_loop_settings_check(const cpl_loop_settings *s, const char *where, nc_error *err);

typedef struct cpl_iteration_record {
    long step;
    int iteration;
    double time_s, dt_s;
    double residual;                /* r of eq. (35) or (36) */
    double alpha;                   /* relaxation factor applied after it (NAN: none/QN) */
    double contact_force[3];        /* total force of the DEM on the net, N */
    int fem_solved;                 /* 0 when skipped by efficiency option (ii) */
    int attempt;                    /* 0 for a step's first try, n after n rejections */
    double jacobian_miss;           /* jacobian_check: the relative miss of the DEM's
                                       linearisation of this iteration along the step to the
                                       next input (NAN: not checked) */
    int compliance;                 /* 1: the DEM's solve that the iteration kept was against
                                       the structure's compliance (interface_compliance: it
                                       answered where its wall ended) */
} cpl_iteration_record;

typedef enum {
    CPL_REJECT_NOT_CONVERGED = 0,   /* max_iterations reached above the tolerance */
    CPL_REJECT_DIVERGED,            /* the relaxation produced a non-finite value */
    CPL_REJECT_STEP_FAILED,         /* a participant's solve failed with CPL_ERR_STEP_FAILED */
    CPL_REJECT_TOO_SLOW             /* reject_slow: it could not have converged in time */
} cpl_reject_reason;

/* A rejected try of a step; the step is begun again with next_dt_s. */
typedef struct cpl_reject_record {
    long step;
    int attempt;                    /* which try was rejected (0 = the first) */
    double time_s;                  /* start time of the step */
    double dt_s, next_dt_s;
    int iterations;
    double residual;                /* of the last iteration (NAN when none completed) */
    cpl_reject_reason reason;
    const char *message;            /* the failure for DIVERGED / STEP_FAILED, else "" */
} cpl_reject_record;

/* "not converged", "diverged", "solve failed", "converging too slowly". */
const char *cpl_reject_reason_text(cpl_reject_reason reason);

typedef struct cpl_step_record {
    long step;
    int jacobian_blocks;            /* blocks of the linearisation of the last iteration
                                       (-1: interface-Jacobian coupling not in use) */
    double time_s;                  /* end time of the step */
    double dt_s;
    int iterations;
    int converged;                  /* weak scheme: whether the single exchange was within
                                       the tolerance (information only) */
    double residual;                /* of the last iteration */
    double contact_force[3];
    int in_contact;                 /* any non-zero contact force */
    int near_interface;
    double min_gap_m;
    int rejected;                   /* tries of this step rejected before this one */
    cpl_energy_record energy;       /* the energy balance after this step */
    int jacobian_dropped;           /* most particles one DEM solve of the step left out of
                                       its linearisation (their contact reaches the FEM as
                                       a force only) */
} cpl_step_record;

/* Every function may be NULL. */
typedef struct cpl_observer {
    void *ctx;
    int (*on_iteration)(void *ctx, const cpl_iteration_record *rec, nc_error *err);
    int (*on_step)(void *ctx, const cpl_step_record *rec, nc_error *err);
    int (*on_reject)(void *ctx, const cpl_reject_record *rec, nc_error *err);
    /* both participants saved the checkpoint `name` after `step` steps at time_s: save the
     * coupler's own state now (cpl_loop_checkpoint_entries + the observer's own) */
    int (*on_checkpoint)(void *ctx, long step, double time_s, const char *name, nc_error *err);
} cpl_observer;

/* Wall-clock split of a run (seconds). wait_* include transport (a command posted to both
 * participants counts for the first awaited until its answer, for the second only beyond
 * that); solver_* are what the participants reported themselves (NAN when they did not). */
typedef struct cpl_timing {
    double total_s;
    double wait_fem_s, wait_dem_s;
    double solver_fem_s, solver_dem_s;
    long fem_solves, dem_solves, steps, iterations;
    long unconverged_steps;         /* strong: accepted without converging */
    long rejected_attempts;         /* tries rejected and begun again with a smaller Δt */
    long slow_rejections;           /* ... of them early, as converging too slowly */
    long reduced_steps;             /* accepted steps that needed at least one rejection */
    long backtracks;                /* DEM solves repeated by contact backtracking */
    long structure_predictions;     /* FEM solves of structure_predictor */
    long fem_repeats_skipped;       /* FEM solves not sent: the input was the one the FEM had
                                       just solved with in the same try (same force, no
                                       linearisation), so its answer is the one it gave */
    long work_test_steps;           /* accepted steps whose velocity residual was above the
                                       tolerance: converged by the work test (work_tolerance) */
    long estimate_steps;            /* ... converged by the error estimate (newton_estimate) */
    long jacobian_dropped_steps;    /* accepted steps with particles left out of the DEM's
                                       linearisation */
    long compliance_tries;          /* tries with the structure's compliance at the start
                                       (interface_compliance) ... */
    long compliance_dropped;        /* ... that went on without it after the DEM's search
                                       with it ended a contact the structure's
                                       linearisation still carried */
    double min_dt_s;                /* smallest Δt of an accepted step, not counting a last
                                       step shortened to end on end_time (INFINITY: none) */
} cpl_timing;

/* Where a failed run stopped. */
typedef struct cpl_failure {
    const cpl_participant *participant;   /* NULL: the coupler itself (or interrupted) */
    long step;
    int iteration;
    const char *command;                  /* "begin_step", "solve", "accept", "relax" */
} cpl_failure;

/* CPL_ERR_STEP_FAILED is for participants: "this step could not be solved (e.g. Newton
 * failure), it may succeed with a smaller Δt" -- the loop then rejects and retries the step.
 * Any other error code from a participant ends the run. */
enum { CPL_ERR_INTERRUPTED = 40, CPL_ERR_NOT_CONVERGED = 41, CPL_ERR_PARTICIPANT = 42,
       CPL_ERR_STEP_FAILED = 43, CPL_ERR_ENERGY_GROWTH = 44 };

typedef struct cpl_loop cpl_loop;

/* n_nodes interface nodes; the initial interface state (u0, v0 may be NULL for zero). */
int cpl_loop_create(cpl_loop **out, const cpl_loop_settings *s, size_t n_nodes,
                    const double *u0, const double *v0, nc_error *err);
void cpl_loop_free(cpl_loop *loop);

/* Runs from start to end time. `stop` (may be NULL) is polled between requests; when it
 * becomes non-zero the run ends with CPL_ERR_INTERRUPTED. On failure `failure` says where;
 * err names the participant, step, iteration and reason. */
int cpl_loop_run(cpl_loop *loop, const cpl_participant *fem, const cpl_participant *dem,
                 const cpl_observer *observer, const volatile sig_atomic_t *stop,
                 cpl_failure *failure, nc_error *err);

const cpl_timing *cpl_loop_timing(const cpl_loop *loop);
/* Accepted interface state (n × 3 each) after the last accepted step. */
const double *cpl_loop_displacement(const cpl_loop *loop);
const double *cpl_loop_velocity(const cpl_loop *loop);
const double *cpl_loop_force(const cpl_loop *loop);
double cpl_loop_time(const cpl_loop *loop);
/* The energy balance and guard of the accepted steps so far. */
const cpl_energy *cpl_loop_energy(const cpl_loop *loop);
const cpl_impulse *cpl_loop_impulse(const cpl_loop *loop);
/* Checkpoint/resume. After the ACCEPT_STEP of the step that reaches the next multiple of
 * checkpoint_interval_s (from the start time) and is not the last step, when both
 * participants have checkpoint/resume: CHECKPOINT "step_%06ld" (steps accepted) to both,
 * then observer->on_checkpoint. Checkpoints are off when a participant cannot (see
 * cpl_loop_checkpoints_on). */
int cpl_loop_checkpoints_on(const cpl_loop *loop, const cpl_participant *fem,
                            const cpl_participant *dem);
/* Adds everything the rest of the run depends on, bit for bit, to t: step, time, step
 * control, relaxation state (its method's own entries), predictor input (the accepted
 * u, u̇, F and the u and Δt of the step before), the interface Jacobian, the restore
 * verification, the energy balance, the counters of the summary, the next checkpoint time. Before loading, call
 * cpl_loop_checkpoint_prepare with the file: it checks the settings the checkpoint was
 * written with against the run's and reads the sizes that vary (the Jacobian's blocks). */
void cpl_loop_checkpoint_entries(cpl_loop *loop, cpl_ckpt_table *t);
int cpl_loop_checkpoint_prepare(cpl_loop *loop, const char *path, nc_error *err);
/* After the load: the node lists it held (the linearisation's, the compliance's) name
 * interface nodes, each once; 0, or -1 with err naming `path` and the list. */
int cpl_loop_checkpoint_loaded(const cpl_loop *loop, const char *path, nc_error *err);
/* The state was loaded from the checkpoint `name` (after cpl_loop_checkpoint_prepare, which
 * checked that the run has the settings the checkpoint was written with: dt, scheme,
 * relaxed quantity, tolerance, interface size, work_tolerance, relaxation method):
 * cpl_loop_run then first sends RESUME (step, time, name) to both participants and
 * continues. */
void cpl_loop_resumed(cpl_loop *loop, const char *name);
/* Steps accepted so far (the index of the next step). */
long cpl_loop_step(const cpl_loop *loop);

/* 1 when the run uses interface-Jacobian coupling (set by cpl_loop_run: the setting is on
 * and both participants can). */
int cpl_loop_uses_jacobian(const cpl_loop *loop);
/* 1 when the run gives the DEM the structure's compliance (interface_compliance, both can). */
int cpl_loop_uses_compliance(const cpl_loop *loop);
/* What jacobian_check found so far. */
const cpl_jacobian_check *cpl_loop_jacobian_check(const cpl_loop *loop);

#endif
