/* test_checkpoint — checkpoint and resume of the coupling loop, bit for bit.
 *
 * A strong-coupling run with Aitken (and one with IQN-ILS, whose columns are kept across
 * steps) and step rejection active (the structure fails every solve with Δt > 0.005 s in
 * [0.05, 0.08) s: two rejections, half steps, the step control growing back) is run three
 * ways with the closed-form participants of cpl_test_models.c:
 *   U  uninterrupted, checkpoints every 0.03 s;
 *   I  the same, stopped (as by a signal) right after its checkpoint at 0.06 s, which lies
 *      inside the window of reduced steps (step control state, relaxation history, energy
 *      balance and counters all non-trivial there);
 *   R  a fresh loop and fresh participants loading I's checkpoint files and resuming.
 * Every iteration record, step record (the energy balance included) and rejection record
 * and every accepted interface displacement, velocity and force of I up to the checkpoint
 * followed by R must equal U's, compared as bytes; so must the summary's counters.
 */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <cmocka.h>

#include "cpl_test_models.h"
#include "../nc_test_assert.h"

/* Everything a run reports, flattened to doubles in the order it is reported. */
typedef struct trace {
    double *v;
    size_t n, cap;
    long steps, rejections, iterations, checkpoints;
    size_t mark;                 /* n at the checkpoint the run stops after */
    long stop_after;             /* stop after this many checkpoints (0: never) */
    volatile sig_atomic_t stop;
    const cpl_loop *loop;
    const char *dir;             /* the coupler's checkpoint files go here */
    char last_name[64];
} trace;

static void push(trace *t, double x)
{
    if (t->n == t->cap) {
        t->cap = t->cap ? 2 * t->cap : 4096;
        t->v = realloc(t->v, t->cap * sizeof *t->v);
        assert_non_null(t->v);
    }
    t->v[t->n++] = x;
}

static void push_n(trace *t, const double *x, size_t n)
{
    for (size_t i = 0; i < n; i++) push(t, x[i]);
}

static int on_iteration(void *ctx, const cpl_iteration_record *r, nc_error *err)
{
    (void)err;
    trace *t = ctx;
    t->iterations++;
    const double v[] = {1.0, (double)r->step, r->iteration, r->time_s, r->dt_s, r->residual,
                        r->alpha, r->fem_solved, r->attempt};
    push_n(t, v, sizeof v / sizeof *v);
    push_n(t, r->contact_force, 3);
    return 0;
}

static int on_step(void *ctx, const cpl_step_record *r, nc_error *err)
{
    (void)err;
    trace *t = ctx;
    t->steps++;
    const cpl_energy_record *e = &r->energy;
    const double v[] = {2.0, (double)r->step, r->jacobian_blocks, r->time_s, r->dt_s,
                        r->iterations, r->converged, r->residual, r->in_contact,
                        r->near_interface, r->min_gap_m, r->rejected, e->available,
                        e->fem_kinetic_j, e->fem_elastic_j, e->fem_potential_j,
                        e->dem_kinetic_j, e->dem_elastic_j, e->dem_potential_j,
                        e->fem_interface_work_j, e->dem_interface_work_j,
                        e->interface_created_j, e->fem_dissipated_j, e->dem_dissipated_j,
                        e->external_work_j, e->created_j, e->input_j, e->limit_j,
                        e->closure_j, e->above};
    push_n(t, v, sizeof v / sizeof *v);
    push_n(t, r->contact_force, 3);
    /* the accepted interface state the next step starts from */
    size_t n3 = 3 * TM_HARD.nodes;
    push_n(t, cpl_loop_displacement(t->loop), n3);
    push_n(t, cpl_loop_velocity(t->loop), n3);
    push_n(t, cpl_loop_force(t->loop), n3);
    return 0;
}

