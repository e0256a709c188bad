/* test_motion — rigid-body motion against analytic results: rolling without slip down an
 * incline at 5/7 g sin θ, sliding at g (sin θ - μ cos θ) when tan θ > 7/2 μ, a cluster's free
 * flight conserving angular momentum and energy, and cluster mass properties. */
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

/* A sphere released on an incline (plane through the origin with normal tilted by θ about y,
 * gravity -z). Returns the acceleration along the slope measured between t = 0.2 s and 0.6 s
 * and the slip velocity v - ω R at the end. */
static double incline(double theta_deg, double mu, double *slip)
{
    double th = theta_deg * M_PI / 180.0, R = 0.1;
    double n[3] = {sin(th), 0.0, cos(th)}; /* surface z = -x tan θ: downhill is +x */
    char json[2048];
    snprintf(json, sizeof json,
             "{\"materials\": [{\"name\": \"m\", \"youngs_modulus_pa\": 1e8, \"poisson_ratio\": 0.25,"
             " \"density_kg_m3\": 2500, \"restitution\": 0.3, \"friction\": %.17g}],"
             " \"particles\": [{\"position\": [%.17g, 0, %.17g], \"radius\": %g}],"
             " \"planes\": [{\"point\": [0, 0, 0], \"normal\": [%.17g, 0, %.17g]}], \"dt_s\": 2e-5}",
             mu, R * n[0], R * n[2], R, n[0], n[2]);
    dem_sim s;
    dem_test_build(&s, json);
    nc_error err;
    double down[3] = {cos(th), 0.0, -sin(th)}; /* unit vector down the slope */
    double v1 = 0, t1 = 0;
    int steps = (int)(0.6 / 2e-5);
    for (int k = 1; k <= steps; k++) {
        assert_int_equal(dem_sim_step(&s, 2e-5, &err), 0);
        if (k == steps / 3) {
            v1 = s.model.bod.vel[0] * down[0] + s.model.bod.vel[2] * down[2];
            t1 = s.time_s;
        }
    }
    double v2 = s.model.bod.vel[0] * down[0] + s.model.bod.vel[2] * down[2];
    double a = (v2 - v1) / (s.time_s - t1);
    /* rolling towards +x about +y: the contact point is at rest when v = ω_y R */
    *slip = v2 - s.model.bod.omega[1] * R;
    dem_sim_free(&s);
    return a;
}

static void test_rolling_without_slip(void **state)
{
    (void)state;
    double slip, g = 9.81, th = 20.0 * M_PI / 180.0;
    double a = incline(20.0, 0.5, &slip); /* tan 20° = 0.36 < 7/2 · 0.5 */
    double ref = 5.0 / 7.0 * g * sin(th);
    print_message("rolling: a = %.5f m/s² (5/7 g sin θ = %.5f), slip %.2e m/s\n", a, ref, slip);
    assert_near_rel(a, ref, 0.01); /* 1 % */
    /* contact point at rest: slip << v (0.5 % of v: the lever arm is R - δ/2, not R) */
    assert_near(slip, 0.0, 5e-3 * a * 0.6);
}

static void test_sliding(void **state)
{
    (void)state;
    double slip, g = 9.81, th = 30.0 * M_PI / 180.0, mu = 0.1;
    double a = incline(30.0, mu, &slip); /* tan 30° = 0.58 > 7/2 · 0.1 = 0.35 */
    double ref = g * (sin(th) - mu * cos(th));
    print_message("sliding: a = %.5f m/s² (g (sin θ - μ cos θ) = %.5f), slip %.3f m/s\n", a, ref, slip);
    assert_near_rel(a, ref, 0.01); /* 1 % */
    /* slip grows: ω̇ R = 5/2 μ g cos θ < a */
    assert_true(slip > 0.1);
}

