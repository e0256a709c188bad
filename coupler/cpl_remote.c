/* cpl_remote — FEM and DEM participants over the netcouple protocol. */
#include "cpl_remote.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "nc_clock.h"

static void options_ms(proto_options *o, double timeout_s)
{
    proto_options_default(o);
    o->timeout_ms = (int)fmin(timeout_s * 1000.0, 2e9);
}

int cpl_remote_open(cpl_remote *r, cpl_remote_kind kind, const char *endpoint,
                    double connect_timeout_s, double reply_timeout_s, nc_error *err)
{
    memset(r, 0, sizeof *r);
    r->kind = kind;
    snprintf(r->name, sizeof r->name, "%s", kind == CPL_REMOTE_FEM ? "fem" : "dem");
    snprintf(r->endpoint, sizeof r->endpoint, "%s", endpoint);
    /* one HELLO within the connect timeout (a participant that is not there fails fast),
     * then the reply timeout for the run */
    proto_options o;
    options_ms(&o, connect_timeout_s);
    if (proto_peer_open(&r->peer, r->name, endpoint, &o, err)) return -1;
    if (proto_peer_hello(r->peer, &r->reply, err)) {
        cpl_remote_close(r);
        return nc_error_prefix(err, "%s: handshake failed", r->name);
    }
    options_ms(&o, reply_timeout_s);
    proto_peer_set_timeout(r->peer, o.timeout_ms);
    snprintf(r->peer_role, sizeof r->peer_role, "%s", r->reply.role);
    snprintf(r->peer_program, sizeof r->peer_program, "%s", r->reply.name);
    snprintf(r->capabilities, sizeof r->capabilities, "%s", r->reply.text);
    r->version = proto_peer_version(r->peer);
    snprintf(r->session, sizeof r->session, "%s", proto_peer_session(r->peer));
    r->idle_timeout_s = proto_message_value(&r->reply, "idle_timeout_s", 0.0);
    r->alive = 1;
    /* the side that stalls must be the one reported: a participant that gives up waiting
     * before the coupler does would be blamed for the other's stall (protocol/README.md §6) */
    if (r->idle_timeout_s > 0.0 && !(r->idle_timeout_s > reply_timeout_s)) {
        nc_error_set(err, 1, "%s: its idle timeout (%.1f s) must be longer than the coupler's "
                     "reply timeout (%.1f s): raise the participant's --idle-timeout or lower "
                     "timeouts.reply in coupler.json", r->name, r->idle_timeout_s,
                     reply_timeout_s);
        return -1;
    }
    return 0;
}

/* After a failed request: records whether the peer is still there. */
static int request_failed(cpl_remote *r, nc_error *err)
{
    /* an error reply or a malformed reply means it is there and answering (so it gets
     * SHUTDOWN); a timeout or a closed connection means it cannot be trusted to answer */
    int code = err ? err->code : 0;
    r->alive = code == PROTO_ERR_PEER || code == PROTO_ERR_STEP_FAILED || code == PROTO_ERR_DECODE;
    if (code == PROTO_ERR_STEP_FAILED) err->code = CPL_ERR_STEP_FAILED;   /* the loop retries */
    return -1;
}

/* Sends r->request and waits for its reply in r->reply. */
static int request(cpl_remote *r, nc_error *err)
{
    if (proto_peer_request(r->peer, &r->request, &r->reply, err) == 0) return 0;
    return request_failed(r, err);
}

