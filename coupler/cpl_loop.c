/* cpl_loop — weak and strong coupling loops (algorithms 1–3 and 5–7 of the paper) with step
 * rejection and Δt control (cpl_loop.h). */
#include "cpl_loop.h"
#include "cpl_compliance_line.h"
#include "cpl_contact_search.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cpl_interface.h"
#include "cpl_residual.h"
#include "nc_clock.h"
#include "nc_json.h"

#define CPL_FINGERPRINT_N 11  /* dt, scheme, relaxed quantity, tolerance, interface size,
                                 work_tolerance, relaxation method, newton_estimate,
                                 interface_compliance, structure_predictor,
                                 compliance_proximity */

/* contact backtracking on a partial loss: the least share of the last iterate's resultant
 * that the nodes whose force ended must have carried (lost_contact) */
#define CPL_LOST_SHARE 0.25

struct cpl_loop {
    cpl_loop_settings s;
    size_t n3;              /* interface dofs per field: 3 × nodes */
    size_t nx;              /* length of the relaxed vector: 6n ([u; Δt·u̇]) or 3n (F) */
    cpl_relax *relax;
    double time_s;
    long step;
    int last_near;          /* DEM's near_interface of the last accepted step, -1 unknown */
    int level;              /* step control: the step is dt_s · 2^-level (0: nominal) */
    int converged_run;      /* converged steps in a row at the current level */
    double grid_origin_s;   /* where the level last left 0: reduced steps lie on its grid */
    double *u, *v, *f;      /* accepted state: u, u̇ at the start of the step, last force on
                               the structure */
    double *u_before;       /* u at the start of the last accepted step (quadratic predictor) */
    double dt_before_s;     /* that step's length; 0: no accepted step yet */
    double *u_in, *v_in;    /* DEM input of the current iteration */
    double *f_dem;          /* DEM output */
    double *f_in;           /* FEM input */
    double *u_out, *v_out;  /* FEM output */
    double *x_in, *x_out, *r;
    double *check0, *check1;    /* restore verification: the repeated solve's outputs */
    double *u_prev, *v_prev;    /* contact backtracking: the last iterate with contact, */
    double *f_prev, *f_pred;    /* its force and the one its linearisation predicted at the
                                   next iterate */
    double *u_end, *v_end;      /* ... and that next iterate, which lost the contact */
    unsigned char *lost;        /* per node: its contact ended between the two */
    unsigned char *on_compliance; /* per node, scratch of move_free_nodes: 0 between calls */
    double *du, *dv, *df;       /* a change of the interface motion and the force change the
                                   linearisation predicts for it (predicted_force,
                                   backtrack, jacobian_check) */
    double *lin_u, *lin_v;      /* jacobian_check: the iteration's DEM input (where the DEM
                                   linearised); the probes' inputs and forces */
    double *probe_u, *probe_v, *probe_plus, *probe_minus;
    cpl_jacobian_check jac_check;   /* what the checks found */
    int verified_fem, verified_dem;
    int use_jacobian;       /* interface-Jacobian coupling in this run */
    cpl_jacobian jac;       /* the DEM's linearisation of the current iteration */
    int use_compliance;     /* the structure's compliance in the DEM's solves in this run */
    cpl_compliance comp;    /* the FEM's last compliance, and where the DEM's wall ended */
    double *comp_u_lin, *comp_v_lin, *comp_f_lin; /* the linearisation point and force of
                                                     the FEM's last solve ... */
    cpl_jacobian comp_jac;  /* ... and its K, C: the structure's force at the DEM's next
                               input */
    cpl_jacobian predictor_jac; /* structure_predictor: zero blocks on the last one's nodes */
    double *v_answer;       /* the iteration's input velocity before the DEM moved its wall:
                               the last answer, when the input was that */
    cpl_timing timing;
    cpl_energy energy;
    cpl_impulse impulse;
    double *correction;     /* K (u_out − u_in) + C (v_out − v_in): what the structure's force
                               differs from the DEM's by (linearised_correction) */
    long next_checkpoint;   /* the next checkpoint is at start + this × interval */
    int resume_pending;     /* loaded from a checkpoint: RESUME before the first step */
    char resume_name[64];
    double fingerprint[CPL_FINGERPRINT_N];  /* checkpoint: settings a resumed run must
                                               share (cpl_loop_checkpoint_prepare) */
};

void cpl_loop_settings_default(cpl_loop_settings *s)
{
    memset(s, 0, sizeof *s);
    s->scheme = CPL_SCHEME_STRONG;
    s->start_time_s = 0.0;
    s->end_time_s = 1.0;
    s->dt_s = 1e-3;
    s->tol_abs = 1e-6;
    s->tol_rel = 0.0;
    s->work_tol = 0.0;
    s->newton_estimate = 0.0;
    s->max_iterations = 50;
    s->on_max_iterations = CPL_MAXIT_ACCEPT;
    s->relaxed = CPL_RELAXED_DISPLACEMENT_VELOCITY;
    cpl_relax_settings_default(&s->relax);
    s->predictor = CPL_PREDICT_QUADRATIC;
    s->far_step = 0;
    s->far_step_factor = 100.0;
    s->skip_fem_without_contact = 0;
    s->contact_force_threshold_n = 0.0;
    s->max_steps = 0;
    s->dt_min_s = 0.0;   /* dt_s / 64 */
    s->grow_after = 4;
    s->reject_slow = 1;
    cpl_energy_settings_default(&s->energy);
    cpl_impulse_settings_default(&s->impulse);
    s->interface_jacobian = 1;
    s->interface_compliance = 0;
    s->structure_predictor = 1;
    s->compliance_proximity = 1;
    s->verify_restore = 1;
    s->contact_backtracking = 8;
    s->checkpoint_interval_s = 0.0;
}

int cpl_compliance_reserve(cpl_compliance *c, size_t n_nodes, nc_error *err)
{
    if (n_nodes > c->cap || !c->nodes) {
        int32_t *nodes = malloc((n_nodes + 1) * sizeof *nodes);
        double *S = malloc((9 * n_nodes * n_nodes + 1) * sizeof *S);
        double *rows = malloc((3 * n_nodes * c->n3 + 1) * sizeof *rows);
        if (!nodes || !S || !rows) {
            free(nodes);
            free(S);
            free(rows);
            return nc_error_set(err, 1, "out of memory for the compliance of %zu nodes", n_nodes);
        }
        free(c->nodes);
        free(c->S);
        free(c->S_interface);
        c->nodes = nodes;
        c->S = S;
        c->S_interface = rows;
        c->cap = n_nodes;
    }
    c->n_nodes = n_nodes;
    return 0;
}

int cpl_jacobian_set(cpl_jacobian *j, size_t n, const int32_t *nodes, const double *stiffness,
                     const double *damping, nc_error *err)
{
    if (n > j->capacity) {
        size_t cap = n > 2 * j->capacity ? n : 2 * j->capacity;
        int32_t *nn = realloc(j->nodes, 2 * cap * sizeof *nn);
        if (nn) j->nodes = nn;
        double *k = nn ? realloc(j->stiffness, 9 * cap * sizeof *k) : NULL;
        if (k) j->stiffness = k;
        double *c = k ? realloc(j->damping, 9 * cap * sizeof *c) : NULL;
        if (c) j->damping = c;
        if (!c) return nc_error_set(err, 1, "interface Jacobian: out of memory for %zu blocks", n);
        j->capacity = cap;
    }
    j->n_blocks = n;
    if (n) {
        memcpy(j->nodes, nodes, 2 * n * sizeof *nodes);
        memcpy(j->stiffness, stiffness, 9 * n * sizeof *stiffness);
        if (damping) memcpy(j->damping, damping, 9 * n * sizeof *damping);
    }
    j->has_damping = damping != NULL;
    return 0;
}

void cpl_jacobian_free(cpl_jacobian *j)
{
    free(j->nodes);
    free(j->stiffness);
    free(j->damping);
    memset(j, 0, sizeof *j);
}

void cpl_jacobian_apply(const cpl_jacobian *j, const double *du, const double *dv, size_t n3,
                        double *out)
{
    for (size_t i = 0; i < n3; i++) out[i] = 0.0;
    for (size_t b = 0; b < j->n_blocks; b++) {
        /* block b: the motion of node nodes[2b+1] on the force of node nodes[2b] */
        const size_t f = 3 * (size_t)j->nodes[2 * b], m = 3 * (size_t)j->nodes[2 * b + 1];
        if (f + 3 > n3 || m + 3 > n3) continue;     /* the remote wrapper checked the nodes */
        const double *K = j->stiffness + 9 * b, *C = j->damping + 9 * b;
        for (int r = 0; r < 3; r++)
            for (int q = 0; q < 3; q++) {
                out[f + r] -= K[3 * r + q] * du[m + q];
                if (j->has_damping) out[f + r] -= C[3 * r + q] * dv[m + q];
            }
    }
}

int cpl_loop_settings_jacobian_applies(const cpl_loop_settings *s)
{
    return s->interface_jacobian &&
           !(s->scheme == CPL_SCHEME_STRONG && s->relaxed == CPL_RELAXED_FORCE);
}

double cpl_loop_settings_dt_min(const cpl_loop_settings *s)
{
    return s->dt_min_s > 0.0 ? s->dt_min_s : s->dt_s / CPL_DT_MIN_DIVISOR;
}

int cpl_loop_settings_check(const cpl_loop_settings *s, const char *where, nc_error *err)
{
    if (!(s->dt_s > 0.0) || !isfinite(s->dt_s))
        return nc_error_set(err, 1, "%s: dt must be a finite number > 0, got %g", where, s->dt_s);
    if (!(s->end_time_s > s->start_time_s))
        return nc_error_set(err, 1, "%s: end_time (%g s) must be after the start time (%g s)",
                            where, s->end_time_s, s->start_time_s);
    if (!(s->tol_abs > 0.0))
        return nc_error_set(err, 1, "%s: tolerance must be > 0, got %g", where, s->tol_abs);
    if (s->tol_rel < 0.0)
        return nc_error_set(err, 1, "%s: relative_tolerance must be >= 0, got %g", where,
                            s->tol_rel);
    if (!(s->work_tol >= 0.0 && s->work_tol <= 1.0))
        return nc_error_set(err, 1, "%s: work_tolerance must be in [0, 1], got %g", where,
                            s->work_tol);
    if (!(s->newton_estimate >= 0.0 && s->newton_estimate <= 0.5))
        return nc_error_set(err, 1, "%s: newton_estimate must be in [0, 0.5], got %g", where,
                            s->newton_estimate);
    if (s->max_iterations < 1)
        return nc_error_set(err, 1, "%s: max_iterations must be >= 1, got %d", where,
                            s->max_iterations);
    if (s->far_step && !(s->far_step_factor >= 1.0))
        return nc_error_set(err, 1, "%s: far_step_factor must be >= 1, got %g", where,
                            s->far_step_factor);
    if (s->dt_min_s < 0.0 || !isfinite(s->dt_min_s) || s->dt_min_s > s->dt_s * (1.0 + 1e-12))
        return nc_error_set(err, 1, "%s: step_control.dt_min must be in (0, dt = %g s], got %g",
                            where, s->dt_s, s->dt_min_s);
    if (!(s->energy.tol_rel >= 0.0) || !isfinite(s->energy.tol_rel))
        return nc_error_set(err, 1, "%s: energy_tolerance must be a finite number >= 0, got %g",
                            where, s->energy.tol_rel);
    if (!(s->energy.tol_abs_j >= 0.0) || !isfinite(s->energy.tol_abs_j))
        return nc_error_set(err, 1, "%s: energy_tolerance_abs_j must be a finite number >= 0, "
                            "got %g", where, s->energy.tol_abs_j);
    if (!(s->checkpoint_interval_s >= 0.0) || !isfinite(s->checkpoint_interval_s))
        return nc_error_set(err, 1, "%s: checkpoint.interval_s must be a finite number > 0 "
                            "(or 0: no checkpoints), got %g", where, s->checkpoint_interval_s);
    if (s->grow_after < 1)
        return nc_error_set(err, 1, "%s: step_control.grow_after must be >= 1, got %d", where,
                            s->grow_after);
    if (s->jacobian_check_interval < 0)
        return nc_error_set(err, 1, "%s: jacobian_check must be >= 0 (0: off), got %d", where,
                            s->jacobian_check_interval);
    if (s->jacobian_check_interval > 0 &&
        (s->scheme != CPL_SCHEME_STRONG || !cpl_loop_settings_jacobian_applies(s)))
        return nc_error_set(err, 1, "%s: jacobian_check needs the strong scheme with "
                            "relaxed_quantity \"displacement_velocity\" and interface_jacobian "
                            "on: it checks the linearisation along the steps of the iteration",
                            where);
    char relax_where[512];
    nc_json_path(relax_where, sizeof relax_where, where, "relaxation");
    if (cpl_relax_settings_check(&s->relax, relax_where, err)) return -1;
    return 0;
}

