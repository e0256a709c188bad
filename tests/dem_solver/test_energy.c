/* test_energy — the DEM's energy balance of a coupling step (dem_energy.h), the values it
 * reports with each SOLVE reply: a net edge driven up into a falling sphere, then held (COR 1,
 * no friction) does work on it that its kinetic + gravity + contact energy take up (the
 * balance's remainder, the integrator's error, below 1 % of the work); with a contact dashpot
 * (COR 0.3) the accumulated dissipation is positive and a visible share of the work; a net
 * contact sliding without friction (mu = 0) but with a dashpot holds no tangential spring
 * energy (the elastic energy is the Hertz normal energy of the overlap). */
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
#include "../../dem_solver/dem_energy.h"

/* One sphere R 0.1 m (E 1e7, nu 0.2, rho 2500) at (0.3, 0, z) with velocity (vx, 0, vz)
 * above a one-edge net along x (same material, friction 0), gravity -9.81 z. */
static void build(dem_sim *s, double z, double vx, double vz, double cor)
{
    char json[2048];
    snprintf(json, sizeof json,
             "{\"materials\": [{\"name\": \"m\", \"youngs_modulus_pa\": 1e7, \"poisson_ratio\": 0.2,"
             " \"density_kg_m3\": 2500, \"restitution\": %g, \"friction\": 0.0}],"
             " \"particles\": [{\"position\": [0.3, 0, %.17g], \"radius\": 0.1, \"velocity\": [%g, 0, %g]}],"
             " \"net_wall\": {\"youngs_modulus_pa\": 1e7, \"poisson_ratio\": 0.2, \"friction\": 0.0,"
             " \"restitution\": %g},"
             " \"gravity\": [0, 0, -9.81], \"dt_s\": 1e-4}",
             cor, z, vx, vz, cor);
    dem_test_build(s, json);
    double xyz[6] = {-1, 0, 0, 2, 0, 0};
    int32_t edges[2] = {0, 1};
    nc_error err;
    assert_int_equal(dem_sim_set_interface(s, 2, NULL, xyz, 1, edges, &err), 0);
}

typedef struct sums {
    double work_j, dissipated_j, e0_j, e1_j, max_contact_j;
} sums;

/* 120 coupling steps of 2.5 ms (25 sub-steps each): the edge rises at 1 m/s for the first 75
 * steps (it meets the sphere falling from 0.2 m above at about 0.165 s, step 66), then
 * stays. */
static void drive(dem_sim *s, sums *out)
{
    nc_error err;
    double disp[6] = {0}, vel[6] = {0}, f[6];
    const double dt = 2.5e-3;
    memset(out, 0, sizeof *out);
    out->e0_j = dem_sim_mechanical_energy(s);
    for (int k = 0; k < 120; k++) {
        double vz = k < 75 ? 1.0 : 0.0;
        disp[2] += vz * dt;
        disp[5] += vz * dt;
        vel[2] = vel[5] = vz;
        assert_int_equal(dem_sim_begin_step(s, &err), 0);
        double e_start = dem_sim_mechanical_energy(s);
        dem_coupled_info info;
        assert_int_equal(dem_sim_solve_coupled(s, dt, disp, vel, f, &info, &err), 0);
        dem_step_energy e;
        dem_sim_step_energy(s, dt, e_start, &e);
        /* the work is minus the averaged force on the net times the wall's displacement */
        assert_near(e.wall_work_j, -(f[2] + f[5]) * vz * dt, 1e-12 + 1e-9 * fabs(e.wall_work_j));
        out->work_j += e.wall_work_j;
        out->dissipated_j += e.dissipated_j;
        out->max_contact_j = fmax(out->max_contact_j, e.contact_j);
        assert_near(e.kinetic_j + e.gravity_j + e.contact_j, dem_sim_mechanical_energy(s), 1e-12);
    }
    out->e1_j = dem_sim_mechanical_energy(s);
}

static void test_wall_work_balance(void **state)
{
    (void)state;
    dem_sim s;
    build(&s, 0.1 + 0.2, 0.0, 0.0, 1.0);   /* 0.2 m above the edge, at rest */
    sums r;
    drive(&s, &r);
    print_message("COR 1: wall work %.6f J, energy change %.6f J, dissipated %.3e J, largest "
                  "contact energy %.4f J\n", r.work_j, r.e1_j - r.e0_j, r.dissipated_j,
                  r.max_contact_j);
    assert_below(1.0, r.work_j);                             /* the edge hit and pushed it */
    assert_below(0.0, r.max_contact_j);
    assert_near(r.e1_j - r.e0_j + r.dissipated_j, r.work_j, 1e-9 * r.work_j);
    assert_below(fabs(r.dissipated_j), 0.01 * r.work_j);
    dem_sim_free(&s);
}

static void test_dashpot_dissipates(void **state)
{
    (void)state;
    dem_sim s;
    build(&s, 0.1 + 0.2, 0.0, 0.0, 0.3);
    sums r;
    drive(&s, &r);
    print_message("COR 0.3: wall work %.6f J, energy change %.6f J, dissipated %.4f J\n", r.work_j,
                  r.e1_j - r.e0_j, r.dissipated_j);
    assert_below(0.05 * r.work_j, r.dissipated_j);
    dem_sim_free(&s);
}

/* A sphere sliding along the edge (vx 3 m/s) while pressed onto it, mu = 0, COR 0.3: the
 * contact's elastic energy is its Hertz normal energy 8/15 E* sqrt(R) d^2.5, no more. */
static void test_frictionless_slide_no_tangential_energy(void **state)
{
    (void)state;
    dem_sim s;
    build(&s, 0.099, 3.0, -0.5, 0.3);
    nc_error err;
    double disp[6] = {0}, vel[6] = {0}, f[6];
    dem_coupled_info info;
    assert_int_equal(dem_sim_begin_step(&s, &err), 0);
    assert_int_equal(dem_sim_solve_coupled(&s, 1e-3, disp, vel, f, &info, &err), 0);
    assert_int_equal(s.contact.list.n, 1);
    double d = s.contact.list.overlap[0];
    double e_star = 1.0 / (2.0 * (1.0 - 0.04) / 1e7);
    double hertz = 8.0 / 15.0 * e_star * sqrt(0.1) * pow(d, 2.5);
    print_message("overlap %.3e m: contact energy %.6e J, Hertz normal %.6e J\n", d,
                  dem_sim_contact_energy(&s), hertz);
    assert_below(0.0, d);
    assert_near_rel(dem_sim_contact_energy(&s), hertz, 1e-12);
    dem_sim_free(&s);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_wall_work_balance),
        cmocka_unit_test(test_dashpot_dissipates),
        cmocka_unit_test(test_frictionless_slide_no_tangential_energy),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