int cpl_remote_interface_fem(cpl_remote *fem, cpl_mesh *mesh, double **u0, double **v0,
                             nc_error *err)
{
    *u0 = *v0 = NULL;
    proto_message_init(&fem->request, PROTO_MSG_INTERFACE);
    fem->request.step = -1;
    if (request(fem, err)) return nc_error_prefix(err, "fem: interface");
    const int32_t *ids, *elements = NULL;
    const double *xyz;
    size_t n = 0, n_ids = 0, m = 0;
    if (proto_message_get_f64(&fem->reply, "coordinates", 0, 3, &xyz, &n, err) ||
        proto_message_get_i32(&fem->reply, "node_ids", n, 0, &ids, &n_ids, err))
        return nc_error_prefix(err, "fem: interface reply");
    for (size_t i = 0; i < fem->reply.n_arrays; i++)
        if (strcmp(fem->reply.arrays[i].name, "elements") == 0 &&
            proto_message_get_i32(&fem->reply, "elements", 0, 2, &elements, &m, err))
            return nc_error_prefix(err, "fem: interface reply");
    if (cpl_mesh_init(mesh, n, ids, xyz, m, elements, "fem: interface reply", err)) return -1;
    fem->n_nodes = n;
    const char *names[2] = {"displacement", "velocity"};
    double **outs[2] = {u0, v0};
    for (int k = 0; k < 2; k++)
        for (size_t i = 0; i < fem->reply.n_arrays; i++)
            if (strcmp(fem->reply.arrays[i].name, names[k]) == 0) {
                const double *d;
                if (proto_message_get_f64(&fem->reply, names[k], n, 3, &d, NULL, err))
                    return nc_error_prefix(err, "fem: interface reply");
                *outs[k] = malloc(3 * n * sizeof(double));
                if (!*outs[k]) return nc_error_set(err, 1, "out of memory");
                memcpy(*outs[k], d, 3 * n * sizeof(double));
            }
    return 0;
}

int cpl_remote_interface_dem(cpl_remote *dem, const cpl_mesh *mesh, nc_error *err)
{
    proto_message_init(&dem->request, PROTO_MSG_INTERFACE);
    dem->request.step = -1;
    if (proto_message_add_i32(&dem->request, "node_ids", mesh->node_ids, mesh->n_nodes, 0, err) ||
        proto_message_add_f64(&dem->request, "coordinates", mesh->coordinates, mesh->n_nodes, 3,
                              err) ||
        proto_message_add_i32(&dem->request, "elements", mesh->elements, mesh->n_elements, 2,
                              err))
        return -1;
    if (request(dem, err)) return nc_error_prefix(err, "dem: interface");
    dem->n_nodes = mesh->n_nodes;
    return 0;
}

static void command(cpl_remote *r, proto_msg_type type, const cpl_call *call)
{
    proto_message_init(&r->request, type);
    r->request.step = call->step;
    r->request.iteration = call->iteration;
    r->request.time_s = call->time_s;
    r->request.dt_s = call->dt_s;
}

static int remote_begin(void *ctx, const cpl_call *call, nc_error *err)
{
    cpl_remote *r = ctx;
    command(r, PROTO_MSG_BEGIN_STEP, call);
    return request(r, err);
}

static int remote_accept(void *ctx, const cpl_call *call, nc_error *err)
{
    cpl_remote *r = ctx;
    command(r, PROTO_MSG_ACCEPT_STEP, call);
    return request(r, err);
}

/* BEGIN_STEP / ACCEPT_STEP in two halves (cpl_participant.post, .await) */
static int remote_post(void *ctx, cpl_command which, const cpl_call *call, nc_error *err)
{
    cpl_remote *r = ctx;
    command(r, which == CPL_COMMAND_BEGIN_STEP ? PROTO_MSG_BEGIN_STEP : PROTO_MSG_ACCEPT_STEP,
            call);
    if (proto_peer_send(r->peer, &r->request, err) == 0) return 0;
    return request_failed(r, err);
}

static int remote_await(void *ctx, nc_error *err)
{
    cpl_remote *r = ctx;
    if (proto_peer_receive(r->peer, &r->reply, err) == 0) return 0;
    return request_failed(r, err);
}

static int copy_array(cpl_remote *r, const char *name, double *out, nc_error *err)
{
    const double *d;
    if (proto_message_get_f64(&r->reply, name, r->n_nodes, 3, &d, NULL, err)) {
        r->alive = 1;   /* it answered, just wrongly */
        return -1;
    }
    memcpy(out, d, 3 * r->n_nodes * sizeof(double));
    return 0;
}

