/* cpl_test_models — in-process closed-form participants for the coupler unit tests.
 *
 * Structure ("FEM"): nd = 3 n dofs, diagonal masses m, dense stiffness K, backward Euler:
 *   (M + Δt² K) u1 = M (u0 + Δt v0) + Δt² F,  v1 = (u1 − u0) / Δt.
 * Particles ("DEM"): one particle per dof, mass mp, bilateral linear contact spring kc to the
 * wall, body acceleration g, backward Euler with the wall at its end-of-step position w:
 *   (mp + Δt² kc) x1 = mp (x0 + Δt y0) + Δt² (kc w + mp g),  force on the wall kc (x1 − w).
 * Both restore their start-of-step state on every solve, like the real solvers, and report
 * their exact discrete energies (cpl_energy_report): backward Euler dissipates exactly
 *   structure: ½ Δv·M Δv + ½ Δu·K Δu, interface work F·Δu, kinetic ½ v·M v, elastic ½ u·K u;
 *   particles: ½ mp Δy² + ½ kc Δs² (s = x − w, the spring's stretch), interface work
 *   −kc s1 Δw (the wall's work on the particles, Δw from the wall of the last accepted step to
 *   this one), kinetic ½ mp y², elastic ½ kc s², potential −mp g x;
 * so each side's balance closes to round-off (with the stiff window the spring energy jumps
 * where kc changes). The
 * structure refuses SOLVE and ACCEPT_STEP outside a begun step, like the serve loop.
 * Step rejection tests: either can fail a solve with CPL_ERR_STEP_FAILED while its step
 * [t, t + Δt) overlaps a time window and Δt is above a limit (tm_fail_window), and the
 * particles' contact can be stiffer inside a window (stiff_*), which makes the unrelaxed
 * iteration diverge there at a large Δt.
 * The monolithic reference solves both together with the same scheme (2 nd unknowns).
 * Gauss–Seidel fixed-point derivative per dof (K diagonal): J = −Δt² kc mp /
 * ((m + Δt² k)(mp + Δt² kc)); unrelaxed iteration converges iff |J| < 1.
 */
#ifndef CPL_TEST_MODELS_H
#define CPL_TEST_MODELS_H

#include <stddef.h>
#include "../../coupler/cpl_loop.h"

/* Solves of a step overlapping [from_s, until_s) with Δt > dt_above_s fail (retryable). */
typedef struct tm_fail_window {
    double from_s, until_s, dt_above_s;   /* dt_above_s = INFINITY: never */
    long failures;
} tm_fail_window;

typedef struct tm_structure {
    size_t nd;
    double *m, *K;            /* [nd], [nd × nd] row-major */
    double *u0, *v0, *u, *v;  /* start of step, current */
    long solves, begins, accepts;
    long fail_step;           /* reply an error at this step/iteration (-1: never) */
    int fail_iteration;
    double dt_seen_max;       /* largest Δt received */
    tm_fail_window fail;
    int open;                 /* BEGIN_STEP done, ACCEPT_STEP not yet */
    const char *checkpoint_dir;   /* checkpoint/resume to files here (NULL: cannot) */
    long checkpoints, resumes;
} tm_structure;

typedef struct tm_particles {
    size_t nd;
    double *mp, *kc, *g;
    double *x0, *y0, *x, *y;
    double *w0, *w;           /* wall at the start of the step (last accepted input), current */
    long solves;
    double far_until_s;       /* report near_interface = 0 while t + Δt < this */
    long fail_step;
    int fail_iteration;
    tm_fail_window fail;
    double stiff_from_s, stiff_until_s, stiff_factor;   /* kc × factor in the window */
    const char *checkpoint_dir;   /* checkpoint/resume to files here (NULL: cannot) */
    long checkpoints, resumes;
} tm_particles;

void tm_structure_init(tm_structure *s, size_t n_nodes, double m, double k, double k_link);
void tm_structure_free(tm_structure *s);
void tm_particles_init(tm_particles *p, size_t n_nodes, double mp, double kc, double g);
void tm_particles_free(tm_particles *p);

/* The cpl_participant wrappers. */
/* A coupled test problem: structure nodes, node mass, spring, link spring; particle mass,
 * contact stiffness, gravity (the arguments of tm_structure_init / tm_particles_init). */
typedef struct tm_problem {
    size_t nodes;
    double m, k, k_link, mp, kc, g;
} tm_problem;
/* Mild coupling: |J| ≈ 0.1 at Δt = 0.01 s. */
extern const tm_problem TM_MILD;
/* Light net, heavy rock, stiff contact: |J| ≈ 45 at Δt = 0.01 s (added-mass-like). */
extern const tm_problem TM_HARD;

/* Loop settings of the unit tests: default settings with the scheme, step and end time, an
 * absolute tolerance of 1e-10 and at most 200 iterations per step. */
cpl_loop_settings tm_loop_settings(cpl_scheme scheme, double dt, double end);

/* With checkpoint_dir set, the participants can checkpoint and resume: their committed
 * state (and the failure counter of the window) goes to <dir>/fem_<name>.bin, dem_<name>.bin
 * and comes back bit for bit; like the serve loop they refuse a checkpoint inside a begun
 * step. */
cpl_participant tm_structure_participant(tm_structure *s);
cpl_participant tm_particles_participant(tm_particles *p);

/* One monolithic backward-Euler step [t, t + Δt] of the coupled system (updates both
 * committed states; the stiff window applies as in the particle participant). */
void tm_monolithic_step(tm_structure *s, tm_particles *p, double t, double dt);

/* Whether the step [t, t + Δt) overlaps [from, until). */
int tm_overlaps(double t, double dt, double from, double until);

/* Dense Gaussian elimination with partial pivoting: solves A x = b (A, b overwritten). */
int tm_solve_dense(double *A, double *b, size_t n);

/* Observer collecting iterations per step. */
typedef struct tm_recorder {
    long steps;
    int iterations[4096];
    double residual[4096];
    int converged[4096];
    double time[4096];
    double force_z[4096];
    double dt[4096];
    int rejected[4096];           /* /steps/rejected of each step */
    long rejections;              /* on_reject calls */
    cpl_reject_record reject[64]; /* the first ones (message not kept) */
    double step0_residual[512];   /* residual of each iteration of step 0 */
    long total_iterations;
    int last_iteration_count;
} tm_recorder;
cpl_observer tm_recorder_observer(tm_recorder *r);

#endif
