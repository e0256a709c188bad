/* Energy balance and energy guard of the coupling loop (cpl_energy.h) against the closed-form
 * participants (cpl_test_models.h), whose discrete energies and dissipation are exact:
 * a converged strong run closes the balance to round-off and the coupling creates no energy
 * beyond the interface tolerance; weak coupling of the added-mass-like problem at a step
 * above its stability limit creates energy and fires the guard, naming the step; the input
 * energy counts the start state. */
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <setjmp.h>
#include <cmocka.h>
#include "../nc_test_assert.h"

#include <math.h>
#include <string.h>

#include "cpl_test_models.h"
#include "../../coupler/cpl_loop.h"

typedef struct energy_log {
    long steps, above_steps, first_above;
    double max_abs_closure, max_input, last_created, max_created;
    cpl_energy_record last;
} energy_log;

static int on_step(void *ctx, const cpl_step_record *rec, nc_error *err)
{
    (void)err;
    energy_log *l = ctx;
    const cpl_energy_record *e = &rec->energy;
    assert_true(e->available);
    l->max_abs_closure = fmax(l->max_abs_closure, fabs(e->closure_j));
    l->max_input = fmax(l->max_input, e->input_j);
    l->max_created = fmax(l->max_created, e->created_j);
    l->last_created = e->created_j;
    if (e->above) {
        if (l->above_steps == 0) l->first_above = rec->step;
        l->above_steps++;
    }
    l->last = *e;
    l->steps++;
    return 0;
}

typedef struct run_out {
    int rc;
    energy_log log;
    cpl_energy energy;
    double fem_kinetic_j, fem_elastic_j;   /* from the structure's final state */
} run_out;

static void run(const tm_problem *pb, const cpl_loop_settings *s, run_out *out)
{
    memset(out, 0, sizeof *out);
    out->log.first_above = -1;
    tm_structure st;
    tm_particles pa;
    tm_structure_init(&st, pb->nodes, pb->m, pb->k, pb->k_link);
    tm_particles_init(&pa, pb->nodes, pb->mp, pb->kc, pb->g);
    cpl_participant fem = tm_structure_participant(&st), dem = tm_particles_participant(&pa);
    cpl_observer obs = {&out->log, NULL, on_step, NULL, NULL};
    cpl_loop *loop;
    nc_error err;
    assert_int_equal(cpl_loop_create(&loop, s, pb->nodes, NULL, NULL, &err), 0);
    out->rc = cpl_loop_run(loop, &fem, &dem, &obs, NULL, NULL, &err);
    out->energy = *cpl_loop_energy(loop);
    for (size_t i = 0; i < st.nd; i++) {
        out->fem_kinetic_j += 0.5 * st.m[i] * st.v0[i] * st.v0[i];
        for (size_t j = 0; j < st.nd; j++) out->fem_elastic_j += 0.5 * st.u0[i] * st.K[i * st.nd + j] * st.u0[j];
    }
    cpl_loop_free(loop);
    tm_structure_free(&st);
    tm_particles_free(&pa);
}

/* Converged strong coupling of the mild problem over 50 steps: the reports close the
 * balance E(n) − E(0) + Σ D − Σ mismatch to round-off (1e-12 of the input energy), the
 * interface work mismatch is below 1e-6 of the input energy (the residual 1e-10 m times
 * forces of ~10 N over 50 steps: ~1e-9 J against 3.7 J; measured 1e-11 J), the system's
 * energy never rises above its start (backward Euler dissipates), the guard stays silent,
 * and the structure's last reported energies are those of its final state. */
static void test_strong_balance_closes(void **state)
{
    (void)state;
    cpl_loop_settings s = tm_loop_settings(CPL_SCHEME_STRONG, 0.01, 0.5);
    run_out r;
    run(&TM_MILD, &s, &r);
    assert_int_equal(r.rc, 0);
    assert_int_equal(r.log.steps, 50);
    print_message("strong: input %.6e J, created %.3e J, closure %.3e J, dissipated fem %.4e J "
                  "dem %.4e J\n", r.log.max_input, r.log.last_created, r.log.max_abs_closure,
                  r.energy.sum_fem_diss_j, r.energy.sum_dem_diss_j);
    assert_below(1e-3, r.log.max_input);                  /* a real motion */
    assert_below(r.log.max_abs_closure, 1e-12 * r.log.max_input);
    assert_below(fabs(r.energy.sum_mismatch_j), 1e-6 * r.log.max_input);
    assert_below(r.log.max_created, 1e-6 * r.log.max_input);
    assert_int_equal(r.log.above_steps, 0);
    assert_int_equal(r.energy.first_step, -1);
    assert_below(0.0, r.energy.sum_fem_diss_j);           /* backward Euler dissipates */
    assert_below(0.0, r.energy.sum_dem_diss_j);
    assert_near_rel(r.log.last.fem_kinetic_j, r.fem_kinetic_j, 1e-12);
    assert_near_rel(r.log.last.fem_elastic_j, r.fem_elastic_j, 1e-12);
}

