/* fem_coupled — the FEM as the netcouple protocol participant "fem": its handlers of the serve
 * loop (protocol/proto_serve.h). INTERFACE replies the interface mesh, BEGIN_STEP saves the
 * start-of-step state (the coupler owns time), a repeated SOLVE restores it (the loop decides
 * when) and, with the same dt, starts Newton from the previous solution, SOLVE takes the
 * interface force and replies displacement + velocity, ACCEPT_STEP
 * writes monitor and output rows when due. A run ended inside a solved but not accepted step
 * writes the last accepted state. See fem_run.h.
 * Interface-Jacobian coupling (capability "jacobian", protocol/README.md §3.1): a SOLVE that
 * carries the DEM's linearisation solves with F(u, v) = force - K (u - u^k) - C (v - v^k)
 * (fem_analysis_set_linearisation); one without it, with the constant force. A Newton failure
 * is answered as retryable: the coupler may try the step again with a smaller dt.
 * The structure's compliance (capability "compliance", protocol/README.md §3.4): such a SOLVE
 * with the value "compliance" 1 also replies S = du/dF at the nodes of the linearisation's
 * blocks (fem_analysis_compliance), for the DEM's next solves.
 * Checkpoint and resume (capability "checkpoint", protocol/README.md §3.3): CHECKPOINT saves
 * the complete state (fem_checkpoint.h) as DIR/checkpoint/fem_<name>.h5; RESUME loads one
 * and reopens fem.h5 cut back to the rows written at that checkpoint. So that a resumed run
 * finds its results intact, fem.h5 and fem.xdmf are created only at the first BEGIN_STEP
 * (with the initial state as their first rows), never before.
 * A run that starts in static equilibrium (analysis.initial_state "static") gives the coupler
 * the interface where that equilibrium has it as its coordinates, and every displacement from
 * there: for the other programs the net starts at rest where it hangs.
 */
#include "fem_run.h"
#include "fem_checkpoint.h"
#include "fem_output.h"
#include "fem_linearisation_psd.h"
#include "nc_file.h"
#include "nc_clock.h"
#include "proto_serve.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

typedef struct coupled {
    const fem_model *m;
    fem_analysis s;
    fem_output out;
    fem_run_summary *sum;
    fem_settle_watch settle_watch; /* progress and stop of the initial equilibrium */
    int32_t *node_ids;
    double *iface_X, *iface_u, *iface_v;
    double *iface_u0;         /* [3n] where the start state has the interface nodes (the static
                                 equilibrium of analysis.initial_state, else 0): the protocol's
                                 coordinates are X + u0 and its displacements u - u0 */
    double *ckpt_u0;          /* [3n] iface_u0 as a checkpoint holds it: a resumed run must
                                 start from the same u0 as the run it continues */
    double *lin_u, *lin_v;    /* [ndof] the linearisation point on the model's dofs */
    int *lin_nodes;           /* [2 blocks] model node numbers of the received blocks */
    size_t lin_cap;
    fem_psd psd;              /* the blocks the FEM solves with */
    double *guess_u;          /* [ndof] the last solution of this step, Newton's start when
                                 the step is solved again with the same dt */
    double guess_dt_s;        /* its dt; 0: none (a new step, a resume) */
    const char *dir;          /* output folder */
    long written_step;
    double next_output_s;     /* time of the next full output */
    nc_ckpt_table run_entries; /* what of this driver a checkpoint holds */
    char first_failure[PROTO_TEXT_MAX];   /* the first error reply, for the final message */
    int32_t *comp_nodes;      /* the compliance of the last reply (interface nodes, [3k x 3k]
                                 m/N, and every interface dof's row [3n x 3k]): the reply
                                 points to them */
    double *comp_S, *comp_rows;
} coupled;

static int on_interface(void *ctx, const proto_message *cmd, proto_message *reply, nc_error *err)
{
    (void)cmd;
    coupled *c = ctx;
    const fem_model *m = c->m;
    size_t n = (size_t)m->n_iface_nodes, e = (size_t)m->n_iface_elements;
    if (proto_message_add_i32(reply, "node_ids", c->node_ids, n, 0, err) ||
        proto_message_add_f64(reply, "coordinates", c->iface_X, n, 3, err) ||
        proto_message_add_i32(reply, "elements", (const int32_t *)m->iface_conn, e, 2, err))
        return -1;
    return 0;
}