static const char *cluster_json =
    "{\"materials\": [{\"name\": \"m\", \"youngs_modulus_pa\": 1e7, \"poisson_ratio\": 0.25,"
    " \"density_kg_m3\": 1000, \"restitution\": 0.5, \"friction\": 0.5}],"
    " \"clusters\": [{\"spheres\": [{\"position\": [0, 0, 0], \"radius\": 0.1},"
    "   {\"position\": [0.2, 0, 0], \"radius\": 0.1}, {\"position\": [0.05, 0.15, 0.02], \"radius\": 0.07}],"
    "   \"velocity\": [1, 0, 2], \"angular_velocity\": [3, 5, 1]}],"
    " \"gravity\": [0, 0, -9.81], \"dt_s\": 1e-5}";

static void test_cluster_free_flight(void **state)
{
    (void)state;
    dem_sim s;
    dem_test_build(&s, cluster_json);
    assert_int_equal(s.model.bod.n, 1);
    assert_int_equal(s.model.sph.n, 3);
    nc_error err;
    double L0[3] = {s.model.bod.angmom[0], s.model.bod.angmom[1], s.model.bod.angmom[2]};
    double e0 = dem_sim_kinetic_energy(&s) + dem_sim_potential_energy(&s);
    double x0[3] = {s.model.bod.pos[0], s.model.bod.pos[1], s.model.bod.pos[2]};
    /* the body-frame distance between two spheres of the rigid body must not change */
    double d0 = hypot(hypot(s.model.sph.pos[3] - s.model.sph.pos[0], s.model.sph.pos[4] - s.model.sph.pos[1]), s.model.sph.pos[5] - s.model.sph.pos[2]);
    double omega0[3] = {s.model.bod.omega[0], s.model.bod.omega[1], s.model.bod.omega[2]};
    for (int k = 0; k < 100000; k++) assert_int_equal(dem_sim_step(&s, 1e-5, &err), 0); /* 1 s */
    double e1 = dem_sim_kinetic_energy(&s) + dem_sim_potential_energy(&s);
    double L1n = 0, dL = 0;
    for (int d = 0; d < 3; d++) {
        dL += (s.model.bod.angmom[d] - L0[d]) * (s.model.bod.angmom[d] - L0[d]);
        L1n += L0[d] * L0[d];
    }
    /* angular velocity recomputed from the orientation: R I⁻¹ Rᵀ L, its L back must match */
    double dw = fabs(s.model.bod.omega[0] - omega0[0]) + fabs(s.model.bod.omega[1] - omega0[1]) +
                fabs(s.model.bod.omega[2] - omega0[2]);
    print_message("|ΔL|/|L| = %.2e, energy %.6f -> %.6f, ω changed by %.3f (precession)\n",
                  sqrt(dL / L1n), e0, e1, dw);
    assert_below(sqrt(dL / L1n), 1e-12); /* no torque: L exactly constant */
    assert_near_rel(e1, e0, 1e-3); /* quaternion integration, 0.1 % */
    assert_true(dw > 1e-3); /* an asymmetric body precesses: ω is not constant */
    /* ballistic centre of mass: x0 + v t + ½ g t² (1e-6 m, O(dt) of symplectic Euler) */
    double t = s.time_s;
    assert_near(s.model.bod.pos[0], x0[0] + 1.0 * t, 1e-6);
    assert_near(s.model.bod.pos[2], x0[2] + 2.0 * t - 0.5 * 9.81 * t * t, 1e-3 * 0.5 * 9.81 * t * t + 1e-4);
    double d1 = hypot(hypot(s.model.sph.pos[3] - s.model.sph.pos[0], s.model.sph.pos[4] - s.model.sph.pos[1]), s.model.sph.pos[5] - s.model.sph.pos[2]);
    assert_near(d1, d0, 1e-12);
    dem_sim_free(&s);
}

