/* dem_participant — the DEM's serve-loop handlers (dem_participant.h). */
#include "dem_participant.h"

#include <ctype.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "dem_checkpoint.h"
#include "dem_compliance.h"
#include "dem_energy.h"
#include "dem_net_jacobian.h"
#include "dem_net_proximity.h"
#include "nc_file.h"
#include "proto_serve.h"

typedef struct participant {
    dem_sim *s;
    dem_output *out;
    const dem_participant_options *opt;
    double *force;          /* 3 per node: last time-averaged nodal force */
    size_t force_cap;
    double next_out_s;      /* next output time */
    double e_start_j;       /* mechanical energy at BEGIN_STEP (dem_energy.h) */
    dem_net_jacobian jac;   /* the linearisation of the last solve, when asked for */
    char last_checkpoint[PROTO_TEXT_MAX]; /* the newest checkpoint saved or resumed from */
    int resume_failed;      /* a RESUME failed: the state may be neither the old nor the new */
    double *wall_end;       /* [3n] where the wall ended in the last solve with the structure's
                               compliance (the reply points to it) */
    size_t wall_end_cap;
    int dashpot_noted;      /* the note on a Hertz dashpot at the first touch was printed */
} participant;

/* The participant's own state in a checkpoint (dem_checkpoint.h): the nodal force of the last
 * step (output), the next output time and the energy at the last BEGIN_STEP. */
static void own_entries(participant *c, nc_ckpt_table *t)
{
    size_t nn = c->s->model.net.active ? c->s->model.net.n_nodes : 0;
    nc_ckpt_add_rows(t, "participant", "net_force", NC_CKPT_F64, c->force, nn, 3, 0);
    nc_ckpt_f64(t, "participant", "next_output_s", &c->next_out_s, 1);
    nc_ckpt_f64(t, "participant", "energy_at_begin_j", &c->e_start_j, 1);
}

static int on_interface(void *ctx, const proto_message *cmd, proto_message *reply, nc_error *err)
{
    (void)reply;
    participant *c = ctx;
    const int32_t *ids, *elements;
    const double *coords;
    size_t n, m;
    if (proto_message_get_i32(cmd, "node_ids", 0, 0, &ids, &n, err) ||
        proto_message_get_f64(cmd, "coordinates", n, 3, &coords, NULL, err) ||
        proto_message_get_i32(cmd, "elements", 0, 2, &elements, &m, err) ||
        dem_sim_set_interface(c->s, n, ids, coords, m, elements, err))
        return -1;
    if (c->force_cap < 3 * n) {
        free(c->force);
        c->force = calloc(3 * n, sizeof *c->force);
        c->force_cap = c->force ? 3 * n : 0;
        if (!c->force) return nc_error_set(err, 1, "dem: out of memory");
    }
    memset(c->force, 0, 3 * n * sizeof *c->force);
    if (c->opt->progress)
        fprintf(c->opt->progress, "dem_solver: interface with %zu nodes and %zu elements\n", n, m);
    return 0;
}

static int on_save(void *ctx, const proto_message *cmd, nc_error *err)
{
    (void)cmd;
    participant *c = ctx;
    if (c->resume_failed)
        return nc_error_set(err, 1, "dem: the RESUME before failed; the run cannot step from a "
                                    "partly loaded state");
    /* output step 0 at the first BEGIN_STEP, not before: a participant that is to resume
     * must not have created or truncated its result files (protocol/README.md §3.3) */
    if (c->out->n_out == 0 &&
        (dem_sim_check_net_start(c->s, err) || dem_output_write(c->out, c->s, c->force, err)))
        return -1;
    if (dem_sim_begin_step(c->s, err)) return -1;
    c->e_start_j = dem_sim_mechanical_energy(c->s);
    return 0;
}

static int on_restore(void *ctx, const proto_message *cmd, nc_error *err)
{
    (void)cmd;
    participant *c = ctx;
    return dem_sim_restore(c->s, err);
}