/* A fresh run's results: fem.h5 and fem.xdmf with the initial state as their first rows
 * (monitor and output at t = 0). Created at the first BEGIN_STEP (or CHECKPOINT) and not
 * before, so that a run about to RESUME never truncates the results it continues. */
static int start_output(coupled *c, nc_error *err)
{
    if (c->out.open) return 0;
    if (fem_output_open(&c->out, c->m, c->dir, err) ||
        fem_output_monitor(&c->out, &c->s, 0.0, err) || fem_output_step(&c->out, &c->s, 0.0, err)) {
        fem_output_close(&c->out);   /* the next BEGIN_STEP tries again */
        c->out.max_u_node = -1;
        return -1;
    }
    c->written_step = 0;
    return 0;
}

static int on_save(void *ctx, const proto_message *cmd, nc_error *err)
{
    coupled *c = ctx;
    if (start_output(c, err)) return -1;
    if (isfinite(cmd->time_s)) c->s.cur.time_s = cmd->time_s;   /* the coupler owns time */
    c->guess_dt_s = 0;
    return fem_analysis_save(&c->s, err);
}

static int on_restore(void *ctx, const proto_message *cmd, nc_error *err)
{
    (void)cmd;
    coupled *c = ctx;
    return fem_analysis_restore(&c->s, err);
}

/* The linearisation of the coupling force that `cmd` carries (or none): interface node
 * indices become model nodes, the point u^k, v^k goes onto the model's dofs. With `project`
 * its positive semi-definite part, else its symmetric part. */
static int set_linearisation(coupled *c, const proto_message *cmd, int project, nc_error *err)
{
    const fem_model *m = c->m;
    fem_analysis *s = &c->s;
    if (!proto_message_find(cmd, "jacobian_nodes")) {
        fem_analysis_clear_linearisation(s);
        return 0;
    }
    size_t n = (size_t)m->n_iface_nodes, b = 0;
    const int32_t *nodes;
    const double *K, *C = NULL, *u_k, *v_k;
    if (proto_message_get_i32(cmd, "jacobian_nodes", 0, 2, &nodes, &b, err) ||
        proto_message_get_f64(cmd, "jacobian_stiffness", b, 9, &K, NULL, err) ||
        (proto_message_find(cmd, "jacobian_damping") &&
         proto_message_get_f64(cmd, "jacobian_damping", b, 9, &C, NULL, err)) ||
        proto_message_get_f64(cmd, "jacobian_displacement", n, 3, &u_k, NULL, err) ||
        proto_message_get_f64(cmd, "jacobian_velocity", n, 3, &v_k, NULL, err))
        return -1;
    /* The full K, in the residual and, through GMRES around the factorisation of the
     * symmetric matrix, in every Newton step (fem_analysis_set_linearisation): the FEM then
     * solves the linearised problem exactly, and the interface iteration is Newton's method
     * (with only the symmetric part it converged linearly, at the rate of the skew part:
     * friction, the closest point sliding along an edge, the rock's lever;
     * docs/notes/interface_jacobian.md). With `project` (a retry after a Newton failure)
     * the positive semi-definite part of the symmetric part (fem_linearisation_psd.h), in
     * both: the rest is left to the interface iteration. */
    if (b > c->lin_cap) {
        int *nn = realloc(c->lin_nodes, 2 * b * sizeof *nn);
        if (!nn) return nc_error_set(err, 1, "out of memory for %zu Jacobian blocks", b);
        c->lin_nodes = nn;
        c->lin_cap = b;
    }
    for (size_t k = 0; k < b; k++)
        for (int e = 0; e < 2; e++) {
            if (nodes[2 * k + e] < 0 || (size_t)nodes[2 * k + e] >= n)
                return nc_error_set(err, 1, "jacobian_nodes row %zu: %d is not an interface "
                                    "node (0..%zu)", k, (int)nodes[2 * k + e], n - 1);
            c->lin_nodes[2 * k + e] = m->iface_nodes[nodes[2 * k + e]];
        }
    if (project && fem_psd_project(&c->psd, b, c->lin_nodes, K, C, err)) return -1;
    for (size_t i = 0; i < n; i++)
        for (int d = 0; d < 3; d++) {
            c->lin_u[3 * m->iface_nodes[i] + d] = u_k[3 * i + d] + c->iface_u0[3 * i + d];
            c->lin_v[3 * m->iface_nodes[i] + d] = v_k[3 * i + d];
        }
    if (!project)
        return fem_analysis_set_linearisation(s, c->lin_u, c->lin_v, (int)b, c->lin_nodes, K, C,
                                              err);
    return fem_analysis_set_linearisation(s, c->lin_u, c->lin_v, (int)c->psd.n_blocks,
                                          c->psd.nodes, c->psd.K, C ? c->psd.C : NULL, err);
}

