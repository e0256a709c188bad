/* test_coupling_force — net_wall.coupling_force: "end_of_step" returns the Hertz force of the
 * last sub-step (particle at its position before that sub-step, wall at its end-of-step
 * position; checked against eq. (A.5) computed here), "average" (the default) the impulse over
 * the step divided by dt; both equal the weight for a particle at rest on the net; a bad value
 * is rejected naming the field. net_wall.wall_position "middle" puts the wall of each
 * sub-step at the sub-step's middle (checked through the last sub-step's force). */
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <setjmp.h>
#include <cmocka.h>
#include "../nc_test_assert.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

#include "dem_test_util.h"

/* One sphere R 0.1 m (E 1e7, nu 0.2, rho 2500, COR 1: no dashpot) above a one-edge net
 * (E 1e7, nu 0.2, no friction); `force` is "" (key left out) or the coupling_force value. */
static void build_wall(dem_sim *s, double z, double vz, double gz, const char *force,
                       const char *wall_position)
{
    char json[2048], key[256] = "";
    size_t used = 0;
    if (force[0]) used += (size_t)snprintf(key, sizeof key, ", \"coupling_force\": \"%s\"", force);
    if (wall_position[0])
        snprintf(key + used, sizeof key - used, ", \"wall_position\": \"%s\"", wall_position);
    snprintf(json, sizeof json,
             "{\"materials\": [{\"name\": \"m\", \"youngs_modulus_pa\": 1e7, \"poisson_ratio\": 0.2,"
             " \"density_kg_m3\": 2500, \"restitution\": 1.0, \"friction\": 0.0}],"
             " \"particles\": [{\"position\": [0.3, 0, %.17g], \"radius\": 0.1, \"velocity\": [0, 0, %g]}],"
             " \"net_wall\": {\"youngs_modulus_pa\": 1e7, \"poisson_ratio\": 0.2, \"friction\": 0.0%s},"
             " \"gravity\": [0, 0, %g], \"dt_s\": 1e-4}",
             z, vz, key, gz);
    dem_test_build(s, json);
    double xyz[6] = {0, 0, 0, 1, 0, 0};
    int32_t edges[2] = {0, 1};
    nc_error err;
    assert_int_equal(dem_sim_set_interface(s, 2, NULL, xyz, 1, edges, &err), 0);
}

static void build(dem_sim *s, double z, double vz, double gz, const char *force)
{
    build_wall(s, z, vz, gz, force, "");
}

/* Hertz normal force (eq. (A.5)) of a sphere R on the cable at overlap d: 4/3 E* sqrt(R) d^1.5 with
 * 1/E* = 2 (1 - 0.2²) / 1e7 (sphere and cable of the same material). */
static double hertz(double d)
{
    double e_star = 1.0 / (2.0 * (1.0 - 0.04) / 1e7);
    return d > 0.0 ? 4.0 / 3.0 * e_star * sqrt(0.1) * pow(d, 1.5) : 0.0;
}

/* The sphere moves down into the edge while the edge moves down too (but more slowly):
 * "end_of_step" gives exactly the Hertz force of the last sub-step (symplectic Euler: the
 * sphere was at x_N - h v_N, the wall at its end position), split by the lever rule
 * (t = 0.3: 70 % to node 0), and differs from the step average of a growing contact. */
static void test_end_of_step_is_end_state(void **state)
{
    (void)state;
    dem_sim s, a;
    build(&s, 0.099, -1.0, 0.0, "end_of_step");
    build(&a, 0.099, -1.0, 0.0, "");
    double disp[6] = {0, 0, -0.002, 0, 0, -0.002}, vel[6] = {0, 0, -0.4, 0, 0, -0.4};
    double f[6], fa[6];
    dem_coupled_info info;
    nc_error err;
    const double dt = 5e-3; /* 50 sub-steps */
    assert_int_equal(dem_sim_begin_step(&s, &err), 0);
    assert_int_equal(dem_sim_solve_coupled(&s, dt, disp, vel, f, &info, &err), 0);
    assert_int_equal(dem_sim_begin_step(&a, &err), 0);
    assert_int_equal(dem_sim_solve_coupled(&a, dt, disp, vel, fa, &info, &err), 0);
    double h = dt / (double)info.substeps;
    assert_int_equal(info.substeps, 50);
    double overlap = 0.1 - ((s.model.bod.pos[2] - h * s.model.bod.vel[2]) - (-0.002));
    double expect = hertz(overlap);
    print_message("end overlap %.6f m: end force %.3f N (Hertz %.3f N), average %.3f N\n",
                  overlap, -(f[2] + f[5]), expect, -(fa[2] + fa[5]));
    assert_true(overlap > 0.0);
    /* same trajectory whatever is reported (1e-15 m): the option only changes the reply */
    assert_near(s.model.bod.pos[2], a.model.bod.pos[2], 1e-15);
    /* force ON the net is downward; round-off only (1e-9 relative) */
    assert_near(-(f[2] + f[5]), expect, 1e-9 * expect);
    assert_near(f[2], 0.7 * (f[2] + f[5]), 1e-9 * expect);
    assert_below(fabs(f[0]) + fabs(f[1]) + fabs(f[3]) + fabs(f[4]), 1e-9 * expect);
    /* a growing contact: the end force exceeds the step average by far more than round-off */
    assert_true(-(f[2] + f[5]) > 1.2 * -(fa[2] + fa[5]));
    dem_sim_free(&s);
    dem_sim_free(&a);
}

