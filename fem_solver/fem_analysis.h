/* fem_analysis — the nonlinear solver: assembly, Newton-Raphson, static load increments,
 * implicit dynamics (Newmark, generalized-alpha, Bossak) and start-of-step save/restore.
 *
 * Contract: fem_analysis_init() builds the equation numbering (supported dofs are eliminated,
 * so the pattern never changes), the sparse pattern and CHOLMOD's symbolic analysis once.
 * fem_analysis_static() and fem_analysis_step() allocate nothing; on Newton failure they leave
 * the state as it was before the call and return -1 with a message naming step/time,
 * iterations and residual. The extra nodal force f_coupling (N, per dof) is added to the
 * model's own loads; the coupled driver fills it from the protocol's `force` array.
 * With analysis.coupling_load "step_constant" (default "end_of_step") f_coupling acts over the whole
 * step: the start-of-step acceleration is shifted by M^-1 (f_coupling - the force it was
 * computed with), so the step transfers exactly f_coupling dt of momentum to the structure,
 * the impulse the DEM gave its particles over the same step.
 */
#ifndef FEM_ANALYSIS_H
#define FEM_ANALYSIS_H

#include "fem_model.h"
#include "fem_sparse.h"

typedef struct fem_state {
    double time_s;
    long step;
    double *u, *v, *a;  /* [ndof] displacement (m), velocity (m/s), acceleration (m/s^2) */
    double *fd;         /* [ndof] F_int(u) + kappa K_T(u) v at this state (alpha methods) */
    double *fc;         /* [ndof] coupling force the acceleration a was computed with (N) */
} fem_state;

typedef struct fem_stats {
    int iterations;            /* Newton iterations of the last solve */
    double residual_norm;      /* final residual 2-norm (N) */
    double increment_norm;     /* last increment max-norm (m) */
    int slack_elements;        /* slack cables at the solution */
    long assemblies, factorizations, lu_factorizations, solves, line_search_cuts;
    long pcg_solves, pcg_iterations, pcg_failures;
    double assembly_s, factor_s, solve_s;  /* accumulated wall time */
} fem_stats;

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
    double factor_cm, factor_ck;        /* c_m, c_k of the current factorisation */
    double saved_factor_cm, saved_factor_ck;
    fem_stats stats;
} fem_analysis;

int fem_analysis_init(fem_analysis *s, const fem_model *m, nc_error *err);
void fem_analysis_free(fem_analysis *s);

/* Static equilibrium under load factor lambda (loads and prescribed displacements scaled),
 * starting Newton from the current displacement. Velocity/acceleration are left at 0. */
int fem_analysis_static(fem_analysis *s, double lambda, nc_error *err);
/* Sets a_0 from M a_0 = F_ext(t) - F_int(u) - C v (call once before dynamic steps). */
int fem_analysis_initial_acceleration(fem_analysis *s, nc_error *err);
/* One implicit dynamic step of dt_s from the current state. */
int fem_analysis_step(fem_analysis *s, double dt_s, nc_error *err);
/* Load factor of the model loads at time t (load_ramp_s). */
double fem_analysis_load_factor(const fem_analysis *s, double time_s);

/* Save/restore the state and the factorisation kept by modified Newton (fem_sparse.h), so
 * a step solved again after a restore repeats the same operations bit for bit. */
int fem_analysis_save(fem_analysis *s, nc_error *err);
int fem_analysis_restore(fem_analysis *s, nc_error *err);

/* Recomputes s->axial and stats.slack_elements at the current state. */
void fem_analysis_update_axial(fem_analysis *s);
/* Total mechanical energy: kinetic (1/2 v^T M v) + strain energy of the elements. */
double fem_analysis_energy(const fem_analysis *s, double *kinetic, double *strain);

#endif