/* A dynamic step of dt. Solved again with the same dt (the next interface iteration), Newton
 * starts from the previous solution: the interface force changed by the iteration's
 * correction only, which late in the iteration is small, so it needs one or two Newton
 * iterations instead of the four to six it needs from the start-of-step displacement. If that
 * start fails, the step is solved from the start-of-step state as a first solve would be. */
static int step_from_guess(coupled *c, double dt, nc_error *err)
{
    fem_analysis *s = &c->s;
    if (c->guess_dt_s == dt) {
        if (fem_analysis_step_from(s, dt, c->guess_u, err) == 0) return 0;
        if (err->code != FEM_ERR_NEWTON) return -1;
        c->sum->warm_start_fallbacks++;
        c->sum->newton_iterations += s->stats.iterations;   /* work done, if in vain */
        /* the failed Newton left its factorisation: start again from the saved one, so that
         * the fallback is the cold solve bit for bit */
        if (fem_analysis_restore(s, err)) return -1;
    }
    return fem_analysis_step(s, dt, err);
}

/* The structure's compliance at the interface nodes the linearisation of `cmd` touches
 * (capability "compliance", protocol/README.md §3.4): "compliance_nodes" [k] interface
 * indices, "compliance" [3k x 3k] m/N, "compliance_interface" [3n x 3k] m/N (how every
 * interface node answers the same forces), "compliance_velocity_per_m" (dv/du at the step's
 * end). Nothing when the linearisation has no block. */
static int add_compliance(coupled *c, const proto_message *cmd, proto_message *reply, nc_error *err)
{
    const fem_model *m = c->m;
    const int32_t *nodes;
    size_t b = 0;
    if (proto_message_get_i32(cmd, "jacobian_nodes", 0, 2, &nodes, &b, err)) return -1;
    if (b == 0) return 0;
    int32_t *list = malloc(2 * b * sizeof *list);
    if (!list) return nc_error_set(err, 1, "out of memory for the compliance's nodes");
    size_t k = 0;
    for (size_t q = 0; q < 2 * b; q++) {
        size_t t = 0;
        while (t < k && list[t] != nodes[q]) t++;
        if (t == k) list[k++] = nodes[q];
    }
    const int nd = (int)(3 * k), nr = 3 * m->n_iface_nodes;
    int *dofs = malloc((size_t)(nd + nr) * sizeof *dofs);
    double *S = malloc((size_t)nd * (size_t)nd * sizeof *S);
    double *rows = malloc((size_t)nr * (size_t)nd * sizeof *rows + 1);
    if (!dofs || !S || !rows) {
        free(list); free(dofs); free(S); free(rows);
        return nc_error_set(err, 1, "out of memory for the compliance of %zu nodes", k);
    }
    for (size_t q = 0; q < k; q++)
        for (int d = 0; d < 3; d++) dofs[3 * q + d] = 3 * m->iface_nodes[list[q]] + d;
    for (int i = 0; i < m->n_iface_nodes; i++)
        for (int d = 0; d < 3; d++) dofs[nd + 3 * i + d] = 3 * m->iface_nodes[i] + d;
    const int rc = fem_analysis_compliance(&c->s, nd, dofs, S, nr, dofs + nd, rows, err);
    free(dofs);
    free(c->comp_nodes);
    free(c->comp_S);
    free(c->comp_rows);
    c->comp_nodes = list;
    c->comp_S = S;
    c->comp_rows = rows;
    if (rc || proto_message_add_i32(reply, "compliance_nodes", c->comp_nodes, k, 1, err) ||
        proto_message_add_f64(reply, "compliance", c->comp_S, (size_t)nd, (size_t)nd, err) ||
        proto_message_add_f64(reply, "compliance_interface", c->comp_rows, (size_t)nr,
                              (size_t)nd, err) ||
        proto_message_set_value(reply, "compliance_velocity_per_m", c->s.last_velocity_per_m, err))
        return -1;
    return 0;
}