int cpl_loop_create(cpl_loop **out, const cpl_loop_settings *s, size_t n_nodes,
                    const double *u0, const double *v0, nc_error *err)
{
    *out = NULL;
    if (cpl_loop_settings_check(s, "coupling settings", err)) return -1;
    if (n_nodes == 0) return nc_error_set(err, 1, "coupling loop: interface without nodes");
    cpl_loop *L = calloc(1, sizeof *L);
    if (!L) return nc_error_set(err, 1, "coupling loop: out of memory");
    L->s = *s;
    L->n3 = 3 * n_nodes;
    L->nx = s->relaxed == CPL_RELAXED_FORCE ? L->n3 : 2 * L->n3;
    L->time_s = s->start_time_s;
    L->last_near = -1;
    double **vectors[] = {&L->u, &L->v, &L->f, &L->u_in, &L->v_in, &L->f_dem, &L->f_in,
                          &L->u_out, &L->v_out, &L->r, &L->check0, &L->check1,
                          &L->u_prev, &L->v_prev, &L->f_prev, &L->f_pred, &L->u_end, &L->v_end,
                          &L->u_before, &L->lin_u, &L->lin_v,
                          &L->du, &L->dv, &L->df, &L->probe_u, &L->probe_v, &L->probe_plus,
                          &L->probe_minus, &L->correction, &L->comp.force_ref,
                          &L->comp_u_lin, &L->comp_v_lin, &L->comp_f_lin, &L->comp.u_wall,
                          &L->v_answer};
    for (size_t i = 0; i < sizeof vectors / sizeof *vectors; i++) {
        *vectors[i] = calloc(L->n3, sizeof(double));
        if (!*vectors[i]) goto oom;
    }
    L->comp.n3 = L->n3;
    L->x_in = calloc(L->nx, sizeof(double));
    L->x_out = calloc(L->nx, sizeof(double));
    L->lost = calloc(n_nodes ? n_nodes : 1, 1);
    L->on_compliance = calloc(n_nodes ? n_nodes : 1, 1);
    if (!L->x_in || !L->x_out || !L->lost || !L->on_compliance) goto oom;
    if (u0) memcpy(L->u, u0, L->n3 * sizeof(double));
    if (v0) memcpy(L->v, v0, L->n3 * sizeof(double));
    if (s->scheme == CPL_SCHEME_STRONG &&
        cpl_relax_create(&L->relax, &s->relax, L->nx,
                         s->relaxed == CPL_RELAXED_FORCE ? 1 : 2, err)) {
        cpl_loop_free(L);
        return -1;
    }
    L->timing.solver_fem_s = NAN;
    L->timing.solver_dem_s = NAN;
    L->timing.min_dt_s = INFINITY;
    cpl_energy_init(&L->energy, &s->energy);
    cpl_impulse_init(&L->impulse, &s->impulse);
    L->next_checkpoint = 1;
    *out = L;
    return 0;
oom:
    cpl_loop_free(L);
    return nc_error_set(err, 1, "coupling loop: out of memory for %zu interface nodes", n_nodes);
}

void cpl_loop_free(cpl_loop *L)
{
    if (!L) return;
    cpl_relax_free(L->relax);
    free(L->u);
    free(L->v);
    free(L->f);
    free(L->u_in);
    free(L->v_in);
    free(L->f_dem);
    free(L->f_in);
    free(L->u_out);
    free(L->v_out);
    free(L->r);
    free(L->x_in);
    free(L->x_out);
    free(L->check0);
    free(L->check1);
    free(L->u_prev);
    free(L->v_prev);
    free(L->f_prev);
    free(L->f_pred);
    free(L->u_end);
    free(L->v_end);
    free(L->lost);
    free(L->on_compliance);
    free(L->u_before);
    double *check_vectors[] = {L->du, L->dv, L->df, L->lin_u, L->lin_v, L->probe_u,
                               L->probe_v, L->probe_plus, L->probe_minus, L->correction};
    for (size_t i = 0; i < sizeof check_vectors / sizeof *check_vectors; i++)
        free(check_vectors[i]);
    cpl_jacobian_free(&L->jac);
    cpl_jacobian_free(&L->comp_jac);
    cpl_jacobian_free(&L->predictor_jac);
    free(L->comp.force_ref); free(L->comp.nodes); free(L->comp.S); free(L->comp.S_interface);
    free(L->comp_u_lin); free(L->comp_v_lin); free(L->comp_f_lin); free(L->comp.u_wall);
    free(L->v_answer);
    free(L);
}

const char *cpl_reject_reason_text(cpl_reject_reason reason)
{
    switch (reason) {
    case CPL_REJECT_NOT_CONVERGED: return "not converged";
    case CPL_REJECT_DIVERGED: return "diverged";
    case CPL_REJECT_STEP_FAILED: return "solve failed";
    case CPL_REJECT_TOO_SLOW: return "converging too slowly";
    }
    return "?";
}

const cpl_timing *cpl_loop_timing(const cpl_loop *L) { return &L->timing; }
const double *cpl_loop_displacement(const cpl_loop *L) { return L->u; }
const double *cpl_loop_velocity(const cpl_loop *L) { return L->v; }
const double *cpl_loop_force(const cpl_loop *L) { return L->f; }
double cpl_loop_time(const cpl_loop *L) { return L->time_s; }
const cpl_energy *cpl_loop_energy(const cpl_loop *L) { return &L->energy; }
const cpl_impulse *cpl_loop_impulse(const cpl_loop *L) { return &L->impulse; }
int cpl_loop_uses_jacobian(const cpl_loop *L) { return L->use_jacobian; }
int cpl_loop_uses_compliance(const cpl_loop *L) { return L->use_compliance; }
const cpl_jacobian_check *cpl_loop_jacobian_check(const cpl_loop *L) { return &L->jac_check; }
long cpl_loop_step(const cpl_loop *L) { return L->step; }

/* ---- checkpoint and resume ------------------------------------------------------------ */

_Static_assert(sizeof(int) == sizeof(int32_t), "Jacobian node ids are saved as int");

int cpl_loop_checkpoints_on(const cpl_loop *L, const cpl_participant *fem,
                            const cpl_participant *dem)
{
    return L->s.checkpoint_interval_s > 0.0 && fem->checkpoint && fem->resume &&
           dem->checkpoint && dem->resume;
}

static void fill_fingerprint(const cpl_loop_settings *s, size_t n3, double *fp)
{
    fp[0] = s->dt_s;
    fp[1] = (double)s->scheme;
    fp[2] = (double)s->relaxed;
    fp[3] = s->tol_abs;
    fp[4] = (double)n3;
    fp[5] = s->work_tol;
    /* a weak step relaxes nothing: its method is none whatever the settings say */
    fp[6] = cpl_relax_method_id(s->scheme == CPL_SCHEME_STRONG
                                    ? cpl_relax_settings_method(&s->relax) : "none");
    fp[7] = s->newton_estimate;
    fp[8] = (double)s->interface_compliance;
    fp[9] = s->interface_compliance ? (double)s->structure_predictor : 0.0;   /* acts only then */
    fp[10] = s->interface_compliance ? (double)s->compliance_proximity : 0.0;
}

/* The settings the checkpoint `path` was written with (L->fingerprint) against this run's. */
static int check_fingerprint(const cpl_loop *L, const char *path, nc_error *err)
{
    double now[CPL_FINGERPRINT_N];
    fill_fingerprint(&L->s, L->n3, now);
    const char *what[CPL_FINGERPRINT_N] = {"dt (s)", "scheme", "relaxed_quantity", "tolerance",
                                           "interface dofs", "work_tolerance",
                                           "relaxation.method", "newton_estimate",
                                           "interface_compliance", "structure_predictor",
                                           "compliance_proximity"};
    for (int i = 0; i < CPL_FINGERPRINT_N; i++) {
        if (memcmp(&now[i], &L->fingerprint[i], sizeof now[i]) == 0) continue;
        if (i == 6) {
            const char *was = cpl_relax_method_name(L->fingerprint[i]);
            return nc_error_set(err, 1, "%s: the checkpoint was written with %s \"%s\", this "
                                "run has \"%s\": a run resumes with the settings it started "
                                "with", path, what[i], was ? was : "(unknown)",
                                cpl_relax_settings_method(&L->s.relax));
        }
        return nc_error_set(err, 1, "%s: the checkpoint was written with %s = %.17g, this "
                            "run has %.17g: a run resumes with the settings it started "
                            "with", path, what[i], L->fingerprint[i], now[i]);
    }
    return 0;
}

static void energy_report_entries(cpl_ckpt_table *t, const char *prefix, cpl_energy_report *r)
{
    cpl_ckpt_int(t, prefix, "valid", &r->valid);
    double *v[] = {&r->kinetic_j, &r->elastic_j, &r->potential_j, &r->interface_work_j,
                   &r->external_work_j, &r->dissipated_j, &r->numerical_j};
    const char *names[] = {"kinetic", "elastic", "potential", "interface_work",
                           "external_work", "dissipated", "numerical"};
    for (int i = 0; i < 7; i++) cpl_ckpt_f64(t, prefix, names[i], v[i], 1);
}

