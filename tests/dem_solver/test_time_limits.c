/* test_time_limits — time and size sanity of the DEM: a dt_s that cannot advance the time or
 * would take more than 1e9 steps is refused when dem.json is read (it used to print
 * "-9223372036854775808 steps" and "done"), and a coupling step needing more than 1e8
 * sub-steps is refused by the coupled solve instead of running for hours. */
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <setjmp.h>
#include <cmocka.h>

#include <stdio.h>
#include <string.h>

#include "dem_test_util.h"

#define ROCK "\"materials\": [{\"name\": \"rock\", \"youngs_modulus_pa\": 3e10, \"poisson_ratio\": 0.2," \
             " \"density_kg_m3\": 2600, \"restitution\": 0.3, \"friction\": 0.5}]," \
             " \"particles\": [{\"position\": [0.3, 0, 0.5], \"radius\": 0.25, \"velocity\": [0, 0, -20]}]"

static void expect_refused(const char *json, const char *const *pieces)
{
    dem_sim s;
    nc_error err;
    if (dem_test_try_build(&s, json, &err) == 0) fail_msg("accepted: %s", json);
    dem_sim_free(&s);
    for (const char *const *p = pieces; *p; p++)
        if (!strstr(err.message, *p)) fail_msg("message lacks \"%s\": %s", *p, err.message);
}

static void test_standalone_step(void **state)
{
    (void)state;
    static const char *const tiny[] = {"dt_s", "1e-300", "too small", NULL};
    expect_refused("{" ROCK ", \"dt_s\": 1e-300, \"end_time_s\": 1}", tiny);
    static const char *const late[] = {"dt_s", "float spacings", NULL};
    expect_refused("{" ROCK ", \"dt_s\": 1, \"end_time_s\": 1e17}", late);
    static const char *const many[] = {"dt_s", "2e+09 steps", NULL};
    expect_refused("{" ROCK ", \"dt_s\": 1e-5, \"end_time_s\": 2e4}", many);
    dem_sim s;
    dem_test_build(&s, "{" ROCK ", \"dt_s\": 1e-6, \"end_time_s\": 2}"); /* 2e6 steps: fine */
    dem_sim_free(&s);
}

static void test_coupled_substeps(void **state)
{
    (void)state;
    dem_sim s;
    nc_error err;
    dem_test_build(&s, "{" ROCK ", \"dt_s\": 1e-5, \"net_wall\": {\"youngs_modulus_pa\": 1e11,"
                       " \"poisson_ratio\": 0.3, \"friction\": 0.3}}");
    double xyz[6] = {0, 0, 0, 1, 0, 0}, zero[6] = {0}, f[6];
    int32_t edges[2] = {0, 1};
    assert_int_equal(dem_sim_set_interface(&s, 2, NULL, xyz, 1, edges, &err), 0);
    dem_coupled_info info;
    assert_int_equal(dem_sim_begin_step(&s, &err), 0);
    /* 1e6 s in steps of 1e-5 s: 1e11 sub-steps */
    assert_int_equal(dem_sim_solve_coupled(&s, 1e6, zero, zero, f, &info, &err), -1);
    if (!strstr(err.message, "sub-steps") || !strstr(err.message, "1e+11"))
        fail_msg("%s", err.message);
    /* a normal coupling step still works after the refusal */
    assert_int_equal(dem_sim_restore(&s, &err), 0);
    if (dem_sim_solve_coupled(&s, 1e-3, zero, zero, f, &info, &err)) fail_msg("%s", err.message);
    assert_int_equal(info.substeps, 100);
    dem_sim_free(&s);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_standalone_step),
        cmocka_unit_test(test_coupled_substeps),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
