/* fem_coupled — the FEM as a netcouple protocol participant ("fem"): answers INTERFACE with
 * its interface mesh, BEGIN_STEP by saving its start-of-step state, SOLVE (force in,
 * displacement + velocity out; restoring the start state first when the step is solved
 * again), ACCEPT_STEP by committing and writing output, SHUTDOWN by closing its files.
 * See fem_run.h and the brief's protocol section. */
#include "fem_run.h"
#include "fem_output.h"
#include "nc_file.h"
#include "nc_clock.h"
#include "proto.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

typedef struct coupled {
    const fem_model *m;
    fem_analysis s;
    fem_output out;
    proto_participant *p;
    proto_message cmd, reply;
    int32_t *node_ids;
    double *iface_X, *iface_u, *iface_v;
    int in_step;          /* BEGIN_STEP received, not yet accepted */
    int solved;           /* a SOLVE ran since BEGIN_STEP (the next one restores first) */
    long written_step;
} coupled;

/* Solves the step with the interface force of `cmd`; fills the reply arrays. */
static int solve(coupled *c, nc_error *err)
{
    const fem_model *m = c->m;
    fem_analysis *s = &c->s;
    int n = m->n_iface_nodes;
    const double *force;
    if (!c->in_step) return nc_error_set(err, 1, "SOLVE before BEGIN_STEP");
    if (!(c->cmd.dt_s > 0) || !isfinite(c->cmd.dt_s))
        return nc_error_set(err, 1, "SOLVE: dt_s must be > 0, got %g", c->cmd.dt_s);
    if (proto_message_get_f64(&c->cmd, "force", (size_t)n, 3, &force, NULL, err)) return -1;
    if (c->solved && fem_analysis_restore(s, err)) return -1;
    c->solved = 1;
    memset(s->f_coupling, 0, (size_t)s->ndof * sizeof(double));
    for (int i = 0; i < n; i++)
        for (int d = 0; d < 3; d++) s->f_coupling[3 * m->iface_nodes[i] + d] = force[3 * i + d];
    double dt = c->cmd.dt_s;
    if (m->settings.type == FEM_STATIC) {
        /* quasi-static coupling: equilibrium under the loads, velocity from the increment */
        double t0 = s->cur.time_s;
        long step0 = s->cur.step;
        if (fem_analysis_static(s, 1.0, err)) return -1;
        for (int i = 0; i < s->ndof; i++) s->cur.v[i] = (s->cur.u[i] - s->start.u[i]) / dt;
        s->cur.time_s = t0 + dt;
        s->cur.step = step0 + 1;
    } else if (fem_analysis_step(s, dt, err)) {
        return -1;
    }
    for (int i = 0; i < n; i++)
        for (int d = 0; d < 3; d++) {
            c->iface_u[3 * i + d] = s->cur.u[3 * m->iface_nodes[i] + d];
            c->iface_v[3 * i + d] = s->cur.v[3 * m->iface_nodes[i] + d];
        }
    proto_message_init(&c->reply, PROTO_MSG_SOLVE);
    if (proto_message_add_f64(&c->reply, "displacement", c->iface_u, (size_t)n, 3, err) ||
        proto_message_add_f64(&c->reply, "velocity", c->iface_v, (size_t)n, 3, err) ||
        proto_message_set_value(&c->reply, "newton_iterations", s->stats.iterations, err) ||
        proto_message_set_value(&c->reply, "residual_norm", s->stats.residual_norm, err))
        return -1;
    return 0;
}