void cpl_loop_checkpoint_entries(cpl_loop *L, cpl_ckpt_table *t)
{
    const char *p = "loop";
    const size_t n3 = L->n3;
    fill_fingerprint(&L->s, n3, L->fingerprint);
    cpl_ckpt_f64(t, p, "settings", L->fingerprint, CPL_FINGERPRINT_N);
    /* where the run is and the step control */
    cpl_ckpt_f64(t, p, "time", &L->time_s, 1);
    cpl_ckpt_long(t, p, "step", &L->step);
    cpl_ckpt_int(t, p, "last_near", &L->last_near);
    cpl_ckpt_int(t, p, "level", &L->level);
    cpl_ckpt_int(t, p, "converged_run", &L->converged_run);
    cpl_ckpt_f64(t, p, "grid_origin", &L->grid_origin_s, 1);
    cpl_ckpt_f64(t, p, "dt_before", &L->dt_before_s, 1);
    cpl_ckpt_long(t, p, "next_checkpoint", &L->next_checkpoint);
    /* the accepted interface state (the predictor's input) and the work vectors of the last
     * iteration (overwritten before use; saved so that nothing is left to chance) */
    struct { const char *name; double *v; size_t n; } vec[] = {
        {"u", L->u, n3}, {"v", L->v, n3}, {"f", L->f, n3}, {"u_before", L->u_before, n3},
        {"u_in", L->u_in, n3}, {"v_in", L->v_in, n3}, {"f_dem", L->f_dem, n3},
        {"f_in", L->f_in, n3},
        {"u_out", L->u_out, n3}, {"v_out", L->v_out, n3}, {"r", L->r, n3},
        {"check0", L->check0, n3}, {"check1", L->check1, n3}, {"x_in", L->x_in, L->nx},
        {"x_out", L->x_out, L->nx}};
    for (size_t i = 0; i < sizeof vec / sizeof *vec; i++)
        cpl_ckpt_f64(t, p, vec[i].name, vec[i].v, vec[i].n);
    /* the restore verification is done once per run, not again after a resume */
    cpl_ckpt_int(t, p, "verified_fem", &L->verified_fem);
    cpl_ckpt_int(t, p, "verified_dem", &L->verified_dem);
    /* the DEM's linearisation of the last iteration */
    cpl_ckpt_size(t, p, "jacobian_blocks", &L->jac.n_blocks);
    cpl_ckpt_int(t, p, "jacobian_has_damping", &L->jac.has_damping);
    cpl_ckpt_add(t, p, "jacobian_nodes", CPL_CKPT_INT, L->jac.nodes, 2 * L->jac.n_blocks);
    cpl_ckpt_f64(t, p, "jacobian_stiffness", L->jac.stiffness, 9 * L->jac.n_blocks);
    cpl_ckpt_f64(t, p, "jacobian_damping", L->jac.damping, 9 * L->jac.n_blocks);
    /* the structure's compliance of the last FEM solve: a resumed step starts with it */
    cpl_ckpt_size(t, p, "compliance_nodes", &L->comp.n_nodes);
    cpl_ckpt_add(t, p, "compliance_node_list", CPL_CKPT_INT, L->comp.nodes, L->comp.n_nodes);
    cpl_ckpt_f64(t, p, "compliance", L->comp.S, 9 * L->comp.n_nodes * L->comp.n_nodes);
    cpl_ckpt_int(t, p, "compliance_has_interface", &L->comp.has_interface);
    cpl_ckpt_f64(t, p, "compliance_interface", L->comp.S_interface, 3 * L->comp.n_nodes * L->n3);
    cpl_ckpt_f64(t, p, "compliance_dt", &L->comp.dt_s, 1);
    cpl_ckpt_f64(t, p, "compliance_velocity_per_m", &L->comp.velocity_per_m, 1);
    cpl_ckpt_int(t, p, "compliance_valid", &L->comp.valid);
    /* the summary's counters (the wall-clock ones too: they keep adding up) */
    cpl_timing *tm = &L->timing;
    const char *q = "timing";
    cpl_ckpt_f64(t, q, "total", &tm->total_s, 1);
    cpl_ckpt_f64(t, q, "wait_fem", &tm->wait_fem_s, 1);
    cpl_ckpt_f64(t, q, "wait_dem", &tm->wait_dem_s, 1);
    cpl_ckpt_f64(t, q, "solver_fem", &tm->solver_fem_s, 1);
    cpl_ckpt_f64(t, q, "solver_dem", &tm->solver_dem_s, 1);
    cpl_ckpt_long(t, q, "fem_solves", &tm->fem_solves);
    cpl_ckpt_long(t, q, "dem_solves", &tm->dem_solves);
    cpl_ckpt_long(t, q, "steps", &tm->steps);
    cpl_ckpt_long(t, q, "iterations", &tm->iterations);
    cpl_ckpt_long(t, q, "unconverged_steps", &tm->unconverged_steps);
    cpl_ckpt_long(t, q, "rejected_attempts", &tm->rejected_attempts);
    cpl_ckpt_long(t, q, "slow_rejections", &tm->slow_rejections);
    cpl_ckpt_long(t, q, "backtracks", &tm->backtracks);
    cpl_ckpt_long(t, q, "fem_repeats_skipped", &tm->fem_repeats_skipped);
    cpl_ckpt_long(t, q, "compliance_tries", &tm->compliance_tries);
    cpl_ckpt_long(t, q, "compliance_dropped", &tm->compliance_dropped);
    cpl_ckpt_long(t, q, "structure_predictions", &tm->structure_predictions);
    cpl_ckpt_long(t, q, "work_test_steps", &tm->work_test_steps);
    cpl_ckpt_long(t, q, "estimate_steps", &tm->estimate_steps);
    cpl_ckpt_long(t, q, "jacobian_dropped_steps", &tm->jacobian_dropped_steps);
    cpl_ckpt_long(t, q, "reduced_steps", &tm->reduced_steps);
    cpl_ckpt_f64(t, q, "min_dt", &tm->min_dt_s, 1);
    cpl_jacobian_check *jc = &L->jac_check;
    cpl_ckpt_long(t, "jacobian_check", "checks", &jc->checks);
    cpl_ckpt_long(t, "jacobian_check", "missed", &jc->missed);
    cpl_ckpt_long(t, "jacobian_check", "solves", &jc->solves);
    cpl_ckpt_f64(t, "jacobian_check", "worst", &jc->worst, 1);
    cpl_ckpt_long(t, "jacobian_check", "worst_step", &jc->worst_step);
    cpl_ckpt_int(t, "jacobian_check", "worst_iteration", &jc->worst_iteration);
    cpl_ckpt_f64(t, "jacobian_check", "worst_time", &jc->worst_time_s, 1);
    /* the energy balance and guard */
    cpl_energy *e = &L->energy;
    const char *r = "energy";
    cpl_ckpt_int(t, r, "started", &e->started);
    cpl_ckpt_int(t, r, "available", &e->available);
    double *ev[] = {&e->e0_j, &e->sum_mismatch_j, &e->sum_fem_diss_j, &e->sum_dem_diss_j,
                    &e->sum_ext_j, &e->input_j, &e->created_j, &e->closure_j,
                    &e->first_time_s, &e->first_created_j, &e->first_limit_j,
                    &e->max_excess_j};
    const char *en[] = {"e0", "sum_mismatch", "sum_fem_dissipated", "sum_dem_dissipated",
                        "sum_external", "input", "created", "closure", "first_time",
                        "first_created", "first_limit", "max_excess"};
    for (size_t i = 0; i < sizeof ev / sizeof *ev; i++) cpl_ckpt_f64(t, r, en[i], ev[i], 1);
    cpl_ckpt_long(t, r, "above_steps", &e->above_steps);
    cpl_ckpt_long(t, r, "first_step", &e->first_step);
    energy_report_entries(t, "energy/fem_last", &e->fem_last);
    /* the interface's momentum balance */
    cpl_impulse *m = &L->impulse;
    cpl_ckpt_f64(t, "impulse", "given", m->given_ns, 3);
    cpl_ckpt_f64(t, "impulse", "given_abs", &m->given_abs_ns, 1);
    cpl_ckpt_f64(t, "impulse", "missed", m->missed_ns, 3);
    cpl_ckpt_long(t, "impulse", "first_step", &m->first_step);
    cpl_ckpt_f64(t, "impulse", "first_time", &m->first_time_s, 1);
    if (L->relax) cpl_relax_checkpoint_entries(L->relax, t, "relax");
}

int cpl_loop_checkpoint_prepare(cpl_loop *L, const char *path, nc_error *err)
{
    /* the settings first: with another relaxation method the state's entries differ, and
     * the load would fail on one of them instead of naming the setting */
    cpl_ckpt_table settings = {0};
    cpl_ckpt_f64(&settings, "loop", "settings", L->fingerprint, CPL_FINGERPRINT_N);
    int loaded = cpl_ckpt_load(&settings, path, err);
    cpl_ckpt_table_free(&settings);
    if (loaded || check_fingerprint(L, path, err)) return -1;
    size_t n = 0;
    if (nc_ckpt_read_scalar(path, "/loop/jacobian_blocks", NC_CKPT_SIZE, &n, err)) return -1;
    if (n > 100000000u)
        return nc_error_set(err, 1, "%s: /loop/jacobian_blocks = %zu is not a block count", path,
                            n);
    int32_t *nodes = calloc(2 * n + 1, sizeof *nodes);
    double *zeros = calloc(9 * n + 1, sizeof *zeros);
    int rc = nodes && zeros ? cpl_jacobian_set(&L->jac, n, nodes, zeros, zeros, err)
                            : nc_error_set(err, 1, "%s: out of memory for %zu Jacobian blocks",
                                           path, n);
    free(nodes);
    free(zeros);
    if (rc) return rc;
    if (nc_ckpt_read_scalar(path, "/loop/compliance_nodes", NC_CKPT_SIZE, &n, err)) return -1;
    if (n > 100000u)
        return nc_error_set(err, 1, "%s: /loop/compliance_nodes = %zu is not a node count", path,
                            n);
    return cpl_compliance_reserve(&L->comp, n, err);
}

int cpl_loop_checkpoint_loaded(const cpl_loop *L, const char *path, nc_error *err)
{
    const size_t n_nodes = L->n3 / 3;
    if (cpl_node_list_check(L->comp.nodes, L->comp.n_nodes, 1, n_nodes, 1,
                            "/loop/compliance_node_list", err) ||
        cpl_node_list_check(L->jac.nodes, 2 * L->jac.n_blocks, 2, n_nodes, 0,
                            "/loop/jacobian_nodes", err))
        return nc_error_prefix(err, "%s", path);
    return 0;
}

void cpl_loop_resumed(cpl_loop *L, const char *name)
{
    snprintf(L->resume_name, sizeof L->resume_name, "%s", name);
    L->resume_pending = 1;
}

/* ---- calls into the participants: timing, interruption, error context ----------------- */

typedef struct run_ctx {
    cpl_loop *L;
    const cpl_participant *fem, *dem;
    const cpl_observer *obs;
    const volatile sig_atomic_t *stop;
    cpl_failure *failure;
    nc_error *err;
    int attempt;            /* tries of the current step rejected so far */
    double clock_s;         /* wall clock up to which timing.total_s is counted */
} run_ctx;

static int fail(run_ctx *c, const cpl_participant *p, const cpl_call *call, const char *command)
{
    c->failure->participant = p;
    c->failure->step = call->step;
    c->failure->iteration = call->iteration;
    c->failure->command = command;
    if (call->iteration > 0)
        return nc_error_prefix(c->err, "%s: step %ld (t = %.6g s), iteration %d, %s",
                               p ? p->name : "coupler", call->step, call->time_s,
                               call->iteration, command);
    return nc_error_prefix(c->err, "%s: step %ld (t = %.6g s), %s", p ? p->name : "coupler",
                           call->step, call->time_s, command);
}

static int check_stop(run_ctx *c, const cpl_call *call)
{
    if (c->stop && *c->stop) {
        c->failure->participant = NULL;
        c->failure->step = call->step;
        c->failure->iteration = call->iteration;
        c->failure->command = "interrupted";
        return nc_error_set(c->err, CPL_ERR_INTERRUPTED,
                            "interrupted by a signal at step %ld (t = %.6g s), iteration %d",
                            call->step, call->time_s, call->iteration);
    }
    return 0;
}

static double *wait_of(run_ctx *c, const cpl_participant *p)
{
    return p == c->fem ? &c->L->timing.wait_fem_s : &c->L->timing.wait_dem_s;
}

/* BEGIN_STEP or ACCEPT_STEP to the participants ps[0..n): each that can post gets the
 * command before any answer is awaited, so that their round trips overlap; the others are
 * called in turn. The wait is booked to each participant until its answer came. */
static int command_participants(run_ctx *c, cpl_command command, const cpl_call *call,
                                const cpl_participant *const *ps, int n)
{
    const char *what = command == CPL_COMMAND_BEGIN_STEP ? "begin_step" : "accept_step";
    int posted[2] = {0, 0};
    if (check_stop(c, call)) return -1;
    double t0 = nc_clock_now_s();
    for (int i = 0; i < n; i++)
        if (ps[i]->post && ps[i]->await) {
            if (ps[i]->post(ps[i]->ctx, command, call, c->err)) return fail(c, ps[i], call, what);
            posted[i] = 1;
        }
    for (int i = 0; i < n; i++) {
        const cpl_participant *p = ps[i];
        int rc = posted[i]                              ? p->await(p->ctx, c->err)
                 : command == CPL_COMMAND_BEGIN_STEP ? p->begin_step(p->ctx, call, c->err)
                                                     : p->accept(p->ctx, call, c->err);
        double t1 = nc_clock_now_s();
        *wait_of(c, p) += t1 - t0;
        t0 = t1;
        if (rc) return fail(c, p, call, what);
    }
    return 0;
}

/* The command to the DEM, and to the FEM too when with_fem. */
static int command_both(run_ctx *c, cpl_command command, const cpl_call *call, int with_fem)
{
    const cpl_participant *both[2] = {c->fem, c->dem};
    return with_fem ? command_participants(c, command, call, both, 2)
                    : command_participants(c, command, call, both + 1, 1);
}

static int verify_restore(run_ctx *c, const cpl_participant *p, const cpl_call *call,
                          const double *in0, const double *in1, const double *out0,
                          const double *out1);

static int do_checkpoint(run_ctx *c, const cpl_participant *p, const cpl_call *call,
                         const char *name, int resume)
{
    if (check_stop(c, call)) return -1;
    double t0 = nc_clock_now_s();
    int rc = resume ? p->resume(p->ctx, call, name, c->err)
                    : p->checkpoint(p->ctx, call, name, c->err);
    *wait_of(c, p) += nc_clock_now_s() - t0;
    return rc ? fail(c, p, call, resume ? "resume" : "checkpoint") : 0;
}

/* After an accepted step: a checkpoint when the step reached the next checkpoint time and
 * the run goes on (a checkpoint of the end would have nothing to resume). */