static int on_reject(void *ctx, const cpl_reject_record *r, nc_error *err)
{
    (void)err;
    trace *t = ctx;
    t->rejections++;
    const double v[] = {3.0, (double)r->step, r->attempt, r->time_s, r->dt_s, r->next_dt_s,
                        r->iterations, r->residual, (double)r->reason};
    push_n(t, v, sizeof v / sizeof *v);
    return 0;
}

static void checkpoint_path(const char *dir, const char *name, char *out, size_t size)
{
    snprintf(out, size, "%s/coupler_%s.h5", dir, name);
}

static int on_checkpoint(void *ctx, long step, double time_s, const char *name, nc_error *err)
{
    trace *t = ctx;
    t->checkpoints++;
    const double v[] = {4.0, (double)step, time_s};
    push_n(t, v, 3);
    char path[1024];
    checkpoint_path(t->dir, name, path, sizeof path);
    cpl_ckpt_table tab = {0};
    cpl_loop_checkpoint_entries((cpl_loop *)t->loop, &tab);
    int rc = cpl_ckpt_save(&tab, path, err);
    cpl_ckpt_table_free(&tab);
    snprintf(t->last_name, sizeof t->last_name, "%s", name);
    if (t->stop_after && t->checkpoints == t->stop_after) {
        t->mark = t->n;
        t->stop = 1;   /* as a signal would: the loop ends at its next request */
    }
    return rc;
}

typedef struct run_out {
    int rc;
    cpl_timing timing;
    cpl_energy energy;
    long fem_checkpoints, dem_checkpoints;
} run_out;

/* One run; resume_from: the checkpoint name to resume from (files in dir), or NULL. */
static void run(const char *method, const char *dir, trace *t, const char *resume_from,
                run_out *out)
{
    const tm_problem *pb = &TM_HARD;
    mkdir(dir, 0755);
    tm_structure s;
    tm_particles p;
    tm_structure_init(&s, pb->nodes, pb->m, pb->k, pb->k_link);
    tm_particles_init(&p, pb->nodes, pb->mp, pb->kc, pb->g);
    s.fail = (tm_fail_window){0.05, 0.08, 0.005, 0};
    s.checkpoint_dir = p.checkpoint_dir = dir;
    cpl_loop_settings set = tm_loop_settings(CPL_SCHEME_STRONG, 0.01, 0.155);
    nc_error err;
    assert_int_equal(cpl_relax_settings_select(&set.relax, method, &err), 0);
    set.checkpoint_interval_s = 0.03;
    cpl_loop *loop;
    assert_int_equal(cpl_loop_create(&loop, &set, pb->nodes, NULL, NULL, &err), 0);
    t->loop = loop;
    t->dir = dir;
    if (resume_from) {
        char path[1024];
        checkpoint_path(dir, resume_from, path, sizeof path);
        cpl_ckpt_table tab = {0};
        assert_int_equal(cpl_loop_checkpoint_prepare(loop, path, &err), 0);
        cpl_loop_checkpoint_entries(loop, &tab);
        int rc = cpl_ckpt_load(&tab, path, &err);
        if (rc) fail_msg("%s", err.message);
        cpl_ckpt_table_free(&tab);
        cpl_loop_resumed(loop, resume_from);
    }
    cpl_participant fem = tm_structure_participant(&s), dem = tm_particles_participant(&p);
    cpl_observer obs = {t, on_iteration, on_step, on_reject, on_checkpoint};
    cpl_failure failure;
    out->rc = cpl_loop_run(loop, &fem, &dem, &obs, &t->stop, &failure, &err);
    if (out->rc && err.code != CPL_ERR_INTERRUPTED) fail_msg("%s", err.message);
    if (out->rc) assert_int_equal(err.code, CPL_ERR_INTERRUPTED);
    out->timing = *cpl_loop_timing(loop);
    out->energy = *cpl_loop_energy(loop);
    out->fem_checkpoints = s.checkpoints;
    out->dem_checkpoints = p.checkpoints;
    if (resume_from) {
        assert_int_equal(s.resumes, 1);
        assert_int_equal(p.resumes, 1);
    }
    cpl_loop_free(loop);
    tm_structure_free(&s);
    tm_particles_free(&p);
}