/* Solves the step with the interface force of `cmd`; fills the reply arrays. */
static int solve(coupled *c, const proto_message *cmd, proto_message *reply, nc_error *err)
{
    const fem_model *m = c->m;
    fem_analysis *s = &c->s;
    int n = m->n_iface_nodes;
    const double *force;
    if (!(cmd->dt_s > 0) || !isfinite(cmd->dt_s))
        return nc_error_set(err, 1, "dt_s must be > 0, got %g", cmd->dt_s);
    if (proto_message_get_f64(cmd, "force", (size_t)n, 3, &force, NULL, err)) return -1;
    memset(s->f_coupling, 0, (size_t)s->ndof * sizeof(double));
    for (int i = 0; i < n; i++)
        for (int d = 0; d < 3; d++) s->f_coupling[3 * m->iface_nodes[i] + d] = force[3 * i + d];
    if (set_linearisation(c, cmd, 0, err)) return -1;
    double dt = cmd->dt_s;
    const long floor_before = s->stats.roundoff_converged;
    const int retries_before = c->sum->semidefinite_retries;
    if (m->settings.type == FEM_STATIC) {
        /* quasi-static coupling: equilibrium under the loads, velocity from the increment */
        double t0 = s->cur.time_s;
        long step0 = s->cur.step;
        if (fem_analysis_static(s, 1.0, err)) return -1;
        for (int i = 0; i < s->ndof; i++) s->cur.v[i] = (s->cur.u[i] - s->start.u[i]) / dt;
        memcpy(s->cur.fc, s->f_coupling, (size_t)s->ndof * sizeof(double));   /* for the energy */
        s->cur.time_s = t0 + dt;
        s->cur.step = step0 + 1;
    } else if (step_from_guess(c, dt, err)) {
        /* Newton failed with the symmetric part of the linearisation: a negative part of it
         * can make the step's problem indefinite; retry once with its semi-definite part */
        if (err->code != FEM_ERR_NEWTON || !s->lin.active) return -1;
        char first[NC_ERROR_MESSAGE_MAX];
        snprintf(first, sizeof first, "%s", err->message);
        if (set_linearisation(c, cmd, 1, err)) return -1;
        if (c->psd.last_clipped == 0) {
            nc_error_set(err, FEM_ERR_NEWTON, "%s", first);
            return -1;
        }
        c->sum->semidefinite_retries++;
        if (fem_analysis_step(s, dt, err))
            return nc_error_prefix(err, "%s; retried with the semi-definite part of the "
                                        "interface linearisation", first);
    }
    /* the next solve of this step starts from this solution, unless it ended at the rounding
     * floor or with the semi-definite retry: the same input again might then take another
     * Newton path, and the same input twice must give the same answer bit for bit */
    c->guess_dt_s = 0;
    if (m->settings.type != FEM_STATIC && s->stats.roundoff_converged == floor_before &&
        c->sum->semidefinite_retries == retries_before) {
        memcpy(c->guess_u, s->cur.u, (size_t)s->ndof * sizeof(double));
        c->guess_dt_s = dt;
    }
    for (int i = 0; i < n; i++)
        for (int d = 0; d < 3; d++) {
            c->iface_u[3 * i + d] = s->cur.u[3 * m->iface_nodes[i] + d] - c->iface_u0[3 * i + d];
            c->iface_v[3 * i + d] = s->cur.v[3 * m->iface_nodes[i] + d];
        }
    /* the energy values of protocol/README.md §3 (fem_analysis_step_energy): elastic =
     * strain, potential = of the model loads, external work = their ramp's share,
     * dissipated = Rayleigh + the integrator's numerical damping */
    fem_step_energy e;
    if (fem_analysis_step_energy(s, m->settings.type != FEM_STATIC, &e))
        return nc_error_set(err, 1, "step energy: no step was solved");
    if (proto_message_add_f64(reply, "displacement", c->iface_u, (size_t)n, 3, err) ||
        proto_message_add_f64(reply, "velocity", c->iface_v, (size_t)n, 3, err) ||
        proto_message_set_value(reply, "kinetic_energy_j", e.kinetic_j, err) ||
        proto_message_set_value(reply, "elastic_energy_j", e.strain_j, err) ||
        proto_message_set_value(reply, "potential_energy_j", e.load_potential_j, err) ||
        proto_message_set_value(reply, "interface_work_j", e.coupling_work_j, err) ||
        proto_message_set_value(reply, "external_work_j", e.load_input_j, err) ||
        proto_message_set_value(reply, "dissipated_energy_j", e.rayleigh_j + e.numerical_j + e.element_dissipation_j, err) ||
        proto_message_set_value(reply, "rayleigh_dissipation_j", e.rayleigh_j, err) ||
        proto_message_set_value(reply, "numerical_dissipation_j", e.numerical_j, err) ||
        proto_message_set_value(reply, "newton_iterations", s->stats.iterations, err) ||
        proto_message_set_value(reply, "residual_norm", s->stats.residual_norm, err))
        return -1;
    /* the coupler asks for the structure's compliance with the value "compliance" 1 */
    if (proto_message_value(cmd, "compliance", 0.0) != 0.0 && m->settings.type != FEM_STATIC &&
        s->lin.active && add_compliance(c, cmd, reply, err))
        return -1;
    return 0;
}