static int maybe_checkpoint(run_ctx *c)
{
    cpl_loop *L = c->L;
    if (!cpl_loop_checkpoints_on(L, c->fem, c->dem)) return 0;
    const double start = L->s.start_time_s, every = L->s.checkpoint_interval_s;
    const double eps = 1e-9 * L->s.dt_s;
    if (L->time_s < start + (double)L->next_checkpoint * every - eps) return 0;
    while (start + (double)L->next_checkpoint * every <= L->time_s + eps) L->next_checkpoint++;
    if (L->time_s >= L->s.end_time_s - eps || (L->s.max_steps > 0 && L->step >= L->s.max_steps))
        return 0;
    char name[64];
    snprintf(name, sizeof name, "step_%06ld", L->step);
    cpl_call call = {.step = L->step, .iteration = 0, .time_s = L->time_s, .dt_s = 0.0};
    if (do_checkpoint(c, c->fem, &call, name, 0) || do_checkpoint(c, c->dem, &call, name, 0))
        return -1;
    /* the saved wall time must include this run's part so far: a resumed run adds to it */
    double now = nc_clock_now_s();
    L->timing.total_s += now - c->clock_s;
    c->clock_s = now;
    if (c->obs && c->obs->on_checkpoint &&
        c->obs->on_checkpoint(c->obs->ctx, L->step, L->time_s, name, c->err))
        return fail(c, NULL, &call, "checkpoint");
    return 0;
}

static int do_solve(run_ctx *c, const cpl_participant *p, const cpl_call *call,
                    const double *in0, const double *in1, double *out0, double *out1,
                    cpl_solve_info *info)
{
    if (check_stop(c, call)) return -1;
    info->near_interface = 1;
    info->min_gap_m = INFINITY;
    info->contacts = 0.0;
    info->solver_time_s = NAN;
    info->energy = cpl_energy_report_none();
    info->jacobian_dropped = 0.0;
    double t0 = nc_clock_now_s();
    int rc = p->solve(p->ctx, call, in0, in1, out0, out1, info, c->err);
    *wait_of(c, p) += nc_clock_now_s() - t0;
    if (rc) return fail(c, p, call, "solve");
    size_t n = c->L->n3;
    if (verify_restore(c, p, call, in0, in1, out0, out1)) return -1;
    const double *outs[2] = {out0, out1};
    for (int o = 0; o < 2; o++)
        if (outs[o])
            for (size_t i = 0; i < n; i++)
                if (!isfinite(outs[o][i])) {
                    nc_error_set(c->err, CPL_ERR_PARTICIPANT,
                                 "reply contains a non-finite value at node %zu", i / 3);
                    return fail(c, p, call, "solve");
                }
    cpl_timing *t = &c->L->timing;
    if (p == c->fem) {
        t->fem_solves++;
        if (isfinite(info->solver_time_s))
            t->solver_fem_s = (isnan(t->solver_fem_s) ? 0.0 : t->solver_fem_s) + info->solver_time_s;
    } else {
        t->dem_solves++;
        if (isfinite(info->solver_time_s))
            t->solver_dem_s = (isnan(t->solver_dem_s) ? 0.0 : t->solver_dem_s) + info->solver_time_s;
    }
    return 0;
}

/* Strong coupling repeats a step from its saved start: a participant that does not restore
 * would converge to nonsense without a sign. So the first solve of each participant with a
 * non-zero answer is sent again with the same input (the second SOLVE of a step restores
 * first, protocol/README.md §3) and the two answers must be identical. */
static int verify_restore(run_ctx *c, const cpl_participant *p, const cpl_call *call,
                          const double *in0, const double *in1, const double *out0,
                          const double *out1)
{
    cpl_loop *L = c->L;
    int *verified = p == c->fem ? &L->verified_fem : &L->verified_dem;
    if (L->s.scheme != CPL_SCHEME_STRONG || !L->s.verify_restore || *verified) return 0;
    /* an answer of zeros (a DEM without contact, a structure at rest and unloaded) would be
     * the same from any state: verify at the first answer that is not */
    int trivial = 1;
    for (size_t i = 0; i < L->n3 && trivial; i++)
        trivial = out0[i] == 0.0 && (!out1 || out1[i] == 0.0);
    if (trivial) return 0;
    *verified = 1;
    cpl_solve_info again = {1, INFINITY, 0.0, NAN, cpl_energy_report_none(), 0.0};
    /* the repeated solve fills a scratch Jacobian so the one of the first answer stays */
    cpl_call repeat = *call;
    cpl_jacobian scratch = {0};
    if (repeat.jacobian_out) repeat.jacobian_out = &scratch;
    double t0 = nc_clock_now_s();
    int rc = p->solve(p->ctx, &repeat, in0, in1, L->check0, out1 ? L->check1 : NULL, &again, c->err);
    *wait_of(c, p) += nc_clock_now_s() - t0;
    cpl_jacobian_free(&scratch);
    if (rc) return fail(c, p, call, "solve (repeated to verify restore)");
    /* a SOLVE the participant answered like any other: counted with them */
    if (p == c->fem) L->timing.fem_solves++;
    else L->timing.dem_solves++;
    const double *outs[2] = {out0, out1}, *checks[2] = {L->check0, L->check1};
    for (int o = 0; o < 2; o++) {
        if (!outs[o]) continue;
        for (size_t i = 0; i < L->n3; i++)
            if (memcmp(&outs[o][i], &checks[o][i], sizeof(double)) != 0) {
                nc_error_set(c->err, CPL_ERR_PARTICIPANT,
                             "does not restore its start-of-step state: the same solve sent twice "
                             "gave %.17g and %.17g at node %zu, component %zu (or its answer "
                             "depends on where an iteration started: protocol/README.md §3 "
                             "solve); strong coupling needs a participant that repeats a step "
                             "exactly (or set \"verify_restore\": false to skip this check)",
                             outs[o][i], checks[o][i], i / 3, i % 3);
                return fail(c, p, call, "solve");
            }
    }
    return 0;
}

/* FEM solve, or efficiency option (ii): while no contact force acts and the structure has
 * not been solved in this step, it stays where it is (valid only when it is otherwise
 * unloaded and at rest). Returns 1 when solved, 0 when skipped, -1 on failure. */
static int fem_solve_or_skip(run_ctx *c, const cpl_call *call, const double *force,
                             int solved_before, cpl_solve_info *info)
{
    cpl_loop *L = c->L;
    if (L->s.skip_fem_without_contact) {
        if (!solved_before && cpl_max_abs(force, L->n3) <= L->s.contact_force_threshold_n) {
            memcpy(L->u_out, L->u, L->n3 * sizeof(double));
            memcpy(L->v_out, L->v, L->n3 * sizeof(double));
            return 0;
        }
        /* with this option the FEM's step begins only when it is first solved: a skipped
         * step is not a step for it at all (no BEGIN_STEP, no ACCEPT_STEP) */
        if (!solved_before &&
            command_participants(c, CPL_COMMAND_BEGIN_STEP, call, &c->fem, 1))
            return -1;
    }
    if (do_solve(c, c->fem, call, force, NULL, L->u_out, L->v_out, info)) return -1;
    return 1;
}

/* x = [u; Δt_nominal · u̇]: both halves in metres, so IQN's least squares is balanced. */
static void pack(const cpl_loop *L, double *x, const double *u, const double *v)
{
    memcpy(x, u, L->n3 * sizeof(double));
    for (size_t i = 0; i < L->n3; i++) x[L->n3 + i] = L->s.dt_s * v[i];
}

static void unpack(const cpl_loop *L, const double *x, double *u, double *v)
{
    memcpy(u, x, L->n3 * sizeof(double));
    for (size_t i = 0; i < L->n3; i++) v[i] = x[L->n3 + i] / L->s.dt_s;
}

/* Δt of a step's first try: the step control's Δt·2^-level, enlarged by efficiency option
 * (i) at the nominal level, shortened (or stretched by a sliver) to end on end_time.
 * *ends: the step ends on end_time. */
static double choose_dt(const cpl_loop *L, int *ends)
{
    double dt = ldexp(L->s.dt_s, -L->level);
    if (L->level == 0 && L->s.far_step && L->last_near == 0)
        dt *= L->s.far_step_factor;   /* algorithm 1, l. 3–6 */
    double remaining = L->s.end_time_s - L->time_s;
    *ends = dt > remaining || remaining - dt < 1e-6 * L->s.dt_s;   /* no sliver */
    return *ends ? remaining : dt;
}

/* The Δt a rejected try of size dt_rejected is begun again with: the largest Δt·2^-k
 * (k >= 0) clearly below it (Δt/2 for a nominal step, Δt for an enlarged far step), or 0
 * when that is below dt_min. *level gets k. The margin keeps the retry out of the no-sliver
 * rule of choose_dt, so it is never stretched back to the rejected size. */
static double retry_dt(const cpl_loop *L, double dt_rejected, int *level)
{
    const double nominal = L->s.dt_s, margin = 2e-6 * nominal;
    int k = 0;
    while (k < 1000 && ldexp(nominal, -k) > dt_rejected - margin) k++;
    double dt = ldexp(nominal, -k);
    if (dt < cpl_loop_settings_dt_min(&L->s) * (1.0 - 1e-9)) return 0.0;
    *level = k;
    return dt;
}

static int report_iteration(run_ctx *c, const cpl_call *call, double residual, double alpha,
                            int fem_solved, double jacobian_miss)
{
    if (!c->obs || !c->obs->on_iteration) return 0;
    cpl_iteration_record rec = {.step = call->step, .iteration = call->iteration,
                                .time_s = call->time_s, .dt_s = call->dt_s,
                                .residual = residual, .alpha = alpha, .fem_solved = fem_solved,
                                .attempt = c->attempt, .jacobian_miss = jacobian_miss,
                                .compliance = call->compliance_in && c->L->comp.wall_valid};
    cpl_total_force(c->L->f_dem, c->L->n3 / 3, rec.contact_force);
    if (c->obs->on_iteration(c->obs->ctx, &rec, c->err)) return fail(c, NULL, call, "history");
    return 0;
}

/* How far a residual is from the tolerance: residual / max(tol_abs, tol_rel ‖value‖), below
 * 1 where cpl_converged() says converged. */
static double tolerance_ratio(const cpl_loop *L, double residual, double value_norm)
{
    return residual / fmax(L->s.tol_abs, L->s.tol_rel * value_norm);
}

/* L->correction = K (u_out − u_in) + C (v_out − v_in) of the iteration's DEM linearisation:
 * the structure solved with the DEM's force minus this. 0 (and nothing computed) without the
 * interface Jacobian. */
static int linearised_correction(cpl_loop *L)
{
    if (!L->use_jacobian) return 0;
    const cpl_jacobian *j = &L->jac;
    memset(L->correction, 0, L->n3 * sizeof(double));
    for (size_t b = 0; b < j->n_blocks; b++) {
        const size_t a = 3 * (size_t)j->nodes[2 * b], m = 3 * (size_t)j->nodes[2 * b + 1];
        const double *K = j->stiffness + 9 * b, *C = j->damping + 9 * b;
        for (int r = 0; r < 3; r++)
            for (int q = 0; q < 3; q++) {
                L->correction[a + r] += K[3 * r + q] * (L->u_out[m + q] - L->u_in[m + q]);
                if (j->has_damping)
                    L->correction[a + r] += C[3 * r + q] * (L->v_out[m + q] - L->v_in[m + q]);
            }
    }
    return 1;
}

/* The work test (work_tolerance): the interface work mismatch the step would take on if
 * this iterate were accepted (the coupler's balance, README "Energy balance"), over
 * work_tol x the input energy: <= 1 passes; INFINITY while off or before any energy is
 * known. correction: linearised_correction's, NULL without the interface Jacobian. The DEM did the work of its force F over its input motion, u_in - u; the structure
 * took the work of the force it solved with, F - K (u_out - u_in) - C (v_out - v_in) with the
 * interface Jacobian, over u_out - u. The difference:
 *   F . (u_out - u_in) - [K (u_out - u_in) + C (v_out - v_in)] . (u_out - u).
 * The second term matters with stiff contacts: without it, the MEL test's first 40 ms lost
 * 2.6 kJ at the interface instead of 56 J. */
static double work_ratio(cpl_loop *L, const double *correction)
{
    if (!(L->s.work_tol > 0.0) || !(L->energy.input_j > 0.0)) return INFINITY;
    double w = 0.0;
    for (size_t i = 0; i < L->n3; i++) w += L->f_dem[i] * (L->u_out[i] - L->u_in[i]);
    if (correction) {
        for (size_t i = 0; i < L->n3; i++) w -= correction[i] * (L->u_out[i] - L->u[i]);
    }
    return fabs(w) / (L->s.work_tol * L->energy.input_j);
}