/* Weak coupling of the hard problem (|J| ≈ 45 at Δt = 0.01 s: the explicit exchange is far
 * above its stability limit) creates energy at the interface: the guard fires within the
 * first steps (measured: step 0, 3.3 J above the start against a limit of 0.035 J), names
 * the first step whose energy rise exceeds 1 % of the input energy, and the balance still
 * closes (the reports are exact, only the coupling is wrong). The same problem with
 * converged strong coupling creates none. */
static void test_weak_unstable_fires_guard(void **state)
{
    (void)state;
    cpl_loop_settings s = tm_loop_settings(CPL_SCHEME_WEAK, 0.01, 0.1);
    run_out r;
    run(&TM_HARD, &s, &r);
    assert_int_equal(r.rc, 0);                            /* the loop itself goes on */
    print_message("weak, hard: first step above the limit %ld (t = %g s), created %.3e J "
                  "there (limit %.3e J), at the end %.3e J of input %.3e J\n",
                  r.energy.first_step, r.energy.first_time_s, r.energy.first_created_j,
                  r.energy.first_limit_j, r.log.last_created, r.log.max_input);
    assert_true(r.energy.first_step >= 0);
    assert_int_equal(r.energy.first_step, r.log.first_above);
    assert_true(r.energy.first_step < 5);
    assert_near(r.energy.first_time_s, 0.01 * (double)(r.energy.first_step + 1), 1e-12);
    assert_below(r.energy.first_limit_j, r.energy.first_created_j);
    assert_int_equal(r.energy.above_steps, r.log.above_steps);
    assert_below(r.log.max_abs_closure, 1e-9 * r.log.max_input);

    s = tm_loop_settings(CPL_SCHEME_STRONG, 0.01, 0.1);
    nc_error err;
    assert_int_equal(cpl_relax_settings_select(&s.relax, "iqn-ils", &err), 0);
    run(&TM_HARD, &s, &r);
    assert_int_equal(r.rc, 0);
    print_message("strong, hard: created %.3e J of input %.3e J\n", r.log.max_created,
                  r.log.max_input);
    assert_int_equal(r.energy.first_step, -1);
    assert_below(r.log.max_created, 1e-6 * r.log.max_input);
}

/* energy_tolerance is a share of the input energy: over 3 steps of the weak run above the
 * guard stays silent at twice the largest created/input ratio and fires at half of it. */
static void test_tolerance_is_relative_to_input(void **state)
{
    (void)state;
    cpl_loop_settings s = tm_loop_settings(CPL_SCHEME_WEAK, 0.01, 0.03);
    run_out r;
    run(&TM_HARD, &s, &r);
    double ratio = r.log.max_created / r.log.max_input;
    s.energy.tol_rel = 2.0 * ratio;
    run(&TM_HARD, &s, &r);
    assert_int_equal(r.energy.first_step, -1);
    s.energy.tol_rel = 0.5 * ratio;
    run(&TM_HARD, &s, &r);
    assert_true(r.energy.first_step >= 0);
}

/* A first step that holds a whole impact: a 90 J rock (10 m above its potential's zero, 50 J
 * of potential) bounced off within it and kept 10 J, 80 J dissipated, 0.5 J fallen. The input
 * counts the start state (90 J + what fell in the step), not only what the first report has
 * left, so the guard's limit is not ten times too tight. */
static void test_input_counts_the_start_state(void **state)
{
    (void)state;
    cpl_energy_settings s;
    cpl_energy_settings_default(&s);
    cpl_energy e;
    cpl_energy_init(&e, &s);
    cpl_energy_report fem = {1, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, NAN};
    cpl_energy_report dem = {1, 10.0, 0.0, 49.5, 0.0, 0.0, 80.0, NAN};
    cpl_energy_record rec;
    cpl_energy_step(&e, 0, 1e-3, &fem, &dem, &rec);
    assert_near(e.e0_j, 139.5, 1e-12);
    assert_near(rec.input_j, 90.0, 1e-12);
    assert_int_equal(rec.above, 0);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_strong_balance_closes),
        cmocka_unit_test(test_weak_unstable_fires_guard),
        cmocka_unit_test(test_tolerance_is_relative_to_input),
        cmocka_unit_test(test_input_counts_the_start_state),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
