/* coupler.json parsing: defaults, every section, and clear messages for bad input. */
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <setjmp.h>
#include <cmocka.h>
#include "../nc_test_assert.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "../../coupler/cpl_config.h"

static int parse(const char *text, cpl_config *c, nc_error *err)
{
    cJSON *root = cJSON_Parse(text);
    assert_non_null(root);
    cpl_config_default(c);
    int rc = cpl_config_parse(c, root, "coupler.json", "/case", err);
    cJSON_Delete(root);
    return rc;
}

static double relax_key(const cpl_config *c, const char *key)
{
    double value = NAN;
    assert_int_equal(cpl_relax_settings_get(&c->loop.relax, key, &value), 0);
    return value;
}

static void test_minimal_and_defaults(void **state)
{
    (void)state;
    cpl_config c;
    nc_error err;
    assert_int_equal(parse("{\"scheme\": \"weak\", \"dt\": 0.001, \"end_time\": 0.5}", &c, &err), 0);
    assert_int_equal(c.loop.scheme, CPL_SCHEME_WEAK);
    assert_near(c.loop.dt_s, 1e-3, 0.0);
    assert_near(c.loop.end_time_s, 0.5, 0.0);
    assert_near(c.loop.tol_abs, 1e-6, 0.0);
    assert_near(c.loop.work_tol, 0.0, 0.0);   /* eq. (35) as the paper has it */
    assert_near(c.loop.newton_estimate, 0.0, 0.0);
    assert_int_equal(c.loop.interface_compliance, 0);
    assert_int_equal(c.loop.structure_predictor, 1);   /* acts with interface_compliance */
    assert_int_equal(c.loop.compliance_proximity, 1);  /* likewise */
    assert_int_equal(c.loop.max_iterations, 50);
    /* Aitken with its Newton rule, the first iteration's cap left to the regime (0) */
    assert_string_equal(cpl_relax_settings_method(&c.loop.relax), "aitken");
    assert_near(relax_key(&c, "alpha"), 0.5, 0.0);
    assert_near(relax_key(&c, "first_iteration_cap"), 0.0, 0.0);
    assert_near(relax_key(&c, "newton_contraction"), 0.5, 0.0);
    assert_int_equal(c.loop.on_max_iterations, CPL_MAXIT_ACCEPT);
    assert_int_equal(c.loop.predictor, CPL_PREDICT_LINEAR);   /* weak: the linear guess */
    assert_string_equal(c.fem.endpoint, "");
    /* step control: dt_min dt / 64, doubling after 4 good steps, unconverged not accepted */
    assert_near(cpl_loop_settings_dt_min(&c.loop), 1e-3 / 64.0, 0.0);
    assert_int_equal(c.loop.grow_after, 4);
    assert_int_equal(c.loop.reject_slow, 1);
    assert_int_equal(c.accept_unconverged, 0);
    /* energy guard: 1 % of the input energy + 1e-9 J, not accepted */
    assert_near(c.loop.energy.tol_rel, 0.01, 0.0);
    assert_near(c.loop.energy.tol_abs_j, 1e-9, 0.0);
    assert_int_equal(c.accept_energy_growth, 0);
    /* strong: the quadratic guess, unless the file says otherwise */
    assert_int_equal(parse("{\"scheme\": \"strong\", \"dt\": 0.001, \"end_time\": 0.5}", &c, &err), 0);
    assert_int_equal(c.loop.predictor, CPL_PREDICT_QUADRATIC);
    assert_int_equal(parse("{\"scheme\": \"strong\", \"dt\": 0.001, \"end_time\": 0.5,"
                           " \"predictor\": \"linear\"}", &c, &err), 0);
    assert_int_equal(c.loop.predictor, CPL_PREDICT_LINEAR);
    assert_int_equal(parse("{\"scheme\": \"weak\", \"dt\": 0.001, \"end_time\": 0.5,"
                           " \"predictor\": \"quadratic\"}", &c, &err), 0);
    assert_int_equal(c.loop.predictor, CPL_PREDICT_QUADRATIC);
    /* the Jacobian check is opt-in */
    assert_int_equal(c.loop.jacobian_check_interval, 0);
    assert_int_equal(parse("{\"scheme\": \"strong\", \"dt\": 0.001, \"end_time\": 0.5,"
                           " \"jacobian_check\": 10}", &c, &err), 0);
    assert_int_equal(c.loop.jacobian_check_interval, 10);
}