/* The fastest body's centre-of-mass speed (m/s), for the coupler's progress line. */
static double max_body_speed(const dem_sim *s)
{
    const dem_bodies *b = &s->model.bod;
    double v2 = 0.0;
    for (size_t i = 0; i < b->n; i++) {
        const double *v = b->vel + 3 * i;
        v2 = fmax(v2, v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
    }
    return sqrt(v2);
}

/* The Hertz law's dashpot of eq. (A.5), 2 ζ sqrt(m* kn') δ̇ ("fit" or "a7"), grows like
 * δ^(1/4) from the first touch: its dF/dδ, and with it the Jacobian the coupler asks for, is
 * unbounded there (1.2e16 N/m measured on cases/cable_impact at restitution 0.1 and 5x its
 * dt, where the structure's Newton then stalled at its rounding floor, which the FEM now
 * takes from the linearisation). Said once, in the
 * log. Returns the material of the particles whose net contacts have the largest damping
 * ratio (the pair's, as dem_net_wall_pair takes it), or -1 when none is damped. */
static int damped_net_material(const dem_sim *s)
{
    const dem_model *m = &s->model;
    if (m->prm.law != DEM_LAW_HERTZ_MINDLIN || m->prm.damping == DEM_DAMPING_HUNT_CROSSLEY) return -1;
    int worst = -1;
    double worst_zeta = 0.0;
    for (size_t i = 0; i < m->sph.n; i++) {
        const int k = m->sph.material[i];
        const double zi = m->materials[k].zeta;
        const double pair = 0.5 * (zi + (m->net.zeta >= 0.0 ? m->net.zeta : zi));
        if (pair > worst_zeta) {
            worst_zeta = pair;
            worst = k;
        }
    }
    return worst;
}

static void note_dashpot(participant *c)
{
    c->dashpot_noted = 1;
    const dem_model *m = &c->s->model;
    const int k = damped_net_material(c->s);
    if (k < 0 || !c->opt->progress) return;
    char wall[64] = "";
    if (m->net.restitution >= 0.0)
        snprintf(wall, sizeof wall, " and net_wall restitution %g", m->net.restitution);
    fprintf(c->opt->progress,
            "dem_solver: note: %s: damping \"%s\" on net contacts (material \"%s\", restitution "
            "%g%s): its dashpot grows like overlap^(1/4) from the first touch, so the Jacobian the "
            "coupler asks for is unbounded where a contact begins or ends, and the interface "
            "iteration may need more iterations and rejected tries there; \"damping\": "
            "\"hunt_crossley\" is continuous there (dem_solver/README.md, Contact model)\n",
            m->source, m->prm.damping == DEM_DAMPING_A7 ? "a7" : "fit", m->materials[k].name,
            m->materials[k].restitution, wall);
    fflush(c->opt->progress);
}

static int on_solve(void *ctx, const proto_message *cmd, proto_message *reply, nc_error *err)
{
    participant *c = ctx;
    dem_sim *s = c->s;
    if (!s->model.net.active) return nc_error_set(err, 1, "dem: SOLVE before INTERFACE");
    size_t n = s->model.net.n_nodes;
    const double *disp, *vel;
    if (proto_message_get_f64(cmd, "displacement", n, 3, &disp, NULL, err) ||
        proto_message_get_f64(cmd, "velocity", n, 3, &vel, NULL, err))
        return -1;
    dem_coupled_info info;
    /* the coupler asks for the force's linearisation with the value "jacobian" 1
     * (interface-Jacobian coupling, protocol/README.md §3.1) */
    int want_jacobian = proto_message_value(cmd, "jacobian", 0.0) != 0.0;
    if (want_jacobian && !c->dashpot_noted) note_dashpot(c);
    const proto_array *cn = proto_message_find(cmd, "compliance_nodes");
    if (want_jacobian && cn && cn->count > 0) {
        /* the structure's compliance at the contact nodes (capability "compliance",
         * protocol/README.md §3.4; dem_compliance.h): the wall ends where the structure,
         * linearised, puts it under the particles' force, and the reply says where */
        const int32_t *nodes;
        const double *S, *fref;
        size_t k = 0;
        if (proto_message_get_i32(cmd, "compliance_nodes", 0, 1, &nodes, &k, err) ||
            proto_message_get_f64(cmd, "compliance", 3 * k, 3 * k, &S, NULL, err) ||
            proto_message_get_f64(cmd, "compliance_force", n, 3, &fref, NULL, err))
            return -1;
        if (c->wall_end_cap < 3 * n) {
            free(c->wall_end);
            c->wall_end = malloc(3 * n * sizeof *c->wall_end);
            c->wall_end_cap = c->wall_end ? 3 * n : 0;
            if (!c->wall_end) return nc_error_set(err, 1, "dem: out of memory");
        }
        const dem_compliance cmp = {k, nodes, S, fref};
        dem_compliance_stats st;
        if (dem_sim_solve_with_compliance(s, cmd->dt_s, disp, vel, &cmp, c->force, c->wall_end,
                                          &info, &c->jac, &st, err) ||
            proto_message_add_f64(reply, "compliance_displacement", c->wall_end, n, 3, err) ||
            proto_message_set_value(reply, "compliance_evaluations", st.evaluations, err))
            return -1;
    } else if (dem_sim_solve_coupled_jacobian(s, cmd->dt_s, disp, vel, c->force, &info,
                                              want_jacobian ? &c->jac : NULL, err)) {
        return -1;
    }
    /* with "proximity" 1, zero blocks also name the nodes a particle in contact may reach
     * in the next step, so that the structure's compliance covers them (protocol/README.md
     * §3.4, dem_net_proximity.h) */
    if (want_jacobian && proto_message_value(cmd, "proximity", 0.0) != 0.0 &&
        dem_net_jacobian_add_proximity(s, &c->jac, cmd->dt_s, DEM_PROXIMITY_MAX_NODES, NULL,
                                       err))
        return -1;
    /* C = -dF/du̇ is zero (dem_net_jacobian.h), so only the stiffness blocks are sent */
    if (want_jacobian &&
        (proto_message_add_i32(reply, "jacobian_nodes", c->jac.nodes, c->jac.n_blocks, 2, err) ||
         proto_message_add_f64(reply, "jacobian_stiffness", c->jac.K, c->jac.n_blocks, 9, err) ||
         proto_message_set_value(reply, "jacobian_dropped_particles", (double)c->jac.n_dropped, err)))
        return -1;
    /* the energy values of protocol/README.md §3: elastic = contact springs, potential =
     * gravity, interface work = the net wall's work on the particles, no external loads */
    dem_step_energy e;
    dem_sim_step_energy(s, cmd->dt_s, c->e_start_j, &e);
    if (proto_message_add_f64(reply, "force", c->force, n, 3, err) ||
        proto_message_set_value(reply, "kinetic_energy_j", e.kinetic_j, err) ||
        proto_message_set_value(reply, "elastic_energy_j", e.contact_j, err) ||
        proto_message_set_value(reply, "potential_energy_j", e.gravity_j, err) ||
        proto_message_set_value(reply, "interface_work_j", e.wall_work_j, err) ||
        proto_message_set_value(reply, "external_work_j", 0.0, err) ||
        proto_message_set_value(reply, "dissipated_energy_j", e.dissipated_j, err) ||
        proto_message_set_value(reply, "near_interface", info.near_interface, err) ||
        proto_message_set_value(reply, "min_gap_m", info.min_gap_m, err) ||
        proto_message_set_value(reply, "contacts", (double)info.contacts, err) ||
        proto_message_set_value(reply, "substeps", (double)info.substeps, err) ||
        proto_message_set_value(reply, "max_particle_speed_m_s", max_body_speed(s), err))
        return -1;
    return 0;
}

static int on_accept(void *ctx, const proto_message *cmd, proto_message *reply, nc_error *err)
{
    (void)cmd;
    (void)reply;
    participant *c = ctx;
    dem_sim *s = c->s;
    if (s->time_s < c->next_out_s - 1e-6 * s->model.prm.output_interval_s) return 0;
    int rc = dem_output_write(c->out, s, c->force, err);
    /* the next multiple of the interval (not a running sum, which drifts off the FEM's
     * output times) */
    double interval = s->model.prm.output_interval_s;
    if (interval > 0.0)
        c->next_out_s = (floor(s->time_s / interval + 1e-9) + 1.0) * interval;
    else c->next_out_s = s->time_s;
    return rc;
}

/* A checkpoint name becomes part of a file name: letters, digits, '_' and '-' only. */
static int check_name(const char *name, nc_error *err)
{
    size_t len = strlen(name);
    if (len == 0 || len > 200)
        return nc_error_set(err, 1, "dem: checkpoint name of %zu characters (1..200)", len);
    for (size_t k = 0; k < len; k++)
        if (!isalnum((unsigned char)name[k]) && name[k] != '_' && name[k] != '-')
            return nc_error_set(err, 1, "dem: checkpoint name '%s': only letters, digits, '_' "
                                        "and '-' are allowed", name);
    return 0;
}

static void checkpoint_path(const participant *c, const char *name, char *out, size_t size)
{
    snprintf(out, size, "%s/checkpoint/dem_%s.h5", c->out->dir, name);
}

/* Keeps the two newest dem checkpoints of this run: the one just written (`keep`) and the one
 * before it (saved or resumed from); removes the other dem_*.h5 (and temporary files a crash
 * left). Checkpoints of the other participants are not touched. */
static void prune_checkpoints(const participant *c, const char *keep)
{
    char dir[1100], keep1[300], keep2[300];
    snprintf(dir, sizeof dir, "%s/checkpoint", c->out->dir);
    snprintf(keep1, sizeof keep1, "dem_%s.h5", keep);
    snprintf(keep2, sizeof keep2, "dem_%s.h5", c->last_checkpoint);
    const char *kept[2] = {keep1, c->last_checkpoint[0] ? keep2 : NULL};
    nc_ckpt_prune_except(dir, "dem_", kept, 2);
}

static int on_checkpoint(void *ctx, const proto_message *cmd, proto_message *reply, nc_error *err)
{
    (void)reply;
    participant *c = ctx;
    if (c->resume_failed)
        return nc_error_set(err, 1, "dem: the RESUME before failed; nothing to checkpoint");
    if (check_name(cmd->text, err)) return -1;
    char dir[1100], path[1400];
    snprintf(dir, sizeof dir, "%s/checkpoint", c->out->dir);
    checkpoint_path(c, cmd->text, path, sizeof path);
    nc_ckpt_table own = {0};
    own_entries(c, &own);
    /* the result rows the checkpoint counts are on the disk before it is */
    int rc = nc_file_make_dirs(dir, err) || dem_output_sync(c->out, err) ||
             dem_checkpoint_save(path, cmd->text, c->s, c->out, &own, cmd->step, cmd->time_s, err);
    nc_ckpt_table_free(&own);
    if (rc) return -1;
    prune_checkpoints(c, cmd->text);
    snprintf(c->last_checkpoint, sizeof c->last_checkpoint, "%s", cmd->text);
    if (c->opt->progress) {
        fprintf(c->opt->progress, "dem_solver: checkpoint %s (step %ld, t = %.9g s)\n", path,
                cmd->step, cmd->time_s);
        fflush(c->opt->progress);
    }
    return 0;
}

static int on_resume(void *ctx, const proto_message *cmd, proto_message *reply, nc_error *err)
{
    (void)reply;
    participant *c = ctx;
    if (check_name(cmd->text, err)) return -1;
    char path[1400];
    checkpoint_path(c, cmd->text, path, sizeof path);
    if (!c->s->model.net.active)
        return nc_error_set(err, 1, "%s: RESUME before INTERFACE (the checkpoint holds the net "
                                    "wall's state)", path);
    nc_ckpt_table own = {0};
    own_entries(c, &own);
    int rc = dem_checkpoint_load(path, c->s, c->out, &own, cmd->step, cmd->time_s, err);
    nc_ckpt_table_free(&own);
    if (rc) return -1; /* the state is untouched */
    /* the state is the checkpoint's from here: without its result files it must not step */
    if (dem_output_resume(c->out, c->s, err)) {
        c->resume_failed = 1;
        return -1;
    }
    c->resume_failed = 0;
    snprintf(c->last_checkpoint, sizeof c->last_checkpoint, "%s", cmd->text);
    if (c->opt->progress) {
        fprintf(c->opt->progress, "dem_solver: resumed from %s (step %ld, t = %.9g s, %ld output "
                                  "steps kept)\n", path, cmd->step, cmd->time_s, c->out->n_out);
        fflush(c->opt->progress);
    }
    return 0;
}

static void on_report(void *ctx, const char *message)
{
    participant *c = ctx;
    if (c->opt->problems) fprintf(c->opt->problems, "dem_solver: %s\n", message);
}

int dem_participant_check_input(const dem_sim *s, nc_error *err)
{
    if (!(s->model.net.youngs_modulus_pa > 0.0))
        return nc_error_set(err, 1, "%s: net_wall: missing (the coupled mode needs the net wall "
                                    "material: youngs_modulus_pa, poisson_ratio, friction)",
                            s->model.source);
    return 0;
}

int dem_participant_run(dem_sim *s, dem_output *out, const dem_participant_options *opt,
                        const volatile sig_atomic_t *stop, nc_error *err)
{
    if (dem_participant_check_input(s, err)) return -1;
    proto_options popt;
    proto_options_default(&popt);
    popt.idle_timeout_ms = opt->idle_timeout_ms;
    proto_participant *p;
    if (proto_participant_open(&p, opt->endpoint, "dem", "netcouple dem_solver", "restore jacobian checkpoint compliance", &popt, err))
        return -1;
    if (opt->endpoint_file && nc_file_write_line(opt->endpoint_file, proto_participant_endpoint(p), err)) {
        proto_participant_close(p);
        return -1;
    }
    if (opt->progress) {
        fprintf(opt->progress, "dem_solver: %zu spheres, dt = %.3e s, serving %s\n", s->model.sph.n,
                s->model.prm.dt_s, proto_participant_endpoint(p));
        fflush(opt->progress);
    }
    participant c = {.s = s, .out = out, .opt = opt, .next_out_s = s->model.prm.output_interval_s};
    dem_net_jacobian_init(&c.jac);
    c.jac.particle_response = DEM_JAC_RESPOND;   /* the FEM grows its pattern for the pairs */
    const proto_serve_handlers handlers = {
        .interface = on_interface, .save_state = on_save, .restore_state = on_restore,
        .solve = on_solve, .accept_step = on_accept, .checkpoint = on_checkpoint,
        .resume = on_resume, .report = on_report};
    proto_serve_summary sum;
    int served = proto_serve(p, &handlers, &c, stop, &sum, err);
    int rc;
    if (served == 1) {
        if (opt->problems) fprintf(opt->problems, "dem_solver: interrupted at t = %g s\n", s->time_s);
        rc = 130;
    } else if (served < 0) {
        if (err && err->code == PROTO_ERR_IDLE)
            nc_error_prefix(err, "no command from the coupler (idle timeout)");
        rc = -1;
    } else if (sum.failed + sum.rejected > 0) {
        /* the coupler was told, but the run had errors: not a clean exit */
        nc_error_set(err, 1, "%ld command(s) answered with an error during the run (see above)",
                     sum.failed + sum.rejected);
        rc = 1;
    } else {
        rc = 0;
    }
    /* the result rows still in memory: a run (or a stopped one) whose results could not be
     * written failed, and says why; an earlier error is said instead */
    nc_error flushing;
    if (dem_output_flush(out, &flushing) && (rc == 0 || rc == 130)) {
        if (err) *err = flushing;
        rc = -1;
    }
    proto_participant_close(p);
    dem_net_jacobian_free(&c.jac);
    free(c.force);
    free(c.wall_end);
    return rc;
}