static int on_solve(void *ctx, const proto_message *cmd, proto_message *reply, nc_error *err)
{
    coupled *c = ctx;
    if (solve(c, cmd, reply, err)) {
        c->sum->failed_solves++;
        /* Newton did not converge: a smaller step may (the coupler decides) */
        if (err && err->code == FEM_ERR_NEWTON) err->code = PROTO_ERR_STEP_FAILED;
        return -1;
    }
    c->sum->newton_iterations += c->s.stats.iterations;
    return 0;
}

static int on_accept(void *ctx, const proto_message *cmd, proto_message *reply, nc_error *err)
{
    (void)cmd;
    (void)reply;
    coupled *c = ctx;
    fem_analysis *s = &c->s;
    c->sum->steps++;
    fem_analysis_update_axial(s);   /* every step: the peak forces (fem_output_monitor) */
    if (fem_output_monitor(&c->out, s, s->cur.time_s, err)) return -1;
    /* full output at multiples of interval_steps x the nominal dt in TIME: the coupler's
     * steps may be shorter (step control) or longer (far steps), so counting steps would
     * write off the grid the DEM writes on */
    double every_s = c->m->settings.output_interval * c->m->settings.dt_s;
    if (s->cur.time_s >= c->next_output_s - 1e-6 * every_s) {
        if (fem_output_step(&c->out, s, s->cur.time_s, err)) return -1;
        c->written_step = s->cur.step;
        c->next_output_s = (floor(s->cur.time_s / every_s + 1e-6) + 1.0) * every_s;
    }
    return fem_output_write_due(&c->out, err);
}

static int on_checkpoint(void *ctx, const proto_message *cmd, proto_message *reply, nc_error *err)
{
    (void)reply;
    coupled *c = ctx;
    /* checkpointed before its first step: the run's results start now */
    /* the rows the checkpoint counts are in fem.h5 before it names them */
    if (start_output(c, err) || fem_output_sync(&c->out, err)) return -1;
    memcpy(c->ckpt_u0, c->iface_u0, 3 * (size_t)c->m->n_iface_nodes * sizeof(double));
    return fem_checkpoint_save(c->dir, cmd->text, cmd->step, cmd->time_s, &c->s, &c->out,
                               &c->run_entries, err);
}

/* A fresh analysis in its start state (fem_run_initial_state), and the interface's offset
 * and coordinates from it. */
static int start_state(coupled *c, nc_error *err)
{
    const fem_model *m = c->m;
    if (fem_analysis_init(&c->s, m, err)) return -1;
    c->s.settle_watch = c->settle_watch;
    if (fem_run_initial_state(&c->s, c->sum, err)) return -1;
    for (int i = 0; i < m->n_iface_nodes; i++)
        for (int d = 0; d < 3; d++) {
            const int dof = 3 * m->iface_nodes[i] + d;
            c->iface_u0[3 * i + d] = c->s.cur.u[dof];
            c->iface_X[3 * i + d] = m->X[dof] + c->s.cur.u[dof];
        }
    return 0;
}