static void test_cluster_mass_properties(void **state)
{
    (void)state;
    /* two equal spheres (R, m) at ±a on x: I_xx = 2 · 2/5 m R², I_yy = I_zz = 2 (2/5 m R² + m a²) */
    const char *json =
        "{\"materials\": [{\"name\": \"m\", \"youngs_modulus_pa\": 1e7, \"poisson_ratio\": 0.25,"
        " \"density_kg_m3\": 1000, \"restitution\": 0.5, \"friction\": 0.5}],"
        " \"clusters\": [{\"spheres\": [{\"position\": [0.9, 2, 3], \"radius\": 0.1},"
        "   {\"position\": [1.1, 2, 3], \"radius\": 0.1}]}]}";
    dem_sim s;
    dem_test_build(&s, json);
    double m = 4.0 / 3.0 * M_PI * 1e-3 * 1000, R = 0.1, a = 0.1;
    const double *I = s.model.bod.inertia_body;
    assert_near(s.model.bod.mass[0], 2 * m, 1e-12);
    assert_near(s.model.bod.pos[0], 1.0, 1e-12);
    assert_near(s.model.bod.pos[1], 2.0, 1e-12);
    assert_near(I[0], 2 * 0.4 * m * R * R, 1e-12);
    assert_near(I[4], 2 * (0.4 * m * R * R + m * a * a), 1e-12);
    assert_near(I[8], I[4], 1e-12);
    assert_near(I[1], 0.0, 1e-15);
    dem_sim_free(&s);
}

/* A sphere at rest on a floor moving sideways at V (a conveyor): friction accelerates it until
 * it rolls without slip; angular momentum about the contact line gives v = 2/7 V. Checked for
 * a moving plane and for a moving STL mesh (the wall velocity enters the contact velocity). */
static void test_conveyor_moving_walls(void **state)
{
    (void)state;
    static const char *stl =
        "solid floor\n"
        "facet normal 0 0 1\n outer loop\n vertex -10 -10 0\n vertex 10 -10 0\n vertex 10 10 0\n endloop\nendfacet\n"
        "facet normal 0 0 1\n outer loop\n vertex -10 -10 0\n vertex 10 10 0\n vertex -10 10 0\n endloop\nendfacet\n"
        "endsolid floor\n";
    char path[512], json[2048];
    dem_test_write_file(path, sizeof path, "conveyor.stl", stl, strlen(stl));
    for (int c = 0; c < 2; c++) {
        snprintf(json, sizeof json,
                 "{\"materials\": [{\"name\": \"m\", \"youngs_modulus_pa\": 1e8, \"poisson_ratio\": 0.25,"
                 " \"density_kg_m3\": 2500, \"restitution\": 0.3, \"friction\": 0.4}],"
                 " \"particles\": [{\"position\": [0, 0, 0.1], \"radius\": 0.1}], %s, \"dt_s\": 2e-5}",
                 c == 0 ? "\"planes\": [{\"point\": [0, 0, 0], \"normal\": [0, 0, 1], \"velocity\": [1, 0, 0]}]"
                        : "\"meshes\": [{\"file\": \"PATH\", \"velocity\": [1, 0, 0]}]");
        char *at = strstr(json, "PATH");
        if (at) {
            char rest[2048];
            snprintf(rest, sizeof rest, "%s", at + 4);
            snprintf(at, sizeof json - (size_t)(at - json), "%s%s", path, rest);
        }
        dem_sim s;
        dem_test_build(&s, json);
        nc_error err;
        for (int k = 0; k < 25000; k++) assert_int_equal(dem_sim_step(&s, 2e-5, &err), 0); /* 0.5 s */
        print_message("%s moving at 1 m/s: sphere v = %.5f m/s (2/7 = %.5f), ω R = %.5f\n",
                      c == 0 ? "plane" : "mesh", s.model.bod.vel[0], 2.0 / 7.0, -s.model.bod.omega[1] * 0.1);
        assert_near_rel(s.model.bod.vel[0], 2.0 / 7.0, 0.01); /* 1 % */
        dem_sim_free(&s);
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_rolling_without_slip),
        cmocka_unit_test(test_sliding),
        cmocka_unit_test(test_cluster_free_flight),
        cmocka_unit_test(test_cluster_mass_properties),
        cmocka_unit_test(test_conveyor_moving_walls),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