static int handle(coupled *c, int *done, fem_run_summary *sum, nc_error *err)
{
    const fem_model *m = c->m;
    fem_analysis *s = &c->s;
    proto_message_init(&c->reply, c->cmd.type);
    switch (c->cmd.type) {
    case PROTO_MSG_INTERFACE: {
        size_t n = (size_t)m->n_iface_nodes, e = (size_t)m->n_iface_elements;
        if (proto_message_add_i32(&c->reply, "node_ids", c->node_ids, n, 0, err) ||
            proto_message_add_f64(&c->reply, "coordinates", c->iface_X, n, 3, err) ||
            proto_message_add_i32(&c->reply, "elements", (const int32_t *)m->iface_conn, e, 2, err))
            return -1;
        return 0;
    }
    case PROTO_MSG_BEGIN_STEP:
        /* a step begun again without ACCEPT_STEP starts from the last accepted state */
        if (c->in_step && c->solved && fem_analysis_restore(s, err)) return -1;
        if (isfinite(c->cmd.time_s)) s->cur.time_s = c->cmd.time_s;  /* the coupler owns time */
        if (fem_analysis_save(s, err)) return -1;
        c->in_step = 1;
        c->solved = 0;
        return 0;
    case PROTO_MSG_SOLVE:
        if (solve(c, err)) {
            sum->failed_solves++;
            return -1;
        }
        sum->newton_iterations += s->stats.iterations;
        return 0;
    case PROTO_MSG_ACCEPT_STEP:
        if (!c->in_step || !c->solved) return nc_error_set(err, 1, "ACCEPT_STEP without a solved step");
        c->in_step = 0;
        c->solved = 0;
        sum->steps++;
        if (fem_output_monitor(&c->out, s, s->cur.time_s, err)) return -1;
        if (s->cur.step % m->settings.output_interval == 0) {
            fem_analysis_update_axial(s);
            if (fem_output_step(&c->out, s, s->cur.time_s, err)) return -1;
            c->written_step = s->cur.step;
        }
        return 0;
    case PROTO_MSG_SHUTDOWN:
        *done = 1;
        return 0;
    default:
        return nc_error_set(err, 1, "the FEM solver does not handle %s commands", proto_type_name(c->cmd.type));
    }
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
    c->written_step = -1;
    int rc = -1;
    size_t n = (size_t)m->n_iface_nodes;
    c->node_ids = malloc((n + 1) * sizeof *c->node_ids);
    c->iface_X = malloc(3 * (n + 1) * sizeof(double));
    c->iface_u = calloc(3 * (n + 1), sizeof(double));
    c->iface_v = calloc(3 * (n + 1), sizeof(double));
    if (!c->node_ids || !c->iface_X || !c->iface_u || !c->iface_v) {
        nc_error_set(err, 1, "out of memory");
        goto done;
    }
    for (size_t i = 0; i < n; i++) {
        c->node_ids[i] = m->iface_nodes[i];
        for (int d = 0; d < 3; d++) c->iface_X[3 * i + d] = m->X[3 * m->iface_nodes[i] + d];
    }
    if (fem_analysis_init(&c->s, m, err) || fem_output_open(&c->out, m, output_dir, err)) goto done;
    if (m->settings.type == FEM_DYNAMIC && fem_analysis_initial_acceleration(&c->s, err)) goto done;
    if (fem_output_monitor(&c->out, &c->s, 0.0, err) || fem_output_step(&c->out, &c->s, 0.0, err))
        goto done;
    c->written_step = 0;
    proto_options po;
    proto_options_default(&po);
    po.idle_timeout_ms = opt->idle_timeout_ms;
    if (proto_participant_open(&c->p, opt->endpoint, "fem", "netcouple fem_solver", "restore", &po, err))
        goto done;
    if (opt->endpoint_file &&
        nc_file_write_line(opt->endpoint_file, proto_participant_endpoint(c->p), err))
        goto done;
    int finished = 0;
    while (!finished) {
        if (stop && *stop) { rc = 1; goto done; }
        nc_error e;
        nc_error_clear(&e);
        if (proto_participant_receive(c->p, &c->cmd, &e)) {
            if (stop && *stop) { rc = 1; goto done; }
            if (e.code == PROTO_ERR_IDLE || e.code == PROTO_ERR_TRANSPORT) {
                *err = e;
                goto done;
            }
            continue;   /* malformed command: already answered with an error */
        }
        if (handle(c, &finished, &sum, &e)) {
            nc_error e2;
            if (proto_participant_reply_error(c->p, e.message, &e2)) { *err = e2; goto done; }
            continue;
        }
        if (proto_participant_reply(c->p, &c->reply, &e)) { *err = e; goto done; }
    }
    rc = sum.failed_solves ? -1 : 0;
    if (rc) nc_error_set(err, 3, "%d SOLVE command(s) failed during the run", sum.failed_solves);
done:
    if (c->out.open && c->s.m) {
        /* a step begun but not accepted is not a result: write the last accepted state */
        nc_error ignored;
        if (c->in_step && c->solved) fem_analysis_restore(&c->s, &ignored);
    }
    if (c->out.open && c->written_step != c->s.cur.step && c->s.m) {
        nc_error ignored;
        fem_analysis_update_axial(&c->s);
        fem_output_step(&c->out, &c->s, c->s.cur.time_s, &ignored);
    }
    sum.final_time_s = c->s.cur.u ? c->s.cur.time_s : 0;
    sum.output_steps = c->out.n_out;
    if (c->s.cur.u)
        for (int i = 0; i < m->n_nodes; i++) {
            const double *u = c->s.cur.u + 3 * i;
            sum.max_displacement_m = fmax(sum.max_displacement_m, sqrt(u[0] * u[0] + u[1] * u[1] + u[2] * u[2]));
        }
    sum.stats = c->s.stats;
    if (c->p) proto_participant_close(c->p);
    proto_message_free(&c->cmd);
    proto_message_free(&c->reply);
    fem_output_close(&c->out);
    fem_analysis_free(&c->s);
    free(c->node_ids); free(c->iface_X); free(c->iface_u); free(c->iface_v);
    free(c);
    sum.wall_s = nc_clock_now_s() - t0;
    if (summary) *summary = sum;
    return rc;
}