/* The optional energy values of a SOLVE reply (protocol/README.md §3): valid only when all
 * six are present. */
static void read_energy(const proto_message *reply, cpl_energy_report *e)
{
    e->kinetic_j = proto_message_value(reply, "kinetic_energy_j", NAN);
    e->elastic_j = proto_message_value(reply, "elastic_energy_j", NAN);
    e->potential_j = proto_message_value(reply, "potential_energy_j", NAN);
    e->interface_work_j = proto_message_value(reply, "interface_work_j", NAN);
    e->external_work_j = proto_message_value(reply, "external_work_j", NAN);
    e->dissipated_j = proto_message_value(reply, "dissipated_energy_j", NAN);
    e->numerical_j = proto_message_value(reply, "numerical_dissipation_j", NAN);
    e->valid = isfinite(e->kinetic_j) && isfinite(e->elastic_j) && isfinite(e->potential_j) &&
               isfinite(e->interface_work_j) && isfinite(e->external_work_j) &&
               isfinite(e->dissipated_j);
}

/* The FEM's SOLVE: the linearisation and the point it was taken at (§3.1). */
static int add_jacobian(cpl_remote *r, const cpl_call *call, nc_error *err)
{
    const cpl_jacobian *j = call->jacobian_in;
    const size_t n = r->n_nodes;
    if (proto_message_add_i32(&r->request, "jacobian_nodes", j->nodes, j->n_blocks, 2, err) ||
        proto_message_add_f64(&r->request, "jacobian_stiffness", j->stiffness, j->n_blocks, 9, err) ||
        (j->has_damping &&
         proto_message_add_f64(&r->request, "jacobian_damping", j->damping, j->n_blocks, 9, err)) ||
        proto_message_add_f64(&r->request, "jacobian_displacement", call->jacobian_u, n, 3, err) ||
        proto_message_add_f64(&r->request, "jacobian_velocity", call->jacobian_v, n, 3, err))
        return -1;
    return 0;
}

/* The DEM's reply: the linearisation it was asked for, node indices checked. */
static int read_jacobian(cpl_remote *r, cpl_jacobian *j, nc_error *err)
{
    const int32_t *nodes;
    const double *K, *C = NULL;
    size_t b = 0;
    r->alive = 1;   /* whatever is wrong below, it answered */
    if (proto_message_get_i32(&r->reply, "jacobian_nodes", 0, 2, &nodes, &b, err) ||
        proto_message_get_f64(&r->reply, "jacobian_stiffness", b, 9, &K, NULL, err) ||
        cpl_node_list_check(nodes, 2 * b, 2, r->n_nodes, 0, "jacobian_nodes", err))
        return nc_error_prefix(err, "asked for the interface Jacobian");
    for (size_t i = 0; i < r->reply.n_arrays; i++)
        if (strcmp(r->reply.arrays[i].name, "jacobian_damping") == 0 &&
            proto_message_get_f64(&r->reply, "jacobian_damping", b, 9, &C, NULL, err))
            return -1;
    return cpl_jacobian_set(j, b, nodes, K, C, err);
}