static double dot3(const double a[3], const double b[3])
{
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

/* The resultant of an interface force field (n × 3), N. */
static void resultant(const double *f, size_t n3, double out[3])
{
    out[0] = out[1] = out[2] = 0.0;
    for (size_t i = 0; i < n3; i++) out[i % 3] += f[i];
}

/* The impulse guard's share (cpl_impulse.h) with this iterate accepted, or the step's own
 * share if that is smaller, over half of impulse_tolerance: ≤ 1 passes; 0 without the
 * interface Jacobian (correction NULL) or with impulse_tolerance 0. What the step adds is the
 * resultant of K (u_out − u_in) + C (u̇_out − u̇_in) (correction), the force the structure
 * solved with at its answer minus the DEM's. Near the end of a damped contact K grows without
 * bound (δ^(−3/4)): an answer within eq. (35)'s tolerance of u_in can then carry a force far
 * from the DEM's (angled_net at restitution 0.1 and 5× Δt: 439 N against 46 N in one step,
 * and the guard fired at the end of the run). The run's share counts it against the run's
 * impulse so far, so that a grazing contact after an impact is not held to a share of its own
 * few newtons (cases/barrier_mel: 24 % more iterations with the step's share alone). The
 * step's own share lets a consistent step pass after an earlier one was accepted unconverged
 * and left the run's share above the limit (else every later step would be rejected down to
 * dt_min). Either way a step that passes keeps a run's share that was within the limit within
 * it, as |M + m| ≤ |M| + |m|. */
static double force_mismatch(cpl_loop *L, double dt_s, const double *correction)
{
    const double share = 0.5 * L->impulse.s.tol_rel;
    if (!(share > 0.0) || !correction) return 0.0;
    double own;
    const double run = cpl_impulse_share_after(&L->impulse, dt_s, L->f_dem, correction,
                                               L->n3 / 3, &own);
    return fmin(run, own) / share;
}

/* Residual of algorithm 2: max(r_u, r_u̇), eq. (35); convergence needs both fields, eq. (27),
 * or r_u and the work test (work_tolerance; *by_work_test: it decided). *ratio: r_u's
 * tolerance_ratio or that of the second test passed more nearly (r_u̇'s or the work test's),
 * whichever is larger. */
static double residual_uv(cpl_loop *L, double dt_s, double rv_prev, const double *v_answer_prev,
                          int *converged, int *by_work_test, int *by_estimate, double *ratio,
                          double *rv_out)
{
    const double nu = cpl_scaled_norm(L->u_out, L->n3), nv = cpl_scaled_norm(L->v_out, L->n3);
    const double ru = cpl_residual(L->u_out, L->u_in, L->r, L->n3);
    const double rv = cpl_residual(L->v_out, L->v_in, L->r, L->n3);
    /* the step between the structure's answers, which the estimate's contraction is about:
     * r_u̇ itself when the input was the last answer, else (the DEM moved its wall from
     * there: interface_compliance) measured from the last answer */
    const double step = v_answer_prev ? cpl_residual(L->v_out, v_answer_prev, L->dv, L->n3) : rv;
    const double *correction = linearised_correction(L) ? L->correction : NULL;
    const double work = work_ratio(L, correction);
    const int u_ok = cpl_converged(ru, nu, L->s.tol_abs, L->s.tol_rel);
    const int v_ok = cpl_converged(rv, nv, L->s.tol_abs, L->s.tol_rel);
    double estimate = INFINITY;
    if (L->s.newton_estimate > 0.0 && L->use_jacobian && rv_prev > 0.0 && isfinite(rv_prev)) {
        const double theta = step / rv_prev;
        if (theta <= L->s.newton_estimate) estimate = theta / (1.0 - theta) * step;
    }
    const int estimate_ok = cpl_converged(estimate, nv, L->s.tol_abs, L->s.tol_rel);
    const double mismatch = force_mismatch(L, dt_s, correction);
    *converged = u_ok && (v_ok || work <= 1.0 || estimate_ok) && mismatch <= 1.0;
    *by_work_test = *converged && !v_ok && work <= 1.0;
    *by_estimate = *converged && !v_ok && !(work <= 1.0);
    *ratio = fmax(fmax(tolerance_ratio(L, ru, nu), mismatch),
                  fmin(fmin(tolerance_ratio(L, rv, nv), work), tolerance_ratio(L, estimate, nv)));
    *rv_out = step;
    return fmax(ru, rv);
}

/* The force the structure balanced at the DEM's input u_in (interface_compliance): before
 * the try's first FEM solve the last step's, else the FEM's last solve's linearised force
 * there, F^k - K (u_in - u^k) - C (u̇_in - u̇^k) (after structure_predictor's solve, its force
 * at the input it chose). */
static void compliance_reference(cpl_loop *L, int fem_solved)
{
    const size_t n3 = L->n3;
    if (!fem_solved) {
        memcpy(L->comp.force_ref, L->f, n3 * sizeof(double));
        return;
    }
    for (size_t i = 0; i < n3; i++) {
        L->du[i] = L->u_in[i] - L->comp_u_lin[i];
        L->dv[i] = L->v_in[i] - L->comp_v_lin[i];
    }
    cpl_jacobian_apply(&L->comp_jac, L->du, L->dv, n3, L->df);
    for (size_t i = 0; i < n3; i++) L->comp.force_ref[i] = L->comp_f_lin[i] + L->df[i];
}

/* The DEM moved its wall on the compliance nodes only, u_in + S (F − F_ref) there: the rest
 * of the interface, which no particle touches, goes where the same compliance puts it under
 * the DEM's answer, u_in + S_interface (F − F_ref) (when the structure sent those rows), so
 * that the iteration's residual measures what the DEM's model of the structure missed and
 * not the net's response to a force change that model already holds. A node the DEM touched
 * outside the compliance (a force or a block of its linearisation there) stays where the
 * DEM computed its force. */
static void move_free_nodes(cpl_loop *L)
{
    cpl_compliance *c = &L->comp;
    if (!c->has_interface) return;
    for (size_t q = 0; q < 3 * c->n_nodes; q++) {
        const size_t dof = 3 * (size_t)c->nodes[q / 3] + q % 3;
        L->df[q] = L->f_dem[dof] - c->force_ref[dof];
    }
    cpl_compliance_answer(c, L->df, L->du);
    const size_t n_nodes = L->n3 / 3;
    for (size_t q = 0; q < c->n_nodes; q++) L->on_compliance[c->nodes[q]] = 1;
    for (size_t b = 0; b < 2 * L->jac.n_blocks; b++)
        if (L->jac.nodes[b] >= 0 && (size_t)L->jac.nodes[b] < n_nodes)
            L->on_compliance[L->jac.nodes[b]] = 1;
    for (size_t i = 0; i < L->n3; i++)
        if (L->f_dem[i] != 0.0) L->on_compliance[i / 3] = 1;
    for (size_t i = 0; i < L->n3; i++)
        if (!L->on_compliance[i / 3]) c->u_wall[i] = L->u_in[i] + L->du[i];
    memset(L->on_compliance, 0, n_nodes);
}

/* 1 when every node of the linearisation's blocks has its compliance in c. */
static int compliance_covers(const cpl_compliance *c, const cpl_jacobian *j)
{
    for (size_t b = 0; b < 2 * j->n_blocks; b++) {
        size_t q = 0;
        while (q < c->n_nodes && c->nodes[q] != j->nodes[b]) q++;
        if (q == c->n_nodes) return 0;
    }
    return 1;
}

/* How one try of a step ended (the step is not accepted yet); TRY_SLOW: given up early by
 * reject_slow. */
typedef enum { TRY_CONVERGED = 0, TRY_UNCONVERGED, TRY_SLOW, TRY_DIVERGED, TRY_FAILED } try_outcome;

/* reject_slow (cpl_loop.h, CPL_SLOW_*): whether the try, after iteration k, cannot reach the
 * tolerance by max_iterations at the rate of its last CPL_SLOW_WINDOW iterations, while a
 * smaller Δt is left to retry with. ratios: tolerance_ratio of iteration i in slot
 * i % (CPL_SLOW_WINDOW + 1). Such a try would be rejected anyway after max_iterations; giving
 * up now saves the rest (on terrain_net 7800 of 34400 iterations). At dt_min the try runs
 * on, to be accepted or stopped as on_max_iterations says. */
static int too_slow(const cpl_loop *L, const double *ratios, int k, double dt_s)
{
    if (!L->s.reject_slow || k < CPL_SLOW_FIRST || k >= L->s.max_iterations) return 0;
    const double now = ratios[k % (CPL_SLOW_WINDOW + 1)];
    const double then = ratios[(k - CPL_SLOW_WINDOW) % (CPL_SLOW_WINDOW + 1)];
    if (!(now > 0.0 && then > 0.0 && isfinite(now) && isfinite(then))) return 0;
    const double rate = fmin(1.0, pow(now / then, 1.0 / CPL_SLOW_WINDOW));
    if (now * pow(rate, L->s.max_iterations - k) <= CPL_SLOW_MARGIN) return 0;
    int level = L->level;
    return retry_dt(L, dt_s, &level) > 0.0;
}

typedef struct try_result {
    try_outcome outcome;    /* weak: CONVERGED / UNCONVERGED is information only */
    int iterations;
    double residual;        /* of the last completed iteration, NAN if none */
    int fem_solved;         /* the FEM was solved (efficiency option (ii) may skip it) */
    cpl_solve_info dem_info;
    cpl_solve_info fem_info;    /* of the last FEM solve (when fem_solved) */
    int jacobian_dropped;       /* most particles a linearisation of this try left out */
    int by_work_test;           /* converged by the work test, not by r_u̇ */
    int by_estimate;            /* converged by the Newton error estimate (newton_estimate) */
} try_result;

/* A failed request that a smaller step may cure: the participant said so. c->err keeps the
 * message (with where it happened) for the rejection record. */
static int try_failed(run_ctx *c, try_result *t)
{
    if (c->err->code != CPL_ERR_STEP_FAILED) return -1;
    t->outcome = TRY_FAILED;
    return 0;
}

static int all_zero(const double *f, size_t n3)
{
    for (size_t i = 0; i < n3; i++)
        if (f[i] != 0.0) return 0;
    return 1;
}

/* a == b element by element (−0 and +0 alike: a force either way is none) */
static int same_values(const double *a, const double *b, size_t n)
{
    for (size_t i = 0; i < n; i++)
        if (a[i] != b[i]) return 0;
    return 1;
}

/* a == b up to the rounding of a full relaxation step, a + 1 (b − a): within 1e-12 of the
 * largest |b| */
static int same_within(const double *a, const double *b, size_t n)
{
    double scale = 0.0, diff = 0.0;
    for (size_t i = 0; i < n; i++) {
        scale = fmax(scale, fabs(b[i]));
        diff = fmax(diff, fabs(a[i] - b[i]));
    }
    return diff <= 1e-12 * scale;
}

/* The force that the linearisation L->jac about (u0, v0), with force f0 there, predicts at
 * (u1, v1), f0 − K (u1 − u0) − C (v1 − v0), what the FEM solved with (without
 * interface-Jacobian coupling: the constant force f0), into out (n3). */
static void predicted_force(cpl_loop *L, const double *f0, const double *u0, const double *v0,
                            const double *u1, const double *v1, double *out)
{
    memcpy(out, f0, L->n3 * sizeof(double));
    if (!L->use_jacobian) return;
    for (size_t i = 0; i < L->n3; i++) {
        L->du[i] = u1[i] - u0[i];
        L->dv[i] = v1[i] - v0[i];
    }
    cpl_jacobian_apply(&L->jac, L->du, L->dv, L->n3, L->df);
    for (size_t i = 0; i < L->n3; i++) out[i] += L->df[i];
}

/* The DEM's solve at the point t of the way from (u_prev, v_prev) (t = 0) to (u_end, v_end)
 * (t = 1), which becomes the iteration's input (u_in, v_in). */
static int solve_along(run_ctx *c, cpl_call *call, try_result *t, double s)
{
    cpl_loop *L = c->L;
    for (size_t i = 0; i < L->n3; i++) {
        L->u_in[i] = L->u_prev[i] + s * (L->u_end[i] - L->u_prev[i]);
        L->v_in[i] = L->v_prev[i] + s * (L->v_end[i] - L->v_prev[i]);
    }
    L->timing.backtracks++;
    if (call->compliance_in) compliance_reference(L, t->fem_solved);
    return do_solve(c, c->dem, call, L->u_in, L->v_in, L->f_dem, NULL, &t->dem_info);
}

/* Contact backtracking. The sum over the nodes of L->lost of f's components along e. */
static double lost_component(const cpl_loop *L, const double *f, const double e[3])
{
    double sum = 0.0;
    for (size_t j = 0; j < L->n3 / 3; j++)
        if (L->lost[j]) sum += f[3 * j] * e[0] + f[3 * j + 1] * e[1] + f[3 * j + 2] * e[2];
    return sum;
}

static int node_zero(const double *f, size_t j)
{
    return f[3 * j] == 0.0 && f[3 * j + 1] == 0.0 && f[3 * j + 2] == 0.0;
}

/* Whether the DEM's answer f_dem at the iterate (u_in, v_in) lost the contact that the last
 * iterate with contact (u_prev, v_prev) had, with force f_prev there and f_pred predicted
 * here by its linearisation. Marks the nodes whose force ended in L->lost, and sets e (the
 * direction of their resultant in f_prev) and *target (f_pred's resultant over them along e,
 * the force the structure balanced there; ≤ 0: none, as always for the plain exchange, whose
 * prediction is the last force unchanged). The contact is lost when
 * - no node has force although the prediction over them kept its sense, or although the try
 *   has seen the contact-free answer collide (contact_required);
 * - or (with the interface Jacobian) the nodes whose force ended carried at least
 *   CPL_LOST_SHARE of the last iterate's resultant, the prediction over them kept its sense, and the
 *   answer's resultant is below the predicted one: the step passed the end of a contact while
 *   another one still touches (angled_net: the rock leaving its main nodes while 41 N or
 *   840 N stay on others, which the test on no force at all missed: Newton then crept back
 *   from the deep side). */
static int lost_contact(cpl_loop *L, int contact_required, double e[3], double *target)
{
    const size_t n = L->n3 / 3;
    double r_lost[3] = {0.0, 0.0, 0.0};
    int any = 0;
    for (size_t j = 0; j < n; j++) {
        L->lost[j] = !node_zero(L->f_prev, j) && node_zero(L->f_dem, j);
        if (!L->lost[j]) continue;
        any = 1;
        for (int d = 0; d < 3; d++) r_lost[d] += L->f_prev[3 * j + d];
    }
    const double norm = sqrt(dot3(r_lost, r_lost));
    if (!any || !(norm > 0.0)) return 0;
    for (int d = 0; d < 3; d++) e[d] = r_lost[d] / norm;
    *target = lost_component(L, L->f_pred, e);
    if (all_zero(L->f_dem, L->n3)) {
        const int lost = contact_required || *target > 0.0;
        /* the plain exchange predicts the last force unchanged: no target to search for */
        if (!L->use_jacobian) *target = 0.0;
        return lost;
    }
    if (!L->use_jacobian) return 0;
    double r_prev[3], r_pred[3], r_now[3];
    resultant(L->f_prev, L->n3, r_prev);
    resultant(L->f_pred, L->n3, r_pred);
    resultant(L->f_dem, L->n3, r_now);
    return *target > 0.0 && norm >= CPL_LOST_SHARE * sqrt(dot3(r_prev, r_prev)) &&
           dot3(r_now, r_now) < dot3(r_pred, r_pred);
}

/* Contact backtracking (cpl_contact_search.h) after lost_contact: solves the DEM again at up
 * to contact_backtracking points of the way back from the iterate (u_in, v_in) to the last
 * one with contact (u_prev, v_prev), following the force of the nodes in L->lost along e, and
 * leaves the iterate, and the DEM's last solve, at the point the search ends at (target ≤ 0:
 * the first point where they touch again). Returns the number of DEM solves, -1 on a failed
 * one. */
static int backtrack(run_ctx *c, cpl_call *call, try_result *t, const double e[3],
                     double target)
{
    cpl_loop *L = c->L;
    const size_t n3 = L->n3;
    memcpy(L->u_end, L->u_in, n3 * sizeof(double));
    memcpy(L->v_end, L->v_in, n3 * sizeof(double));
    for (size_t i = 0; i < n3; i++) {
        L->du[i] = L->u_end[i] - L->u_prev[i];
        L->dv[i] = L->v_end[i] - L->v_prev[i];
    }
    const double start = lost_component(L, L->f_prev, e);
    cpl_contact_search search;
    /* the slope at the start: the linearisation's own prediction */
    cpl_contact_search_begin(&search, start, target > 0.0 ? target - start : NAN, target);
    int solves = 0;
    double t_last = 1.0;
    while (solves < L->s.contact_backtracking && !search.done) {
        t_last = cpl_contact_search_next(&search);
        if (solve_along(c, call, t, t_last)) return -1;
        solves++;
        int contact = 0;
        for (size_t j = 0; j < n3 / 3 && !contact; j++)
            contact = L->lost[j] && !node_zero(L->f_dem, j);
        double phi = 0.0, slope = NAN;
        if (contact) {
            phi = lost_component(L, L->f_dem, e);
            if (L->use_jacobian) {
                cpl_jacobian_apply(&L->jac, L->du, L->dv, n3, L->df);
                slope = lost_component(L, L->df, e);
            }
        }
        cpl_contact_search_add(&search, t_last, contact, phi, slope);
    }
    /* the DEM's last solve must be the iterate's: again at the best point if it was not */
    if (search.t_best >= 0.0 && search.t_best != t_last) {
        if (solve_along(c, call, t, search.t_best)) return -1;
        solves++;
    }
    return solves;
}

/* The first guess of the end-of-step interface motion (u_in, v_in) for a step of dt_s, the
 * DEM's input in iteration 1 (the DEM moves its wall from where it was to this position
 * during the step): u + Δt u̇ ("linear"); the last accepted u alone ("constant") makes the
 * wall lag a further half step behind the structure. "quadratic" adds the acceleration of
 * the parabola through the last two accepted positions with the last velocity as its slope,
 * u(−Δt₀) = u_before, u(0) = u, u̇(0) = v:
 *   u + Δt v + c Δt², v + 2 c Δt,   c = (u_before − u + Δt₀ v) / Δt₀²,
 * so that the error of the guess falls from ½ ü Δt² to O(Δt³): with the Jacobian the
 * structure's answer to iteration 1 is Newton's step from the guess, whose error falls with
 * the square of the guess's (docs/notes/interface_jacobian.md "A quadratic predictor"). Used
 * only while the step is within a factor 2 of the last one (the step control halves and
 * doubles it; a far step of efficiency option (i) would stretch one step's acceleration over
 * many), else linear. */
static void predict(cpl_loop *L, double dt_s)
{
    const size_t n3 = L->n3;
    const double dt0 = L->dt_before_s, ratio = dt0 > 0.0 ? dt_s / dt0 : 0.0;
    const int quadratic = L->s.predictor == CPL_PREDICT_QUADRATIC && ratio >= 0.5 &&
                          ratio <= 2.0;
    const double moving = L->s.predictor == CPL_PREDICT_CONSTANT ? 0.0 : 1.0;
    for (size_t i = 0; i < n3; i++) {
        const double c =
            quadratic ? (L->u_before[i] - L->u[i] + dt0 * L->v[i]) / (dt0 * dt0) : 0.0;
        L->u_in[i] = L->u[i] + moving * dt_s * L->v[i] + c * dt_s * dt_s;
        L->v_in[i] = L->v[i] + 2.0 * c * dt_s;
    }
}

/* jacobian_check (cpl_jacobian_check.h): the linearisation L->jac the structure just solved
 * with, taken by the DEM at (lin_u, lin_v), along the step to the next input (u_in, v_in):
 * two more DEM solves at lin ± ε step. The DEM's next solve is the iteration's own, so its
 * state after the step is not the probes'. *miss stays NAN where there is nothing to compare
 * (no force and no linearisation, or no step). */
static int check_linearisation(run_ctx *c, cpl_call *call, double *miss)
{
    cpl_loop *L = c->L;
    const size_t n3 = L->n3;
    *miss = NAN;
    if (L->jac.n_blocks == 0 && all_zero(L->f_dem, n3)) return 0;
    for (size_t i = 0; i < n3; i++) {
        L->du[i] = L->u_in[i] - L->lin_u[i];
        L->dv[i] = L->v_in[i] - L->lin_v[i];
    }
    const double eps = cpl_jacobian_check_epsilon(L->du, L->dv, n3, call->dt_s);
    if (!(eps > 0.0)) return 0;
    cpl_jacobian_apply(&L->jac, L->du, L->dv, n3, L->df);
    cpl_jacobian *jacobian_out = call->jacobian_out;
    const cpl_jacobian *jacobian_in = call->jacobian_in;
    cpl_compliance *compliance_out = call->compliance_out;
    const cpl_compliance *compliance_in = call->compliance_in;
    call->jacobian_out = NULL;
    call->jacobian_in = NULL;
    /* the probes ask for the DEM's force at their own positions */
    call->compliance_out = NULL;
    call->compliance_in = NULL;
    for (int side = 0; side < 2; side++) {
        const double sign = side ? -1.0 : 1.0;
        for (size_t i = 0; i < n3; i++) {
            L->probe_u[i] = L->lin_u[i] + sign * eps * L->du[i];
            L->probe_v[i] = L->lin_v[i] + sign * eps * L->dv[i];
        }
        cpl_solve_info info;
        if (do_solve(c, c->dem, call, L->probe_u, L->probe_v,
                     side ? L->probe_minus : L->probe_plus, NULL, &info))
            return -1;
        L->jac_check.solves++;
    }
    call->jacobian_out = jacobian_out;
    call->jacobian_in = jacobian_in;
    call->compliance_out = compliance_out;
    call->compliance_in = compliance_in;
    *miss = cpl_jacobian_check_miss(L->probe_plus, L->probe_minus, eps, L->df, n3);
    cpl_jacobian_check_add(&L->jac_check, *miss, call->step, call->iteration, call->time_s);
    return 0;
}

/* structure_predictor: a try after a step with contact begins with the structure's own
 * motion. The FEM solves the step under the last step's force held (L->f), with a
 * linearisation of zero blocks on the last one's nodes (L->jac: the accepted step's, or on a
 * retry the rejected try's last) so that it returns its compliance there
 * (protocol/README.md §3.4) without the answer changing. The DEM's model of
 * the structure, u_in + S (F − F_ref), then holds the structure's motion over the step
 * instead of the kinematic guess of it, which on terrain_net at 5× Δt missed it by 5e-5 m at
 * the contact nodes (docs/notes/interface_jacobian.md, "The structure's compliance in the
 * DEM", item 8). The DEM's search starts on that answer where S puts the contact nodes at
 * the guess. Returns 1 when the FEM solved, 0 when it was skipped, -1 on failure. */
static int predict_structure(run_ctx *c, cpl_call *call, try_result *t)
{
    cpl_loop *L = c->L;
    const size_t n3 = L->n3;
    const size_t nb = L->jac.n_blocks;
    if (cpl_jacobian_set(&L->predictor_jac, nb, L->jac.nodes, L->jac.stiffness, NULL, c->err))
        return -1;
    memset(L->predictor_jac.stiffness, 0, 9 * nb * sizeof(double));
    call->iteration = 1;
    call->jacobian_out = NULL;
    call->jacobian_in = &L->predictor_jac;
    call->jacobian_u = L->u;
    call->jacobian_v = L->v;
    call->compliance_in = NULL;
    call->compliance_out = &L->comp;
    const int solved = fem_solve_or_skip(c, call, L->f, t->fem_solved, &t->fem_info);
    call->compliance_out = NULL;
    call->jacobian_in = NULL;
    if (solved <= 0) return solved;
    t->fem_solved = 1;
    L->timing.structure_predictions++;
    /* the point of the structure's linear answer with the compliance nodes at the kinematic
     * guess (u_in, predict()): under L->f + dF with S dF = guess − answer there. Begun at
     * the answer itself (L->f), the DEM's search failed from 4 kN off on terrain_net's rock
     * resting in the net (restitution 0.1, its Δt), where from the guess it starts within
     * 0.2 kN; a singular S leaves it at the answer. */
    const cpl_compliance *cp = &L->comp;
    const size_t k3 = 3 * cp->n_nodes;
    int on_line = cp->valid && cp->has_interface && k3 > 0;
    if (on_line) {
        for (size_t q = 0; q < k3; q++) {
            const size_t dof = 3 * (size_t)cp->nodes[q / 3] + q % 3;
            L->dv[q] = L->u_in[dof] - L->u_out[dof];
        }
        nc_error singular;   /* a singular S: the answer itself, nothing to report */
        on_line = cpl_compliance_force_for(cp, L->dv, L->df, &singular) == 0;
    }
    memcpy(L->comp_f_lin, L->f, n3 * sizeof(double));
    if (on_line) {
        cpl_compliance_answer(cp, L->df, L->du);
        for (size_t q = 0; q < k3; q++)
            L->comp_f_lin[3 * (size_t)cp->nodes[q / 3] + q % 3] += L->df[q];
        for (size_t i = 0; i < n3; i++) {
            L->u_in[i] = L->u_out[i] + L->du[i];
            L->v_in[i] = L->v_out[i] + cp->velocity_per_m * L->du[i];
        }
    }
    /* else (no rows in this reply, or S singular) the kinematic guess stays the DEM's input
     * under the last force, as without the predictor, but with S fresh */
    /* the force the structure balances at the input, whatever the position: comp_f_lin */
    memcpy(L->comp_u_lin, L->u_in, n3 * sizeof(double));
    memcpy(L->comp_v_lin, L->v_in, n3 * sizeof(double));
    if (cpl_jacobian_set(&L->comp_jac, 0, NULL, NULL, NULL, c->err)) return -1;
    return 1;
}

/* One try of the step of `call`: BEGIN_STEP, the iterations, no ACCEPT_STEP. Returns -1 on a
 * failure that ends the run, else 0 with the outcome in t. */
static int run_step(run_ctx *c, cpl_call *call, try_result *t)
{
    cpl_loop *L = c->L;
    const int strong = L->s.scheme == CPL_SCHEME_STRONG;
    const int force_mode = strong && L->s.relaxed == CPL_RELAXED_FORCE;
    const size_t n3 = L->n3;
    t->outcome = TRY_UNCONVERGED;
    t->iterations = 0;
    t->residual = NAN;
    t->fem_solved = 0;
    t->dem_info = (cpl_solve_info){1, INFINITY, 0.0, NAN, cpl_energy_report_none(), 0.0};
    t->fem_info = t->dem_info;
    t->jacobian_dropped = 0;
    t->by_work_test = 0;
    t->by_estimate = 0;

    const int lazy_fem = L->s.skip_fem_without_contact;
    if (command_both(c, CPL_COMMAND_BEGIN_STEP, call, !lazy_fem)) return -1;
    if (strong) cpl_relax_begin_step(L->relax);

    predict(L, call->dt_s);
    memcpy(L->f_in, L->f, n3 * sizeof(double));
    const int max_it = strong ? L->s.max_iterations : 1;
    int converged = 0, slow = 0, k;
    double ratios[CPL_SLOW_WINDOW + 1];     /* tolerance ratios of the last iterations */
    int backtrack_prev = 0;                 /* u_prev, v_prev, f_prev, f_pred are set */
    int fem_answer_plain = 0;               /* u_out, v_out are the FEM's answer in this try
                                               to the force f_in without a linearisation */
    int free_seen = 0;                      /* an iterate of this try had no contact */
    int contact_required = 0;               /* ... and a later one had contact again */
    double rv_prev = NAN;                   /* r_u̇ of the last iteration when this
                                               iteration's input is that iteration's FEM
                                               answer unchanged (α = 1), else NAN */
    int compliance_on = L->use_compliance;  /* off for the rest of the try once the DEM's
                                               search with it ended a contact the structure
                                               still carried */
    L->timing.compliance_tries += compliance_on;
    int compliance_asked = 0;               /* the FEM gave its compliance in this try */
    const int check_due = L->use_jacobian && !force_mode && L->s.jacobian_check_interval > 0 &&
                          call->step % L->s.jacobian_check_interval == 0;
    if (strong && !force_mode && compliance_on && L->s.structure_predictor &&
        L->comp.has_interface && L->jac.n_blocks > 0 && !all_zero(L->f, n3)) {
        const int solved = predict_structure(c, call, t);
        if (solved < 0) return try_failed(c, t);
        compliance_asked = solved;
    }
    for (k = 1; k <= max_it; k++) {
        call->iteration = k;
        t->iterations = k;
        L->timing.iterations++;
        /* DEM with the current interface position and velocity -> contact forces (and their
         * linearisation, which the FEM then solves with: interface-Jacobian coupling) */
        call->jacobian_out = L->use_jacobian ? &L->jac : NULL;
        call->jacobian_in = NULL;
        /* the nodes a contact may reach matter only to the structure's compliance */
        call->proximity = compliance_on && L->s.compliance_proximity;
        if (compliance_on) {
            call->compliance_in = &L->comp;
            call->compliance_out = &L->comp;
            compliance_reference(L, t->fem_solved);
        } else {
            call->compliance_in = NULL;
            call->compliance_out = NULL;
            L->comp.wall_valid = 0;
        }
        if (do_solve(c, c->dem, call, L->u_in, L->v_in, L->f_dem, NULL, &t->dem_info))
            return try_failed(c, t);
        /* the DEM's model of the structure, S about the try's first solve, let it end every
         * contact although the structure's own linearisation about the last iterate with
         * contact still predicted force where one ended (lost_contact): the two disagree
         * there, and the DEM would keep answering zero; the rest of the try without the
         * compliance, the DEM solved again at the iterate itself, and contact backtracking
         * from there (docs/notes/interface_jacobian.md, item 7) */
        if (compliance_on && L->comp.wall_valid && backtrack_prev && all_zero(L->f_dem, n3)) {
            double e[3], target;
            if (lost_contact(L, 0, e, &target)) {
                compliance_on = 0;
                L->timing.compliance_dropped++;
                cpl_relax_forget(L->relax, CPL_RELAX_FORGET_PAIR);   /* the map changes */
                call->compliance_in = NULL;
                call->compliance_out = NULL;
                call->proximity = 0;
                L->comp.wall_valid = 0;
                if (do_solve(c, c->dem, call, L->u_in, L->v_in, L->f_dem, NULL, &t->dem_info))
                    return try_failed(c, t);
            }
        }
        /* with the structure's compliance the DEM chose where its wall ends: that is the
         * iteration's interface position, its velocity the structure's at that position
         * (protocol/README.md §3.4); the error estimate then measures the step between the
         * structure's answers from the last answer, where the input came from */
        const int wall_moved = compliance_on && L->comp.wall_valid;
        if (wall_moved) {
            move_free_nodes(L);
            memcpy(L->v_answer, L->v_in, n3 * sizeof(double));
            for (size_t i = 0; i < n3; i++) {
                L->v_in[i] += L->comp.velocity_per_m * (L->comp.u_wall[i] - L->u_in[i]);
                L->u_in[i] = L->comp.u_wall[i];
            }
        }
        /* the step went past a contact's end: the iterate lost the contact although the
         * linearisation about the last iterate with contact still predicted its force, or
         * although this step's contact-free answer was already seen to collide
         * (lost_contact); search back along the step towards that iterate (the DEM alone is
         * solved again) so that the FEM keeps a linearisation of the contact (not after a
         * move of the DEM's own: its no-contact answer is then the one it found consistent) */
        const int no_contact = all_zero(L->f_dem, n3);
        if (!no_contact && free_seen) contact_required = 1;
        double lost_e[3], lost_target;
        if (backtrack_prev && !wall_moved &&
            lost_contact(L, contact_required, lost_e, &lost_target)) {
            const int solves = backtrack(c, call, t, lost_e, lost_target);
            if (solves < 0) return try_failed(c, t);
            if (solves) {
                cpl_relax_forget(L->relax, CPL_RELAX_FORGET_PAIR);
                rv_prev = NAN;
            }
        }
        if (all_zero(L->f_dem, n3)) free_seen = 1;
        /* the linearisation the FEM solves with is the last DEM solve's */
        /* (a participant's number: NaN and infinities are ignored, huge ones capped) */
        const double dropped = t->dem_info.jacobian_dropped;
        if (L->use_jacobian && isfinite(dropped) && dropped > t->jacobian_dropped)
            t->jacobian_dropped = dropped > 1e9 ? 1000000000 : (int)dropped;
        call->jacobian_out = NULL;
        if (L->use_jacobian) {
            call->jacobian_in = &L->jac;
            call->jacobian_u = L->u_in;
            call->jacobian_v = L->v_in;
        }
        if (!force_mode) {
            /* weak, or algorithm 2: forces go to the structure unrelaxed, eq. (39) */
            const int plain_input = !L->use_jacobian || L->jac.n_blocks == 0;
            int solved, fem_answer = 1;   /* u_out, v_out are the FEM's answer to this input */
            if (fem_answer_plain && plain_input && same_values(L->f_dem, L->f_in, n3)) {
                /* the FEM's input is the one it last solved with in this try (typically no
                 * contact in either iteration): a participant answers the same input with
                 * the same reply (protocol/README.md §3 solve), which u_out, v_out hold */
                solved = 0;
                L->timing.fem_repeats_skipped++;
            } else {
                /* the structure's compliance: at the try's first FEM solve, and again when
                 * the contact reaches a node it does not cover; the structure's tangent
                 * changes little within a step, and each S costs the FEM a factorisation and
                 * 3 solves per node (cases/steel_net: FEM 2.1 -> 1.5 s, the iterations the
                 * same: 3.08 -> 3.06 per contact step) */
                const int refresh = compliance_on &&
                    (!compliance_asked || !L->comp.valid || L->comp.dt_s != call->dt_s ||
                     !compliance_covers(&L->comp, &L->jac));
                call->compliance_out = refresh ? &L->comp : NULL;
                solved = fem_solve_or_skip(c, call, L->f_dem, t->fem_solved, &t->fem_info);
                call->compliance_out = compliance_on ? &L->comp : NULL;
                if (solved < 0) return try_failed(c, t);
                if (solved && refresh) compliance_asked = 1;
                if (solved && compliance_on) {
                    memcpy(L->comp_u_lin, L->u_in, n3 * sizeof(double));
                    memcpy(L->comp_v_lin, L->v_in, n3 * sizeof(double));
                    memcpy(L->comp_f_lin, L->f_dem, n3 * sizeof(double));
                    if (cpl_jacobian_set(&L->comp_jac, L->jac.n_blocks, L->jac.nodes,
                                         L->jac.stiffness,
                                         L->jac.has_damping ? L->jac.damping : NULL, c->err))
                        return try_failed(c, t);
                }
                if (solved) fem_answer_plain = plain_input;
                fem_answer = solved;   /* skipped without contact: the accepted motion */
            }
            t->fem_solved |= solved;
            memcpy(L->f_in, L->f_dem, n3 * sizeof(double));
            double rv;
            t->residual = residual_uv(L, call->dt_s, fem_answer ? rv_prev : NAN,
                                      wall_moved ? L->v_answer : NULL, &converged,
                                      &t->by_work_test, &t->by_estimate,
                                      &ratios[k % (CPL_SLOW_WINDOW + 1)], &rv);
                                                               /* eqs. (28), (29), (35) */
            slow = strong && !converged && too_slow(L, ratios, k, call->dt_s);
            if (!strong || converged || k == max_it || slow) {
                if (report_iteration(c, call, t->residual, NAN, solved, NAN)) return -1;
                break;
            }
            double alpha;
            backtrack_prev = L->s.contact_backtracking > 0 && !all_zero(L->f_dem, n3);
            if (backtrack_prev) {
                memcpy(L->u_prev, L->u_in, n3 * sizeof(double));
                memcpy(L->v_prev, L->v_in, n3 * sizeof(double));
                memcpy(L->f_prev, L->f_dem, n3 * sizeof(double));
            }
            if (check_due) {
                memcpy(L->lin_u, L->u_in, n3 * sizeof(double));
                memcpy(L->lin_v, L->v_in, n3 * sizeof(double));
            }
            pack(L, L->x_in, L->u_in, L->v_in);
            pack(L, L->x_out, L->u_out, L->v_out);
            if (cpl_relax_update(L->relax, L->x_in, L->x_out, L->x_in, &alpha, c->err)) {
                int code = c->err->code;                       /* eqs. (31), (32), (34) */
                fail(c, NULL, call, "relaxation");
                if (code != CPL_RELAX_ERR_NOT_FINITE) return -1;
                t->outcome = TRY_DIVERGED;
                return 0;
            }
            unpack(L, L->x_in, L->u_in, L->v_in);              /* eqs. (40), (41) */
            /* the estimate's contraction is that of Newton's iterates: only when the next
             * input is this answer itself (a full step of every block, not a restart from an
             * older iterate, whatever α the method reports) */
            rv_prev = fem_answer && same_within(L->u_in, L->u_out, n3) &&
                              same_within(L->v_in, L->v_out, n3)
                          ? rv : NAN;
            if (backtrack_prev)
                predicted_force(L, L->f_dem, L->u_prev, L->v_prev, L->u_in, L->v_in, L->f_pred);
            double miss = NAN;
            if (check_due && check_linearisation(c, call, &miss)) return try_failed(c, t);
            if (report_iteration(c, call, t->residual, alpha, solved, miss)) return -1;
        } else {
            /* algorithm 3: residual and relaxation of the forces, then the structure */
            t->residual = cpl_residual(L->f_dem, L->f_in, L->r, n3);       /* eqs. (30), (36) */
            const double norm = cpl_scaled_norm(L->f_dem, n3);
            converged = cpl_converged(t->residual, norm, L->s.tol_abs, L->s.tol_rel);
            ratios[k % (CPL_SLOW_WINDOW + 1)] = tolerance_ratio(L, t->residual, norm);
            if (!converged && too_slow(L, ratios, k, call->dt_s)) {
                if (report_iteration(c, call, t->residual, NAN, 0, NAN)) return -1;
                slow = 1;
                break;
            }
            double alpha;
            if (cpl_relax_update(L->relax, L->f_in, L->f_dem, L->f_in, &alpha, c->err)) {
                int code = c->err->code;                                   /* eqs. (33), (34) */
                fail(c, NULL, call, "relaxation");
                if (code != CPL_RELAX_ERR_NOT_FINITE) return -1;
                t->outcome = TRY_DIVERGED;
                return 0;
            }
            /* iteration 1 evaluated the DEM at the predicted position, not at the FEM's
             * answer to the previous relaxed force: no secant information in this pair */
            if (k == 1) cpl_relax_forget(L->relax, CPL_RELAX_FORGET_PAIR);
            int solved = fem_solve_or_skip(c, call, L->f_in, t->fem_solved, &t->fem_info); /* eq. (42) */
            if (solved < 0) return try_failed(c, t);
            t->fem_solved |= solved;
            if (report_iteration(c, call, t->residual, alpha, solved, NAN)) return -1;
            if (converged || k == max_it) break;
            memcpy(L->u_in, L->u_out, n3 * sizeof(double));                /* eqs. (37), (38) */
            memcpy(L->v_in, L->v_out, n3 * sizeof(double));
        }
    }
    call->jacobian_in = NULL;
    t->outcome = converged ? TRY_CONVERGED : slow ? TRY_SLOW : TRY_UNCONVERGED;
    return 0;
}

/* Tells the observer that a try was rejected; c->err holds the failure of DIVERGED and
 * STEP_FAILED tries. */
static int report_reject(run_ctx *c, const cpl_call *call, const try_result *t, double next_dt)
{
    if (!c->obs || !c->obs->on_reject) return 0;
    char message[NC_ERROR_MESSAGE_MAX] = "";
    if (t->outcome == TRY_DIVERGED || t->outcome == TRY_FAILED)
        snprintf(message, sizeof message, "%s", c->err->message);
    cpl_reject_record rec = {
        .step = call->step, .attempt = c->attempt, .time_s = call->time_s, .dt_s = call->dt_s,
        .next_dt_s = next_dt, .iterations = t->iterations, .residual = t->residual,
        .reason = t->outcome == TRY_UNCONVERGED ? CPL_REJECT_NOT_CONVERGED
                  : t->outcome == TRY_SLOW      ? CPL_REJECT_TOO_SLOW
                  : t->outcome == TRY_DIVERGED  ? CPL_REJECT_DIVERGED
                                                : CPL_REJECT_STEP_FAILED,
        .message = message};
    nc_error_clear(c->err);
    if (c->obs->on_reject(c->obs->ctx, &rec, c->err)) return fail(c, NULL, call, "history");
    return 0;
}

/* Appends to a failure message that the step was already retried down to dt_min. */
static void note_retries(run_ctx *c, int rejected, double dt)
{
    if (rejected == 0) return;
    size_t used = strlen(c->err->message);
    snprintf(c->err->message + used, sizeof c->err->message - used,
             " (after %d rejected tries with smaller steps, at dt = %g s = dt_min)", rejected, dt);
}

/* One accepted step, after as many rejected tries as the step control allows. */
static int advance_step(run_ctx *c)
{
    cpl_loop *L = c->L;
    const int strong = L->s.scheme == CPL_SCHEME_STRONG;
    const size_t n3 = L->n3;
    int ends;
    double dt = choose_dt(L, &ends);
    cpl_call call;
    try_result t;
    for (c->attempt = 0;; c->attempt++) {
        call = (cpl_call){.step = L->step, .iteration = 0, .time_s = L->time_s, .dt_s = dt};
        if (run_step(c, &call, &t)) return -1;
        if (t.outcome == TRY_CONVERGED || (!strong && t.outcome == TRY_UNCONVERGED)) break;
        int level = L->level;
        double next = retry_dt(L, dt, &level);
        if (next == 0.0) break;                         /* at dt_min: decided below */
        /* rejected: the participants restore on the repeated BEGIN_STEP; the relaxation's
         * history (of this try, and IQN columns of another Δt) would mislead the retry */
        if (strong) cpl_relax_forget(L->relax, CPL_RELAX_FORGET_HISTORY);
        L->timing.rejected_attempts++;
        if (t.outcome == TRY_SLOW) L->timing.slow_rejections++;
        if (report_reject(c, &call, &t, next)) return -1;
        memset(c->failure, 0, sizeof *c->failure);
        if (L->level == 0 && level > 0) L->grid_origin_s = L->time_s;
        L->level = level;
        L->converged_run = 0;
        dt = next;
        ends = 0;
    }
    const int rejected = c->attempt;
    if (t.outcome == TRY_FAILED || t.outcome == TRY_DIVERGED) {
        note_retries(c, rejected, dt);
        return -1;
    }
    const int converged = t.outcome == TRY_CONVERGED;
    if (strong && !converged) {
        L->timing.unconverged_steps++;
        if (L->s.on_max_iterations == CPL_MAXIT_STOP) {
            nc_error_set(c->err, CPL_ERR_NOT_CONVERGED,
                         "interface residual %.3e still above the tolerance %.3e after %d "
                         "iterations (max_iterations policy \"stop\")", t.residual, L->s.tol_abs,
                         t.iterations);
            note_retries(c, rejected, dt);
            return fail(c, NULL, &call, "convergence");
        }
    }
    if (strong && !converged) {
        cpl_relax_forget(L->relax, CPL_RELAX_FORGET_HISTORY);   /* do not carry a failed step's model along */
    } else if (strong) {
        if (L->s.relaxed == CPL_RELAXED_FORCE) {
            cpl_relax_end_step(L->relax, NULL, NULL);
        } else {
            pack(L, L->x_in, L->u_in, L->v_in);
            pack(L, L->x_out, L->u_out, L->v_out);
            cpl_relax_end_step(L->relax, L->x_in, L->x_out);
        }
    }
    call.iteration = 0;
    const int lazy_fem = L->s.skip_fem_without_contact;
    if (command_both(c, CPL_COMMAND_ACCEPT_STEP, &call, !lazy_fem || t.fem_solved))
        return -1;

    /* the structure's end state is the start of the next step */
    memcpy(L->u_before, L->u, n3 * sizeof(double));
    L->dt_before_s = dt;
    memcpy(L->u, L->u_out, n3 * sizeof(double));
    memcpy(L->v, L->v_out, n3 * sizeof(double));
    memcpy(L->f, L->f_in, n3 * sizeof(double));
    L->time_s = ends ? L->s.end_time_s : L->time_s + dt;
    L->step++;
    L->last_near = t.dem_info.near_interface;
    L->timing.steps++;
    if (!ends) L->timing.min_dt_s = fmin(L->timing.min_dt_s, dt);
    if (rejected) L->timing.reduced_steps++;
    if (t.jacobian_dropped > 0) L->timing.jacobian_dropped_steps++;
    if (strong && converged && t.by_work_test) L->timing.work_test_steps++;
    if (strong && converged && t.by_estimate) L->timing.estimate_steps++;
    cpl_energy_record energy;
    cpl_energy_step(&L->energy, call.step, L->time_s, t.fem_solved ? &t.fem_info.energy : NULL,
                    &t.dem_info.energy, &energy);
    cpl_impulse_step(&L->impulse, call.step, L->time_s, dt, L->f_dem,
                     t.fem_solved && linearised_correction(L) ? L->correction : NULL, n3 / 3);

    /* step control: a reduced Δt doubles after grow_after good steps in a row, once the
     * time is on the grid of the larger step (counted from where the reduction began) */
    if (strong && !converged) {
        L->converged_run = 0;
    } else if (L->level > 0 && ++L->converged_run >= L->s.grow_after) {
        double cells = (L->time_s - L->grid_origin_s) / ldexp(L->s.dt_s, 1 - L->level);
        if (fabs(cells - nearbyint(cells)) < 1e-6) {
            L->level--;
            L->converged_run = 0;
        }
    }

    if (c->obs && c->obs->on_step) {
        cpl_step_record rec = {.step = call.step, .time_s = L->time_s, .dt_s = dt,
                               .iterations = t.iterations, .converged = converged,
                               .residual = t.residual,
                               .near_interface = t.dem_info.near_interface,
                               .min_gap_m = t.dem_info.min_gap_m, .rejected = rejected,
                               .energy = energy,
                               .jacobian_blocks = L->use_jacobian ? (int)L->jac.n_blocks : -1,
                               .jacobian_dropped = t.jacobian_dropped};
        cpl_total_force(L->f_dem, n3 / 3, rec.contact_force);
        rec.in_contact = cpl_max_abs(L->f_dem, n3) > L->s.contact_force_threshold_n;
        if (c->obs->on_step(c->obs->ctx, &rec, c->err)) return fail(c, NULL, &call, "history");
    }
    /* the step is accepted and recorded: the results up to it stay readable */
    if (L->s.stop_on_energy_growth && energy.above &&
        L->time_s < L->s.end_time_s - 1e-9 * L->s.dt_s) {   /* the last step simply ends */
        nc_error_set(c->err, CPL_ERR_ENERGY_GROWTH, "the energy guard fired: the run has created "
                     "%.6g J of energy, above the limit %.6g J; stopped here "
                     "(coupler.json stop_on_energy_growth)", energy.created_j, energy.limit_j);
        return fail(c, NULL, &call, "energy guard");
    }
    return 0;
}

int cpl_loop_run(cpl_loop *L, const cpl_participant *fem, const cpl_participant *dem,
                 const cpl_observer *observer, const volatile sig_atomic_t *stop,
                 cpl_failure *failure, nc_error *err)
{
    cpl_failure dummy;
    if (!failure) failure = &dummy;
    memset(failure, 0, sizeof *failure);
    run_ctx c = {L, fem, dem, observer, stop, failure, err, 0, nc_clock_now_s()};
    /* not with relaxed forces: the FEM's answer then depends on the linearisation point as
     * well as on the relaxed force, and a secant model of the force map alone misleads
     * (coupler/README.md, "Interface Jacobian") */
    L->use_jacobian = cpl_loop_settings_jacobian_applies(&L->s) && fem->can_jacobian &&
                      dem->can_jacobian;
    if (L->relax) cpl_relax_set_linearised(L->relax, L->use_jacobian);
    L->use_compliance = L->use_jacobian && L->s.interface_compliance && fem->can_compliance &&
                        dem->can_compliance;
    int rc = 0;
    if (L->resume_pending) {
        cpl_call call = {.step = L->step, .iteration = 0, .time_s = L->time_s, .dt_s = 0.0};
        const cpl_participant *both[2] = {fem, dem};
        for (int i = 0; i < 2 && rc == 0; i++) {
            if (!both[i]->resume) {
                nc_error_set(err, 1, "cannot resume: the participant does not announce the "
                             "capability 'checkpoint'");
                rc = fail(&c, both[i], &call, "resume");
            } else {
                rc = do_checkpoint(&c, both[i], &call, L->resume_name, 1);
            }
        }
        if (rc == 0) L->resume_pending = 0;
    }
    const double eps = 1e-9 * L->s.dt_s;
    while (rc == 0 && L->time_s < L->s.end_time_s - eps &&
           (L->s.max_steps <= 0 || L->step < L->s.max_steps)) {
        if ((rc = advance_step(&c)) != 0 || (rc = maybe_checkpoint(&c)) != 0) break;
    }
    L->timing.total_s += nc_clock_now_s() - c.clock_s;
    return rc;
}