/* The state of a freshly started solver (what a failed RESUME leaves). */
static int fresh_state(coupled *c, nc_error *err)
{
    fem_analysis_free(&c->s);
    fem_output_close(&c->out);
    c->out.max_u_node = -1;
    c->written_step = -1;
    c->next_output_s = c->m->settings.output_interval * c->m->settings.dt_s;
    c->sum->steps = c->sum->newton_iterations = 0;
    c->sum->failed_solves = 0;
    c->sum->semidefinite_retries = 0;
    c->sum->warm_start_fallbacks = 0;
    return start_state(c, err);
}

/* The interface start of the checkpoint just loaded against this run's: the other programs'
 * coordinates and displacements are measured from it. */
static int same_start(coupled *c, nc_error *err)
{
    const size_t n3 = 3 * (size_t)c->m->n_iface_nodes;
    for (size_t i = 0; i < n3; i++)
        if (memcmp(&c->ckpt_u0[i], &c->iface_u0[i], sizeof(double)) != 0)
            return nc_error_set(err, 1, "the checkpoint was written by a run that started from "
                                "another state: interface node %zu at %.9g m, this run at "
                                "%.9g m (analysis.initial_state, the loads or the analysis "
                                "settings changed since)", i / 3, c->ckpt_u0[i],
                                c->iface_u0[i]);
    return 0;
}

static int on_resume(void *ctx, const proto_message *cmd, proto_message *reply, nc_error *err)
{
    (void)reply;
    coupled *c = ctx;
    c->guess_dt_s = 0;
    if (fem_checkpoint_load(c->dir, cmd->text, cmd->step, cmd->time_s, &c->s, &c->out,
                            &c->run_entries, err) ||
        same_start(c, err) || fem_output_reopen(&c->out, c->m, c->dir, err)) {
        nc_error again;
        if (fresh_state(c, &again)) nc_error_prefix(err, "and starting afresh failed (%s)", again.message);
        return -1;
    }
    return 0;
}

static void on_report(void *ctx, const char *message)
{
    coupled *c = ctx;
    if (!c->first_failure[0]) snprintf(c->first_failure, sizeof c->first_failure, "%s", message);
}

