/* test_cluster_inertia — clusters with given mass properties (dem.json mass_kg,
 * center_of_mass, inertia_kg_m2) instead of the spheres' sum: the body takes them (mass,
 * centre, offsets, impact_energy_j speed), a torque-free spin conserves angular momentum and
 * energy and follows Euler's equations of the given tensor (integrated here independently with
 * RK4), an eccentric frictionless elastic impact on a plane gives the impulse 2 m_eff v_n of
 * rigid-body impact theory with the given mass and inertia, mass_kg alone scales the spheres'
 * inertia, and bad values are refused naming file and field. */
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <setjmp.h>
#include <cmocka.h>
#include "../nc_test_assert.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

#include "dem_integrate.h"
#include "dem_test_util.h"

static void matvec(const double m[9], const double v[3], double out[3])
{
    for (int a = 0; a < 3; a++) out[a] = m[3 * a] * v[0] + m[3 * a + 1] * v[1] + m[3 * a + 2] * v[2];
}

static void cross(const double a[3], const double b[3], double out[3])
{
    out[0] = a[1] * b[2] - a[2] * b[1];
    out[1] = a[2] * b[0] - a[0] * b[2];
    out[2] = a[0] * b[1] - a[1] * b[0];
}

static double dot(const double a[3], const double b[3])
{
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

static void inverse3(const double a[9], double inv[9])
{
    double det = a[0] * (a[4] * a[8] - a[5] * a[7]) - a[1] * (a[3] * a[8] - a[5] * a[6]) +
                 a[2] * (a[3] * a[7] - a[4] * a[6]);
    inv[0] = (a[4] * a[8] - a[5] * a[7]) / det; inv[1] = (a[2] * a[7] - a[1] * a[8]) / det;
    inv[2] = (a[1] * a[5] - a[2] * a[4]) / det; inv[3] = (a[5] * a[6] - a[3] * a[8]) / det;
    inv[4] = (a[0] * a[8] - a[2] * a[6]) / det; inv[5] = (a[2] * a[3] - a[0] * a[5]) / det;
    inv[6] = (a[3] * a[7] - a[4] * a[6]) / det; inv[7] = (a[1] * a[6] - a[0] * a[7]) / det;
    inv[8] = (a[0] * a[4] - a[1] * a[3]) / det;
}

/* R diag(d) Rᵀ with R the rotation by `angle` about the unit axis `u` (a full tensor in the
 * input frame, off-diagonal terms and all). */
static void rotated_tensor(const double d[3], const double u[3], double angle, double out[9])
{
    double c = cos(angle), s = sin(angle), r[9];
    for (int a = 0; a < 3; a++)
        for (int b = 0; b < 3; b++) r[3 * a + b] = (a == b ? c : 0.0) + (1 - c) * u[a] * u[b];
    r[1] -= s * u[2]; r[2] += s * u[1]; r[3] += s * u[2];
    r[5] -= s * u[0]; r[6] -= s * u[1]; r[7] += s * u[0];
    for (int a = 0; a < 3; a++)
        for (int b = 0; b < 3; b++) {
            out[3 * a + b] = 0.0;
            for (int k = 0; k < 3; k++) out[3 * a + b] += r[3 * a + k] * d[k] * r[3 * b + k];
        }
}

static void tensor_json(char *buf, size_t size, const double I[9])
{
    snprintf(buf, size, "[[%.17g, %.17g, %.17g], [%.17g, %.17g, %.17g], [%.17g, %.17g, %.17g]]",
             I[0], I[1], I[2], I[3], I[4], I[5], I[6], I[7], I[8]);
}

#define ROCK "{\"materials\": [{\"name\": \"rock\", \"youngs_modulus_pa\": 3e10, \"poisson_ratio\": 0.25," \
             " \"density_kg_m3\": 2650, \"restitution\": %s, \"friction\": %s}],"

/* Euler's equations of a free rigid body in its body frame, I ω̇ = (I ω) × ω. */
static void euler_rate(const double I[9], const double Iinv[9], const double w[3], double dw[3])
{
    double Iw[3], t[3];
    matvec(I, w, Iw);
    cross(Iw, w, t);
    matvec(Iinv, t, dw);
}

static void test_torque_free_spin(void **state)
{
    (void)state;
    const double d[3] = {150.0, 220.0, 300.0}, axis[3] = {0.48, 0.6, 0.64};
    const double com[3] = {0.05, -0.02, 0.03}, w0[3] = {2.0, -3.0, 4.0}, mass = 1200.0;
    double I[9], Iinv[9];
    rotated_tensor(d, axis, 0.7, I);
    inverse3(I, Iinv);
    char tj[512], json[4096];
    tensor_json(tj, sizeof tj, I);
    snprintf(json, sizeof json, ROCK
             " \"clusters\": [{\"spheres\": [{\"position\": [0, 0, 0], \"radius\": 0.3},"
             "   {\"position\": [0.35, 0, 0], \"radius\": 0.2}, {\"position\": [0, 0.3, 0.1], \"radius\": 0.2},"
             "   {\"position\": [-0.1, -0.1, 0.3], \"radius\": 0.15}],"
             "   \"mass_kg\": %.17g, \"center_of_mass\": [%.17g, %.17g, %.17g], \"inertia_kg_m2\": %s,"
             "   \"impact_energy_j\": 60000, \"impact_direction\": [1, 0, 0],"
             "   \"angular_velocity\": [%g, %g, %g]}],"
             " \"gravity\": [0, 0, 0], \"dt_s\": 1e-5}",
             "0.3", "0.5", mass, com[0], com[1], com[2], tj, w0[0], w0[1], w0[2]);
    dem_sim s;
    dem_test_build(&s, json);
    const dem_bodies *B = &s.model.bod;
    /* the body is the given one, not the spheres' sum (≈ 4.1e2 kg of 2650 kg/m³ spheres) */
    assert_near(B->mass[0], mass, 1e-12 * mass);
    for (int k = 0; k < 3; k++) assert_near(B->pos[k], com[k], 1e-15);
    for (int k = 0; k < 9; k++) assert_near(B->inertia_body[k], I[k], 1e-12 * d[2]);
    /* the speed of impact_energy_j from the true mass: sqrt(2 · 60 kJ / 1200 kg) = 10 m/s */
    assert_near(B->vel[0], 10.0, 1e-12);
    /* spheres where they were given; offsets from the given centre */
    assert_near(s.model.sph.pos[3], 0.35, 1e-15);
    assert_near(s.model.sph.offset[3], 0.35 - com[0], 1e-15);
    double L0[3], e0;
    matvec(I, w0, L0);
    e0 = 0.5 * dot(w0, L0);
    for (int k = 0; k < 3; k++) assert_near(B->angmom[k], L0[k], 1e-12 * sqrt(dot(L0, L0)));
    double p0[4][3];
    for (int q = 0; q < 4; q++)
        for (int k = 0; k < 3; k++) p0[q][k] = s.model.sph.pos[3 * q + k] - com[k];

    /* independent: RK4 of Euler's equations in the body frame (= input frame at t = 0) */
    double w[3] = {w0[0], w0[1], w0[2]}, h = 1e-5;
    nc_error err;
    double worst = 0.0;
    for (int step = 1; step <= 50000; step++) { /* 0.5 s, about 4 turns */
        assert_int_equal(dem_sim_step(&s, h, &err), 0);
        double k1[3], k2[3], k3[3], k4[3], t[3];
        euler_rate(I, Iinv, w, k1);
        for (int k = 0; k < 3; k++) t[k] = w[k] + 0.5 * h * k1[k];
        euler_rate(I, Iinv, t, k2);
        for (int k = 0; k < 3; k++) t[k] = w[k] + 0.5 * h * k2[k];
        euler_rate(I, Iinv, t, k3);
        for (int k = 0; k < 3; k++) t[k] = w[k] + h * k3[k];
        euler_rate(I, Iinv, t, k4);
        for (int k = 0; k < 3; k++) w[k] += h / 6.0 * (k1[k] + 2 * k2[k] + 2 * k3[k] + k4[k]);
        if (step % 5000 == 0) {
            double r[9], wb[3];
            dem_quat_to_matrix(B->quat, r);
            for (int a = 0; a < 3; a++) wb[a] = r[a] * B->omega[0] + r[3 + a] * B->omega[1] + r[6 + a] * B->omega[2];
            double dw = sqrt((wb[0] - w[0]) * (wb[0] - w[0]) + (wb[1] - w[1]) * (wb[1] - w[1]) +
                             (wb[2] - w[2]) * (wb[2] - w[2]));
            worst = fmax(worst, dw / sqrt(dot(w, w)));
        }
    }
    double dL = 0.0;
    for (int k = 0; k < 3; k++) dL += (B->angmom[k] - L0[k]) * (B->angmom[k] - L0[k]);
    double e1 = dem_sim_kinetic_energy(&s) - 0.5 * mass * dot(B->vel, B->vel);
    print_message("spin: |ΔL|/|L| = %.2e, rotational energy %.6f -> %.6f J, body-frame ω vs RK4 "
                  "of Euler's equations: %.2e of |ω|\n", sqrt(dL / dot(L0, L0)), e0, e1, worst);
    assert_below(sqrt(dL / dot(L0, L0)), 1e-12); /* no torque: L exactly constant */
    assert_near_rel(e1, e0, 1e-4);                /* first-order quaternion step (3e-6 measured) */
    assert_below(worst, 2e-4);                    /* O(dt) of the quaternion step (2e-5 measured) */
    /* rigid about the given centre: sphere = centre + R (p0 - com) */
    double r[9];
    dem_quat_to_matrix(B->quat, r);
    for (int q = 0; q < 4; q++) {
        double rp[3];
        matvec(r, p0[q], rp);
        for (int k = 0; k < 3; k++) assert_near(s.model.sph.pos[3 * q + k], B->pos[k] + rp[k], 1e-12);
    }
    assert_near(B->pos[0], com[0] + 10.0 * s.time_s, 1e-9);
    dem_sim_free(&s);
}

/* A cluster falls frictionless and undamped (ε = 1, μ = 0) onto a plane and touches it with one
 * sphere whose centre is off the centre of mass by r. The contact force is along the normal n
 * through that sphere's centre, so rigid-body impact theory gives the normal impulse
 * J = 2 m_eff v_n, 1/m_eff = 1/m + (r × n)·I⁻¹(r × n) (the lever moves little during the short
 * contact). Also: the momentum and angular momentum changes equal the impulse and its moment
 * recorded step by step, and ω = I⁻¹ L with the given tensor. */
static void test_impact_impulse(void **state)
{
    (void)state;
    const double d[3] = {80.0, 120.0, 150.0}, axis[3] = {0.0, 0.6, 0.8}, mass = 900.0;
    double I[9], Iinv[9];
    rotated_tensor(d, axis, 0.5, I);
    inverse3(I, Iinv);
    char tj[512], json[4096];
    tensor_json(tj, sizeof tj, I);
    snprintf(json, sizeof json, ROCK
             " \"clusters\": [{\"spheres\": [{\"position\": [0.3, 0, -0.4], \"radius\": 0.1},"
             "   {\"position\": [0, 0, 0], \"radius\": 0.3}, {\"position\": [-0.3, 0.1, 0.1], \"radius\": 0.2}],"
             "   \"mass_kg\": %.17g, \"center_of_mass\": [0, 0, 0], \"inertia_kg_m2\": %s,"
             "   \"velocity\": [0, 0, -3]}],"
             " \"planes\": [{\"point\": [0, 0, -0.52], \"normal\": [0, 0, 1]}],"
             " \"gravity\": [0, 0, 0], \"dt_s\": 1e-6}",
             "1.0", "0.0", mass, tj);
    dem_sim s;
    dem_test_build(&s, json);
    const dem_bodies *B = &s.model.bod;
    double v0[3] = {B->vel[0], B->vel[1], B->vel[2]}, L0[3] = {B->angmom[0], B->angmom[1], B->angmom[2]};
    double ke0 = dem_sim_kinetic_energy(&s);
    double J[3] = {0, 0, 0}, H[3] = {0, 0, 0}, h = 1e-6;
    nc_error err;
    int touched = 0, steps = 0;
    for (; steps < 100000; steps++) {
        assert_int_equal(dem_sim_step_forces(&s, h, &err), 0);
        /* force ON the body = - force on the wall; its moment about the centre of mass */
        double F[3] = {-s.wall_force[0], -s.wall_force[1], -s.wall_force[2]}, lever[3], m[3];
        for (int k = 0; k < 3; k++) lever[k] = s.model.sph.pos[k] - B->pos[k];
        cross(lever, F, m);
        for (int k = 0; k < 3; k++) {
            J[k] += F[k] * h;
            H[k] += m[k] * h;
        }
        if (F[2] > 0) touched = 1;
        else if (touched) break; /* separated */
        dem_sim_step_advance(&s, h);
    }
    dem_sim_step_advance(&s, h);
    assert_true(touched);
    /* the impulse changes the velocity by J / m of the GIVEN mass, L by the moment */
    for (int k = 0; k < 3; k++) {
        assert_near(mass * (B->vel[k] - v0[k]), J[k], 1e-9 * fabs(J[2]));
        assert_near(B->angmom[k] - L0[k], H[k], 1e-9 * sqrt(dot(H, H)));
    }
    double r[9], Lb[3], wb[3], w[3];
    dem_quat_to_matrix(B->quat, r);
    for (int a = 0; a < 3; a++) Lb[a] = r[a] * B->angmom[0] + r[3 + a] * B->angmom[1] + r[6 + a] * B->angmom[2];
    matvec(Iinv, Lb, wb);
    matvec(r, wb, w);
    for (int k = 0; k < 3; k++) assert_near(B->omega[k], w[k], 1e-12 * sqrt(dot(w, w)));
    /* rigid-body impact theory with the given mass and inertia */
    const double n[3] = {0, 0, 1}, lever[3] = {0.3, 0.0, -0.4};
    double rn[3], Irn[3];
    cross(lever, n, rn);
    matvec(Iinv, rn, Irn);
    double meff = 1.0 / (1.0 / mass + dot(rn, Irn));
    double J_ref = 2.0 * meff * 3.0;
    /* what the spheres' sum would give instead (to show the test can tell them apart) */
    double m_sum = 4.0 / 3.0 * M_PI * (0.001 + 0.027 + 0.008) * 2650.0;
    double ke1 = dem_sim_kinetic_energy(&s);
    print_message("impact: J = %.3f N s (2 m_eff v_n = %.3f, m_eff %.2f kg of m %.0f kg; the "
                  "spheres' sum would be %.0f kg), kinetic energy %.2f -> %.2f J, %d steps\n",
                  J[2], J_ref, meff, mass, m_sum, ke0, ke1, steps);
    assert_near_rel(J[2], J_ref, 0.01);              /* lever moves during the contact: 1 % */
    assert_below(fabs(J[0]) + fabs(J[1]), 1e-9 * J[2]); /* frictionless: normal only */
    assert_near_rel(ke1, ke0, 2e-3);                 /* ε = 1: elastic */
    assert_true(fabs(m_sum - mass) > 0.3 * mass);
    dem_sim_free(&s);
}

static void test_mass_only_scales_spheres(void **state)
{
    (void)state;
    /* two equal spheres (R, m) at ±a on x, total mass given as 3 × their sum */
    const char *json =
        "{\"materials\": [{\"name\": \"m\", \"youngs_modulus_pa\": 1e7, \"poisson_ratio\": 0.25,"
        " \"density_kg_m3\": 1000, \"restitution\": 0.5, \"friction\": 0.5}],"
        " \"clusters\": [{\"spheres\": [{\"position\": [0.9, 2, 3], \"radius\": 0.1},"
        "   {\"position\": [1.1, 2, 3], \"radius\": 0.1}], \"mass_kg\": 25.132741228718345,"
        "   \"impact_energy_j\": 100, \"impact_direction\": [0, 0, -1]}]}";
    dem_sim s;
    dem_test_build(&s, json);
    double m = 4.0 / 3.0 * M_PI * 1e-3 * 1000, R = 0.1, a = 0.1, M = 25.132741228718345;
    const double *I = s.model.bod.inertia_body;
    assert_near(s.model.bod.mass[0], M, 1e-12);
    assert_near(s.model.bod.pos[0], 1.0, 1e-12);
    assert_near(I[0], M / (2 * m) * 2 * 0.4 * m * R * R, 1e-12);
    assert_near(I[4], M / (2 * m) * 2 * (0.4 * m * R * R + m * a * a), 1e-12);
    assert_near(s.model.bod.vel[2], -sqrt(2 * 100 / M), 1e-12);
    dem_sim_free(&s);
}

static void test_bad_inputs_refused(void **state)
{
    (void)state;
    static const struct {
        const char *keys, *expect;
    } cases[] = {
        {"\"mass_kg\": -5", "test.json: clusters[0].mass_kg"},
        {"\"center_of_mass\": [0, 0, 0], \"inertia_kg_m2\": [[1,0,0],[0,1,0],[0,0,1]]",
         "test.json: clusters[0].center_of_mass: give mass_kg alone or mass_kg, center_of_mass and inertia_kg_m2 together"},
        {"\"mass_kg\": 100, \"inertia_kg_m2\": [[1,0,0],[0,1,0],[0,0,1]]",
         "test.json: clusters[0].center_of_mass: give mass_kg alone"},
        {"\"mass_kg\": 100, \"center_of_mass\": [0, 0, 0]", "test.json: clusters[0].inertia_kg_m2: give"},
        {"\"mass_kg\": 100, \"center_of_mass\": [0, 0, 0], \"inertia_kg_m2\": [[1,0,0],[0,1,0]]",
         "test.json: clusters[0].inertia_kg_m2: expected a 3x3 array"},
        {"\"mass_kg\": 100, \"center_of_mass\": [0, 0, 0], \"inertia_kg_m2\": [[1,0,0],[0,1,\"x\"],[0,0,1]]",
         "test.json: clusters[0].inertia_kg_m2[1][2]: expected a finite number"},
        {"\"mass_kg\": 100, \"center_of_mass\": [0, 0, 0], \"inertia_kg_m2\": [[1,0.5,0],[0,1,0],[0,0,1]]",
         "test.json: clusters[0].inertia_kg_m2: not symmetric"},
        {"\"mass_kg\": 100, \"center_of_mass\": [0, 0, 0], \"inertia_kg_m2\": [[1,2,0],[2,1,0],[0,0,1]]",
         "test.json: clusters[0].inertia_kg_m2: not positive definite"},
        {"\"mass_kg\": 100, \"center_of_mass\": [0, 0, 0], \"inertia_kg_m2\": [[1,0,0],[0,1,0],[0,0,3]]",
         "test.json: clusters[0].inertia_kg_m2: no body has these principal moments"},
        {"\"mass_kg\": 100, \"center_of_mass\": [0, 0, 5], \"inertia_kg_m2\": [[1,0,0],[0,1,0],[0,0,1]]",
         "test.json: clusters[0].center_of_mass: [0, 0, 5] m lies outside the spheres' bounding box"},
        {"\"mass_kg\": 100, \"center_of_mass\": [0, 0, 0], \"inertia_kg_m2\": [[1,0,0],[0,1e400,0],[0,0,1]]",
         "number out of range"},
    };
    for (size_t c = 0; c < sizeof cases / sizeof *cases; c++) {
        char json[2048];
        snprintf(json, sizeof json,
                 "{\"materials\": [{\"name\": \"m\", \"youngs_modulus_pa\": 1e7, \"poisson_ratio\": 0.25,"
                 " \"density_kg_m3\": 1000, \"restitution\": 0.5, \"friction\": 0.5}],"
                 " \"clusters\": [{\"spheres\": [{\"position\": [-0.1, 0, 0], \"radius\": 0.1},"
                 "   {\"position\": [0.1, 0, 0], \"radius\": 0.1}], %s}]}", cases[c].keys);
        dem_sim s;
        nc_error err;
        int rc = dem_test_try_build(&s, json, &err);
        print_message("%s -> %s\n", cases[c].keys, err.message);
        assert_int_equal(rc, -1);
        assert_non_null(strstr(err.message, cases[c].expect));
        dem_sim_free(&s);
    }
    /* the builder refuses a free sphere and a bad tensor */
    dem_sim s;
    dem_test_build(&s, "{\"materials\": [{\"name\": \"m\", \"youngs_modulus_pa\": 1e7, \"poisson_ratio\": 0.25,"
                       " \"density_kg_m3\": 1000, \"restitution\": 0.5, \"friction\": 0.5}],"
                       " \"particles\": [{\"position\": [0, 0, 0], \"radius\": 0.1}]}");
    nc_error err;
    const double com[3] = {0, 0, 0}, eye[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
    assert_int_equal(dem_sim_set_cluster_mass(&s, 0, 10.0, com, eye, &err), -1);
    assert_non_null(strstr(err.message, "not a cluster"));
    const double nan_tensor[9] = {1, 0, 0, 0, NAN, 0, 0, 0, 1};
    assert_int_equal(dem_inertia_check(nan_tensor, NULL, &err), -1);
    assert_non_null(strstr(err.message, "[1][1] is not a finite number"));
    double l[3];
    const double ok[9] = {2, 0.5, 0, 0.5, 2, 0, 0, 0, 3};
    assert_int_equal(dem_inertia_check(ok, l, &err), 0);
    assert_near(l[0], 1.5, 1e-14);
    assert_near(l[1], 2.5, 1e-14);
    assert_near(l[2], 3.0, 1e-14);
    dem_sim_free(&s);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_torque_free_spin),
        cmocka_unit_test(test_impact_impulse),
        cmocka_unit_test(test_mass_only_scales_spheres),
        cmocka_unit_test(test_bad_inputs_refused),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