static int read_compliance(cpl_remote *r, cpl_compliance *cp, double dt_s, nc_error *err)
{
    cp->valid = 0;
    if (!proto_message_find(&r->reply, "compliance_nodes")) return 0;
    const int32_t *nodes;
    const double *S;
    size_t k = 0;
    if (proto_message_get_i32(&r->reply, "compliance_nodes", 0, 1, &nodes, &k, err) ||
        cpl_node_list_check(nodes, k, 1, r->n_nodes, 1, "compliance_nodes", err) ||
        proto_message_get_f64(&r->reply, "compliance", 3 * k, 3 * k, &S, NULL, err))
        return nc_error_prefix(err, "asked for the structure's compliance");
    if (cp->n3 != 3 * r->n_nodes)
        return nc_error_set(err, 1, "compliance: room for %zu interface dofs, the interface "
                            "has %zu", cp->n3, 3 * r->n_nodes);
    if (cpl_compliance_reserve(cp, k, err)) return -1;
    memcpy(cp->nodes, nodes, k * sizeof *nodes);
    memcpy(cp->S, S, 9 * k * k * sizeof *S);
    cp->has_interface = 0;
    if (proto_message_find(&r->reply, "compliance_interface")) {
        const double *rows;
        if (proto_message_get_f64(&r->reply, "compliance_interface", 3 * r->n_nodes, 3 * k,
                                  &rows, NULL, err))
            return nc_error_prefix(err, "asked for the structure's compliance");
        memcpy(cp->S_interface, rows, 9 * k * r->n_nodes * sizeof *rows);
        cp->has_interface = 1;
    } else {
        /* defined contents for the checkpoint, which holds the array either way */
        memset(cp->S_interface, 0, 9 * k * r->n_nodes * sizeof *cp->S_interface);
    }
    cp->dt_s = dt_s;
    cp->velocity_per_m = proto_message_value(&r->reply, "compliance_velocity_per_m", 0.0);
    cp->valid = 1;
    return 0;
}

static int add_compliance(cpl_remote *r, const cpl_call *call, nc_error *err)
{
    const cpl_compliance *cp = call->compliance_in;
    if (!cp || !cp->valid || cp->dt_s != call->dt_s || !cp->force_ref) return 0;
    const size_t k = cp->n_nodes;
    return proto_message_add_i32(&r->request, "compliance_nodes", cp->nodes, k, 1, err) ||
           proto_message_add_f64(&r->request, "compliance", cp->S, 3 * k, 3 * k, err) ||
           proto_message_add_f64(&r->request, "compliance_force", cp->force_ref, r->n_nodes, 3, err);
}

static int remote_solve(void *ctx, const cpl_call *call, const double *in0, const double *in1,
                        double *out0, double *out1, cpl_solve_info *info, nc_error *err)
{
    cpl_remote *r = ctx;
    command(r, PROTO_MSG_SOLVE, call);
    const size_t n = r->n_nodes;
    if (r->kind == CPL_REMOTE_FEM) {
        if (proto_message_add_f64(&r->request, "force", in0, n, 3, err) ||
            (call->jacobian_in && add_jacobian(r, call, err)) ||
            (call->compliance_out && proto_message_set_value(&r->request, "compliance", 1.0, err)) ||
            request(r, err) ||
            copy_array(r, "displacement", out0, err) || copy_array(r, "velocity", out1, err) ||
            (call->compliance_out && read_compliance(r, call->compliance_out, call->dt_s, err)))
            return -1;
    } else {
        if (proto_message_add_f64(&r->request, "displacement", in0, n, 3, err) ||
            proto_message_add_f64(&r->request, "velocity", in1, n, 3, err) ||
            (call->jacobian_out && proto_message_set_value(&r->request, "jacobian", 1.0, err)) ||
            (call->jacobian_out && call->proximity &&
             proto_message_set_value(&r->request, "proximity", 1.0, err)) ||
            (call->jacobian_out && add_compliance(r, call, err)) ||
            request(r, err) || copy_array(r, "force", out0, err) ||
            (call->jacobian_out && read_jacobian(r, call->jacobian_out, err)))
            return -1;
        if (call->compliance_out) {
            call->compliance_out->wall_valid = 0;
            if (proto_message_find(&r->reply, "compliance_displacement")) {
                if (copy_array(r, "compliance_displacement", call->compliance_out->u_wall, err)) return -1;
                call->compliance_out->wall_valid = 1;
            }
        }
        info->near_interface = proto_message_value(&r->reply, "near_interface", 1.0) != 0.0;
        info->min_gap_m = proto_message_value(&r->reply, "min_gap_m", INFINITY);
        info->contacts = proto_message_value(&r->reply, "contacts", 0.0);
        if (call->jacobian_out)
            info->jacobian_dropped =
                proto_message_value(&r->reply, "jacobian_dropped_particles", 0.0);
    }
    info->solver_time_s = proto_message_value(&r->reply, "solve_time_s", NAN);
    read_energy(&r->reply, &info->energy);
    return 0;
}