static void test_full_file(void **state)
{
    (void)state;
    const char *text =
        "{\"fem\": {\"endpoint\": \"tcp://127.0.0.1:5555\"},"
        " \"dem\": {\"endpoint_file\": \"dem.endpoint\"},"
        " \"scheme\": \"strong\", \"dt\": 2e-3, \"end_time\": 1, \"start_time\": 0.5,"
        " \"tolerance\": 1e-8, \"relative_tolerance\": 1e-4, \"work_tolerance\": 1e-6,"
        " \"newton_estimate\": 0.1, \"structure_predictor\": false,"
        " \"compliance_proximity\": false,"
        " \"max_iterations\": 12,"
        " \"on_max_iterations\": \"stop\", \"relaxed_quantity\": \"force\","
        " \"predictor\": \"linear\", \"max_steps\": 7,"
        " \"relaxation\": {\"method\": \"iqn-ils\", \"alpha\": 0.1, \"filter\": 1e-3,"
        "   \"reuse_steps\": 2, \"max_columns\": 30},"
        " \"efficiency\": {\"far_step\": true, \"far_step_factor\": 100,"
        "   \"skip_fem_without_contact\": true, \"contact_force_threshold\": 1e-9},"
        " \"timeouts\": {\"connect\": 5, \"reply\": 60, \"shutdown\": 2},"
        " \"step_control\": {\"dt_min\": 1e-4, \"grow_after\": 10, \"reject_slow\": false},"
        " \"accept_unconverged\": true,"
        " \"energy_tolerance\": 0.05, \"energy_tolerance_abs\": 1e-3, \"accept_energy_growth\": true,"
        " \"output\": {\"iterations\": false, \"progress_interval\": 1}}";
    cpl_config c;
    nc_error err;
    assert_int_equal(parse(text, &c, &err), 0);
    assert_string_equal(c.fem.endpoint, "tcp://127.0.0.1:5555");
    assert_string_equal(c.dem.endpoint_file, "/case/dem.endpoint");
    assert_int_equal(c.loop.scheme, CPL_SCHEME_STRONG);
    assert_near(c.loop.start_time_s, 0.5, 0.0);
    assert_near(c.loop.tol_rel, 1e-4, 0.0);
    assert_near(c.loop.work_tol, 1e-6, 0.0);
    assert_near(c.loop.newton_estimate, 0.1, 0.0);
    assert_int_equal(c.loop.structure_predictor, 0);
    assert_int_equal(c.loop.compliance_proximity, 0);
    assert_int_equal(c.loop.on_max_iterations, CPL_MAXIT_STOP);
    assert_int_equal(c.loop.relaxed, CPL_RELAXED_FORCE);
    assert_int_equal(c.loop.predictor, CPL_PREDICT_LINEAR);
    assert_int_equal(c.loop.max_steps, 7);
    assert_string_equal(cpl_relax_settings_method(&c.loop.relax), "iqn-ils");
    assert_near(relax_key(&c, "alpha"), 0.1, 0.0);
    assert_near(relax_key(&c, "reuse_steps"), 2.0, 0.0);
    assert_near(relax_key(&c, "max_columns"), 30.0, 0.0);
    assert_near(relax_key(&c, "filter"), 1e-3, 0.0);
    assert_true(c.loop.far_step && c.loop.skip_fem_without_contact);
    assert_near(c.reply_timeout_s, 60.0, 0.0);
    assert_int_equal(c.write_iterations, 0);
    assert_near(cpl_loop_settings_dt_min(&c.loop), 1e-4, 0.0);
    assert_int_equal(c.loop.grow_after, 10);
    assert_int_equal(c.loop.reject_slow, 0);
    assert_int_equal(c.accept_unconverged, 1);
    assert_near(c.loop.energy.tol_rel, 0.05, 0.0);
    assert_near(c.loop.energy.tol_abs_j, 1e-3, 0.0);
    assert_int_equal(c.accept_energy_growth, 1);
}

static void expect_error(const char *text, const char *fragment)
{
    cpl_config c;
    nc_error err;
    nc_error_clear(&err);
    assert_int_equal(parse(text, &c, &err), -1);
    if (!strstr(err.message, fragment)) fail_msg("message '%s' lacks '%s'", err.message, fragment);
}