int fem_run_coupled(const fem_model *m, const char *output_dir, const fem_coupled_options *opt,
                    const volatile sig_atomic_t *stop, fem_run_summary *summary,
                    nc_error *err)
{
    double t0 = nc_clock_now_s();
    fem_run_summary sum;
    memset(&sum, 0, sizeof sum);
    coupled *c = calloc(1, sizeof *c);
    if (!c) return nc_error_set(err, 1, "out of memory");
    c->m = m;
    c->dir = output_dir;
    c->sum = &sum;
    if (opt->settle_watch) c->settle_watch = *opt->settle_watch;
    c->settle_watch.stop = stop;
    c->written_step = -1;
    c->out.max_u_node = -1;
    nc_ckpt_add(&c->run_entries, NULL, "run/written_step", NC_CKPT_LONG, &c->written_step, 1);
    nc_ckpt_add(&c->run_entries, NULL, "run/next_output_s", NC_CKPT_F64, &c->next_output_s, 1);
    nc_ckpt_add(&c->run_entries, NULL, "run/steps", NC_CKPT_LONG, &sum.steps, 1);
    nc_ckpt_add(&c->run_entries, NULL, "run/newton_iterations", NC_CKPT_LONG, &sum.newton_iterations, 1);
    nc_ckpt_add(&c->run_entries, NULL, "run/failed_solves", NC_CKPT_INT, &sum.failed_solves, 1);
    nc_ckpt_add(&c->run_entries, NULL, "run/semidefinite_retries", NC_CKPT_INT,
                &sum.semidefinite_retries, 1);
    nc_ckpt_add(&c->run_entries, NULL, "run/warm_start_fallbacks", NC_CKPT_INT,
                &sum.warm_start_fallbacks, 1);
    proto_participant *p = NULL;
    proto_serve_summary served;
    memset(&served, 0, sizeof served);
    int rc = -1;
    size_t n = (size_t)m->n_iface_nodes;
    c->node_ids = malloc((n + 1) * sizeof *c->node_ids);
    c->iface_X = malloc(3 * (n + 1) * sizeof(double));
    c->iface_u = calloc(3 * (n + 1), sizeof(double));
    c->iface_v = calloc(3 * (n + 1), sizeof(double));
    c->iface_u0 = calloc(3 * (n + 1), sizeof(double));
    c->ckpt_u0 = calloc(3 * (n + 1), sizeof(double));
    c->lin_u = calloc(3 * (size_t)m->n_nodes + 1, sizeof(double));
    c->lin_v = calloc(3 * (size_t)m->n_nodes + 1, sizeof(double));
    c->guess_u = calloc(3 * (size_t)m->n_nodes + 1, sizeof(double));
    if (!c->node_ids || !c->iface_X || !c->iface_u || !c->iface_v || !c->iface_u0 ||
        !c->ckpt_u0 || !c->lin_u || !c->lin_v || !c->guess_u) {
        nc_error_set(err, 1, "out of memory");
        goto done;
    }
    nc_ckpt_add(&c->run_entries, NULL, "run/interface_start", NC_CKPT_F64, c->ckpt_u0, 3 * n);
    for (size_t i = 0; i < n; i++) c->node_ids[i] = m->iface_nodes[i];
    if (start_state(c, err)) goto done;
    c->next_output_s = m->settings.output_interval * m->settings.dt_s;
    proto_options po;
    proto_options_default(&po);
    po.idle_timeout_ms = opt->idle_timeout_ms;
    if (proto_participant_open(&p, opt->endpoint, "fem", "netcouple fem_solver", "restore jacobian checkpoint compliance", &po, err))
        goto done;
    if (opt->endpoint_file && nc_file_write_line(opt->endpoint_file, proto_participant_endpoint(p), err))
        goto done;
    const proto_serve_handlers handlers = {
        .interface = on_interface, .save_state = on_save, .restore_state = on_restore,
        .solve = on_solve, .accept_step = on_accept, .checkpoint = on_checkpoint,
        .resume = on_resume, .report = on_report};
    rc = proto_serve(p, &handlers, c, stop, &served, err);
    if (rc == 0 && served.failed + served.rejected > 0) {
        /* the coupler was told each time, but the run had errors: not a clean exit */
        nc_error_set(err, 3, "%ld command(s) answered with an error during the run; the first: %s",
                     served.failed + served.rejected, c->first_failure);
        rc = -1;
    }
done:
    /* a step begun and solved but not accepted is not a result: write the last accepted state */
    if (c->out.open && c->s.m && served.step_solved) {
        nc_error ignored;
        fem_analysis_restore(&c->s, &ignored);
    }
    /* the last state, the rows still in memory and the run's summary: a run (or a stopped one)
     * whose results could not be written failed, and says why; an earlier error is said
     * instead */
    nc_error flushing;
    int unwritten = 0;
    if (c->out.open && c->written_step != c->s.cur.step && c->s.m) {
        fem_analysis_update_axial(&c->s);
        unwritten = fem_output_step(&c->out, &c->s, c->s.cur.time_s, &flushing) != 0;
    }
    if (!unwritten) unwritten = fem_output_finish(&c->out, &flushing) != 0;
    if (unwritten && rc >= 0) {
        if (err) *err = flushing;
        rc = -1;
    }
    sum.final_time_s = c->s.cur.u ? c->s.cur.time_s : 0;
    sum.output_steps = c->out.n_out;
    /* the run's largest |u| over every accepted step (fem_output_monitor tracks it) */
    sum.max_displacement_m = c->out.max_u_node >= 0 ? c->out.max_u_m : 0.0;
    sum.max_displacement_time_s = c->out.max_u_node >= 0 ? c->out.max_u_time_s : -1.0;
    sum.max_displacement_node = c->out.max_u_node;
    sum.overload = summary ? summary->overload : NULL;
    sum.overloaded_elements = fem_output_overload(&c->out, m, sum.overload);
    sum.stats = c->s.stats;
    if (p) proto_participant_close(p);
    fem_output_close(&c->out);
    fem_analysis_free(&c->s);
    nc_ckpt_table_free(&c->run_entries);
    free(c->node_ids); free(c->iface_X); free(c->iface_u); free(c->iface_v); free(c->iface_u0); free(c->ckpt_u0);
    free(c->lin_u); free(c->lin_v); free(c->lin_nodes); free(c->guess_u);
    free(c->comp_nodes); free(c->comp_S); free(c->comp_rows);
    fem_psd_free(&c->psd);
    free(c);
    sum.wall_s = nc_clock_now_s() - t0;
    if (summary) *summary = sum;
    return rc;
}