/* CHECKPOINT / RESUME: step, time and the checkpoint's name in `text` (§3.3) */
static int remote_named(cpl_remote *r, proto_msg_type type, const cpl_call *call,
                        const char *name, nc_error *err)
{
    command(r, type, call);
    r->request.dt_s = 0.0;
    snprintf(r->request.text, sizeof r->request.text, "%s", name);
    return request(r, err);
}

static int remote_checkpoint(void *ctx, const cpl_call *call, const char *name, nc_error *err)
{
    return remote_named(ctx, PROTO_MSG_CHECKPOINT, call, name, err);
}

static int remote_resume(void *ctx, const cpl_call *call, const char *name, nc_error *err)
{
    return remote_named(ctx, PROTO_MSG_RESUME, call, name, err);
}

int cpl_remote_can_checkpoint(const cpl_remote *r)
{
    return r->version >= 2 && proto_has_capability(r->capabilities, "checkpoint");
}

cpl_participant cpl_remote_participant(cpl_remote *r)
{
    const int ckpt = cpl_remote_can_checkpoint(r);
    cpl_participant p = {r->name, r, remote_begin, remote_solve, remote_accept,
                         r->version >= 2 && proto_has_capability(r->capabilities, "jacobian"),
                         ckpt ? remote_checkpoint : NULL, ckpt ? remote_resume : NULL,
                         remote_post, remote_await,
                         r->version >= 2 && proto_has_capability(r->capabilities, "compliance")};
    return p;
}

int cpl_remote_shutdown(cpl_remote *r, double timeout_s, nc_error *err)
{
    proto_options o;
    options_ms(&o, timeout_s);
    proto_peer *peer = NULL;
    if (proto_peer_open(&peer, r->name, r->endpoint, &o, err)) return -1;
    /* the same coupler on a second connection: its session and version */
    proto_peer_join(peer, r->session, r->version);
    proto_message_init(&r->request, PROTO_MSG_SHUTDOWN);
    r->request.step = -1;
    int rc = proto_peer_request(peer, &r->request, &r->reply, err);
    proto_peer_close(peer);
    return rc;
}

void cpl_remote_close(cpl_remote *r)
{
    proto_peer_close(r->peer);
    r->peer = NULL;
    proto_message_free(&r->request);
    proto_message_free(&r->reply);
}

int cpl_read_endpoint_file(const char *path, double timeout_s, char *endpoint, size_t size,
                           volatile const sig_atomic_t *stop, nc_error *err)
{
    double t0 = nc_clock_now_s();
    for (;;) {
        FILE *f = fopen(path, "r");
        if (f) {
            char line[1024] = "";
            char *ok = fgets(line, sizeof line, f);
            fclose(f);
            line[strcspn(line, "\r\n \t")] = '\0';
            if (ok && line[0]) {
                snprintf(endpoint, size, "%s", line);
                return 0;
            }
        }
        if (stop && *stop)
            return nc_error_set(err, 1, "stopped while the participants were starting, before "
                                "%s was written (the launcher stops the coupler when a "
                                "participant fails, and names it)", path);
        if (nc_clock_now_s() - t0 > timeout_s)
            return nc_error_set(err, 1, "%s: endpoint file did not appear within %.1f s (did "
                                "the participant start?)", path, timeout_s);
        /* a participant publishes its endpoint some 50 ms after it starts (its libraries,
         * its model): looked for often, as the launcher starts all three at once */
        struct timespec ts = {0, 2 * 1000 * 1000};
        nanosleep(&ts, NULL);
    }
}