static void check_method(const char *method)
{
    const char *base = getenv("NC_TMP") ? getenv("NC_TMP") : "/tmp";
    char dir_u[900], dir_i[900];
    snprintf(dir_u, sizeof dir_u, "%s/checkpoint_%s_u", base, method);
    snprintf(dir_i, sizeof dir_i, "%s/checkpoint_%s_i", base, method);
    trace u = {0}, i = {0}, r = {0};
    run_out ou, oi, orr;
    run(method, dir_u, &u, NULL, &ou);
    assert_int_equal(ou.rc, 0);
    i.stop_after = 2;
    run(method, dir_i, &i, NULL, &oi);
    assert_int_equal(oi.rc, -1);   /* interrupted after its second checkpoint */
    assert_true(i.mark > 0);
    run(method, dir_i, &r, i.last_name, &orr);
    assert_int_equal(orr.rc, 0);

    /* the run is the kind this test is about: rejections before and after the checkpoint,
     * checkpoints at 0.03, 0.06, 0.09, 0.12, 0.15 (none at the end) */
    assert_string_equal(i.last_name, "step_000007");   /* 5 steps of 0.01, 2 of 0.005 */
    assert_int_equal(u.checkpoints, 5);
    assert_int_equal(ou.fem_checkpoints, 5);
    assert_int_equal(ou.dem_checkpoints, 5);
    assert_int_equal(ou.timing.rejected_attempts, 2);
    assert_int_equal(oi.timing.rejected_attempts, 1);
    assert_int_equal(r.rejections, 1);
    assert_true(u.iterations > 2 * u.steps);   /* strong coupling really iterates */

    /* I up to its checkpoint, then R: exactly U */
    assert_int_equal(i.mark + r.n, u.n);
    size_t differ = u.n;
    for (size_t k = 0; k < u.n && differ == u.n; k++) {
        const double *x = k < i.mark ? &i.v[k] : &r.v[k - i.mark];
        if (memcmp(x, &u.v[k], sizeof *x) != 0) differ = k;
    }
    if (differ != u.n)
        fail_msg("%s: resumed run differs at trace entry %zu of %zu: %.17g vs %.17g", method,
                 differ, u.n, differ < i.mark ? i.v[differ] : r.v[differ - i.mark], u.v[differ]);
    /* the summary counts the whole run */
    assert_int_equal(orr.timing.steps, ou.timing.steps);
    assert_int_equal(orr.timing.iterations, ou.timing.iterations);
    assert_int_equal(orr.timing.fem_solves, ou.timing.fem_solves);
    assert_int_equal(orr.timing.dem_solves, ou.timing.dem_solves);
    assert_int_equal(orr.timing.rejected_attempts, ou.timing.rejected_attempts);
    assert_int_equal(orr.timing.reduced_steps, ou.timing.reduced_steps);
    assert_int_equal(orr.timing.unconverged_steps, ou.timing.unconverged_steps);
    assert_memory_equal(&orr.timing.min_dt_s, &ou.timing.min_dt_s, sizeof(double));
    assert_memory_equal(&orr.energy.created_j, &ou.energy.created_j, sizeof(double));
    assert_memory_equal(&orr.energy.input_j, &ou.energy.input_j, sizeof(double));
    assert_int_equal(orr.energy.above_steps, ou.energy.above_steps);
    print_message("%s: %zu trace values, %ld steps, %ld iterations, %ld rejections; resumed "
                  "from %s: identical\n", method, u.n, u.steps, u.iterations, u.rejections,
                  i.last_name);
    free(u.v);
    free(i.v);
    free(r.v);
}