static void test_bad_input_messages(void **state)
{
    (void)state;
    expect_error("{\"scheme\": \"strong\", \"dt\": 0.001, \"end_time\": 1, \"tolerence\": 1}",
                 "coupler.json: tolerence: unknown key");
    expect_error("{\"dt\": 0.001, \"end_time\": 1}", "scheme");
    expect_error("{\"scheme\": \"implicit\", \"dt\": 0.001, \"end_time\": 1}", "\"weak\", \"strong\"");
    expect_error("{\"scheme\": \"weak\", \"dt\": -1, \"end_time\": 1}", "dt");
    expect_error("{\"scheme\": \"weak\", \"dt\": 0.1, \"end_time\": 0}", "end_time");
    expect_error("{\"scheme\": \"strong\", \"dt\": 0.1, \"end_time\": 1,"
                 " \"relaxation\": {\"method\": \"aitken\", \"alpha_min\": 1, \"alpha_max\": 0.5}}",
                 "alpha_min");
    expect_error("{\"scheme\": \"strong\", \"dt\": 0.1, \"end_time\": 1,"
                 " \"relaxation\": {\"method\": \"broyden\"}}", "relaxation.method");
    /* restart_growth below 1 would back-track on every iteration */
    expect_error("{\"scheme\": \"strong\", \"dt\": 0.1, \"end_time\": 1,"
                 " \"relaxation\": {\"method\": \"aitken\", \"restart_growth\": 0.5}}",
                 "restart_growth");
    /* 0 is the internal "not given" of the cap, not a value a file may set */
    expect_error("{\"scheme\": \"strong\", \"dt\": 0.1, \"end_time\": 1,"
                 " \"relaxation\": {\"method\": \"aitken\", \"first_iteration_cap\": 0}}",
                 "first_iteration_cap");
    /* a contraction of 1 or more would take α = 1 on a residual that does not shrink */
    expect_error("{\"scheme\": \"strong\", \"dt\": 0.1, \"end_time\": 1,"
                 " \"relaxation\": {\"method\": \"aitken\", \"newton_contraction\": 1}}",
                 "newton_contraction");
    expect_error("{\"scheme\": \"strong\", \"dt\": 0.1, \"end_time\": 1,"
                 " \"fem\": {\"endpoint\": \"a\", \"endpoint_file\": \"b\"}}", "not both");
    expect_error("{\"scheme\": \"strong\", \"dt\": 0.1, \"end_time\": 1, \"max_iterations\": 0}",
                 "max_iterations");
    expect_error("{\"scheme\": \"strong\", \"dt\": 0.1, \"end_time\": 1,"
                 " \"step_control\": {\"dt_min\": 0.2}}", "step_control.dt_min");
    expect_error("{\"scheme\": \"strong\", \"dt\": 0.1, \"end_time\": 1,"
                 " \"step_control\": {\"grow_after\": 0}}", "step_control.grow_after");
    expect_error("{\"scheme\": \"strong\", \"dt\": 0.1, \"end_time\": 1,"
                 " \"step_control\": {\"reject_slow\": 1}}", "step_control.reject_slow");
    expect_error("{\"scheme\": \"strong\", \"dt\": 0.1, \"end_time\": 1,"
                 " \"step_control\": {\"dt_mn\": 0.01}}", "dt_mn: unknown key");
    expect_error("{\"scheme\": \"strong\", \"dt\": 0.1, \"end_time\": 1,"
                 " \"accept_unconverged\": 1}", "accept_unconverged");
    expect_error("{\"scheme\": \"strong\", \"dt\": 0.1, \"end_time\": 1,"
                 " \"energy_tolerance\": -0.01}", "energy_tolerance");
    expect_error("{\"scheme\": \"strong\", \"dt\": 0.1, \"end_time\": 1,"
                 " \"work_tolerance\": 2}", "work_tolerance");
    expect_error("{\"scheme\": \"strong\", \"dt\": 0.1, \"end_time\": 1,"
                 " \"newton_estimate\": 0.7}", "newton_estimate");
    expect_error("{\"scheme\": \"strong\", \"dt\": 0.1, \"end_time\": 1,"
                 " \"stop_on_energy_growth\": true, \"accept_energy_growth\": true}",
                 "stop_on_energy_growth and accept_energy_growth");
    expect_error("{\"scheme\": \"strong\", \"dt\": 0.1, \"end_time\": 1,"
                 " \"accept_energy_growth\": \"yes\"}", "accept_energy_growth");
    expect_error("{\"scheme\": \"strong\", \"dt\": 0.1, \"end_time\": 1,"
                 " \"jacobian_check\": -1}", "jacobian_check");
    /* it checks the linearisation along the iteration's steps: nothing to check without */
    expect_error("{\"scheme\": \"weak\", \"dt\": 0.1, \"end_time\": 1,"
                 " \"jacobian_check\": 1}", "jacobian_check needs the strong scheme");
    expect_error("{\"scheme\": \"strong\", \"dt\": 0.1, \"end_time\": 1,"
                 " \"relaxed_quantity\": \"force\", \"jacobian_check\": 1}",
                 "jacobian_check needs the strong scheme");
    expect_error("{\"scheme\": \"strong\", \"dt\": 0.1, \"end_time\": 1,"
                 " \"interface_jacobian\": false, \"jacobian_check\": 1}",
                 "interface_jacobian");
}

static void test_load_missing_file(void **state)
{
    (void)state;
    cpl_config c;
    nc_error err;
    cpl_config_default(&c);
    assert_int_equal(cpl_config_load(&c, "/nonexistent/coupler.json", &err), -1);
    assert_non_null(strstr(err.message, "/nonexistent/coupler.json"));
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_minimal_and_defaults),
        cmocka_unit_test(test_full_file),
        cmocka_unit_test(test_bad_input_messages),
        cmocka_unit_test(test_load_missing_file),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