/* At rest on the edge (after damping out the drop with many steps, gravity on) both replies
 * carry the weight (1e-6 relative: the residual oscillation of the undamped contact is
 * excluded by starting exactly at the static overlap). */
static void test_rest_both_equal_weight(void **state)
{
    (void)state;
    const char *kinds[2] = {"average", "end_of_step"};
    for (int k = 0; k < 2; k++) {
        dem_sim s;
        build(&s, 0.1, 0.0, -9.81, kinds[k]);
        double m = s.model.bod.mass[0], w = m * 9.81;
        /* static overlap: hertz(d) = w */
        double e_star = 1.0 / (2.0 * (1.0 - 0.04) / 1e7);
        double d = pow(w / (4.0 / 3.0 * e_star * sqrt(0.1)), 2.0 / 3.0);
        dem_sim_free(&s);
        build(&s, 0.1 - d, 0.0, -9.81, kinds[k]);
        double zero[6] = {0}, f[6];
        dem_coupled_info info;
        nc_error err;
        for (int step = 0; step < 3; step++) {
            assert_int_equal(dem_sim_begin_step(&s, &err), 0);
            assert_int_equal(dem_sim_solve_coupled(&s, 1e-3, zero, zero, f, &info, &err), 0);
        }
        print_message("%s: net force %.6f N, weight %.6f N\n", kinds[k], -(f[2] + f[5]), w);
        assert_near(-(f[2] + f[5]), w, 1e-6 * w);
        dem_sim_free(&s);
    }
}

/* wall_position: the last of 50 sub-steps has its wall at 49.5/50 of the way to the end
 * position ("middle") or at the end ("end", the default): the end_of_step reply is the Hertz
 * force for that wall position (1e-9 relative), and the sphere's path differs between the two. */
static void test_wall_position_middle(void **state)
{
    (void)state;
    const char *positions[2] = {"end", "middle"};
    const double frac[2] = {1.0, 49.5 / 50.0};
    double z_end[2];
    for (int k = 0; k < 2; k++) {
        dem_sim s;
        build_wall(&s, 0.099, -1.0, 0.0, "end_of_step", positions[k]);
        double disp[6] = {0, 0, -0.002, 0, 0, -0.002}, vel[6] = {0, 0, -0.4, 0, 0, -0.4}, f[6];
        dem_coupled_info info;
        nc_error err;
        const double dt = 5e-3;
        assert_int_equal(dem_sim_begin_step(&s, &err), 0);
        assert_int_equal(dem_sim_solve_coupled(&s, dt, disp, vel, f, &info, &err), 0);
        assert_int_equal(info.substeps, 50);
        double h = dt / (double)info.substeps;
        double overlap = 0.1 - ((s.model.bod.pos[2] - h * s.model.bod.vel[2]) - frac[k] * -0.002);
        double expect = hertz(overlap);
        print_message("wall %s: last sub-step overlap %.6f m, force %.3f N (Hertz %.3f N)\n",
                      positions[k], overlap, -(f[2] + f[5]), expect);
        assert_true(overlap > 0.0);
        assert_near(-(f[2] + f[5]), expect, 1e-9 * expect);
        z_end[k] = s.model.bod.pos[2];
        dem_sim_free(&s);
    }
    /* the middle wall is half a sub-step behind on its way down, higher under the sphere coming
     * down onto it: more overlap, the sphere is pushed up more */
    print_message("sphere at the end: wall end %.9f m, middle %.9f m\n", z_end[0], z_end[1]);
    assert_true(z_end[1] > z_end[0] + 1e-9);
}

static void test_bad_value_rejected(void **state)
{
    (void)state;
    dem_sim s;
    nc_error err;
    int rc = dem_test_try_build(&s,
        "{\"materials\": [{\"name\": \"m\", \"youngs_modulus_pa\": 1e7, \"poisson_ratio\": 0.2,"
        " \"density_kg_m3\": 2500, \"restitution\": 1.0, \"friction\": 0.0}],"
        " \"particles\": [{\"position\": [0.3, 0, 0.2], \"radius\": 0.1}],"
        " \"net_wall\": {\"youngs_modulus_pa\": 1e7, \"poisson_ratio\": 0.2, \"friction\": 0.0,"
        " \"coupling_force\": \"midstep\"}}", &err);
    assert_int_equal(rc, -1);
    assert_non_null(strstr(err.message, "coupling_force"));
    dem_sim_free(&s);
    rc = dem_test_try_build(&s,
        "{\"materials\": [{\"name\": \"m\", \"youngs_modulus_pa\": 1e7, \"poisson_ratio\": 0.2,"
        " \"density_kg_m3\": 2500, \"restitution\": 1.0, \"friction\": 0.0}],"
        " \"particles\": [{\"position\": [0.3, 0, 0.2], \"radius\": 0.1}],"
        " \"net_wall\": {\"youngs_modulus_pa\": 1e7, \"poisson_ratio\": 0.2, \"friction\": 0.0,"
        " \"wall_position\": \"start\"}}", &err);
    assert_int_equal(rc, -1);
    assert_non_null(strstr(err.message, "wall_position"));
    dem_sim_free(&s);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_end_of_step_is_end_state),
        cmocka_unit_test(test_rest_both_equal_weight),
        cmocka_unit_test(test_wall_position_middle),
        cmocka_unit_test(test_bad_value_rejected),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