static void test_resume_aitken(void **state)
{
    (void)state;
    check_method("aitken");
}

static void test_resume_iqn_ils(void **state)
{
    (void)state;
    check_method("iqn-ils");
}

/* A checkpoint of another model, or of the same model with other settings, is refused
 * before anything is loaded, naming the file and the setting (the interface size, dt,
 * work_tolerance, the relaxation method with both names); the load itself names the entry
 * whose size differs. */
static void test_resume_other_model(void **state)
{
    (void)state;
    const char *base = getenv("NC_TMP") ? getenv("NC_TMP") : "/tmp";
    char dir[900], path[1024];
    snprintf(dir, sizeof dir, "%s/checkpoint_other", base);
    trace u = {0};
    u.stop_after = 1;
    run_out o;
    run("aitken", dir, &u, NULL, &o);
    checkpoint_path(dir, u.last_name, path, sizeof path);
    nc_error err;
    static const struct {
        size_t extra_nodes;
        double dt_s, work_tol;
        const char *method, *says;
    } other[] = {
        {1, 0.01, 0.0, "aitken", "interface dofs"},
        {0, 0.005, 0.0, "aitken", "dt (s) = 0.01"},
        {0, 0.01, 1e-6, "aitken", "work_tolerance"},
        {0, 0.01, 0.0, "iqn-ils", "relaxation.method \"aitken\", this run has \"iqn-ils\""},
    };
    for (size_t k = 0; k < sizeof other / sizeof other[0]; k++) {
        cpl_loop_settings set = tm_loop_settings(CPL_SCHEME_STRONG, other[k].dt_s, 0.155);
        set.work_tol = other[k].work_tol;
        assert_int_equal(cpl_relax_settings_select(&set.relax, other[k].method, &err), 0);
        cpl_loop *loop;
        assert_int_equal(cpl_loop_create(&loop, &set, TM_HARD.nodes + other[k].extra_nodes,
                                         NULL, NULL, &err), 0);
        assert_int_equal(cpl_loop_checkpoint_prepare(loop, path, &err), -1);
        assert_non_null(strstr(err.message, path));
        assert_non_null(strstr(err.message, other[k].says));
        if (other[k].extra_nodes) {
            /* loaded regardless, the first array of another size is named */
            cpl_ckpt_table tab = {0};
            cpl_loop_checkpoint_entries(loop, &tab);
            assert_int_equal(cpl_ckpt_load(&tab, path, &err), -1);
            assert_non_null(strstr(err.message, path));
            assert_non_null(strstr(err.message, "/loop/u"));
            cpl_ckpt_table_free(&tab);
        }
        cpl_loop_free(loop);
    }
    /* the same settings: prepared, loaded and resumed */
    cpl_loop_settings set = tm_loop_settings(CPL_SCHEME_STRONG, 0.01, 0.155);
    assert_int_equal(cpl_relax_settings_select(&set.relax, "aitken", &err), 0);
    cpl_loop *loop;
    assert_int_equal(cpl_loop_create(&loop, &set, TM_HARD.nodes, NULL, NULL, &err), 0);
    cpl_ckpt_table tab = {0};
    assert_int_equal(cpl_loop_checkpoint_prepare(loop, path, &err), 0);
    cpl_loop_checkpoint_entries(loop, &tab);
    assert_int_equal(cpl_ckpt_load(&tab, path, &err), 0);
    cpl_loop_resumed(loop, u.last_name);
    cpl_ckpt_table_free(&tab);
    cpl_loop_free(loop);
    /* a file that is not there */
    assert_int_equal(cpl_ckpt_read_long("no_such_checkpoint.h5", "/loop/step", &u.steps, &err), -1);
    assert_non_null(strstr(err.message, "no_such_checkpoint.h5"));
    free(u.v);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_resume_aitken),
        cmocka_unit_test(test_resume_iqn_ils),
        cmocka_unit_test(test_resume_other_model),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
