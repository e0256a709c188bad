/* test_energy — the DEM's energy balance of a coupling step (dem_energy.h), the values it
 * reports with each SOLVE reply: a net edge driven up into a falling sphere, then held (COR 1,
 * no friction) does work on it that its kinetic + gravity + contact energy take up (the
 * balance's remainder, the integrator's error, below 1 % of the work); with a contact dashpot
 * (COR 0.3) the accumulated dissipation is positive and a visible share of the work; a net
 * contact sliding without friction (mu = 0) but with a dashpot holds no tangential spring
 * energy (the elastic energy is the Hertz normal energy of the overlap); an oblique impact with
 * friction and the Hunt–Crossley dashpot never holds more energy than it started with (the
 * sliding contact's tangential spring is not raised by its fast-growing Coulomb cap). */
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

/* The terrain's ground impact: a 294 kg rock (R 0.3 m, E 1e8 Pa) landing at 0.6 m/s on a 30°
 * slope (friction 0.6, COR 0.3, Hunt–Crossley). The normal force starts at zero and grows fast
 * (1 + ξ δ̇ about 4 at the first touch), so the contact slides first; a tangential spring
 * raised with the cap, or left at cap − c_t v_t, held energy that no work had put in (here
 * 0.51 J, 1 % of the impact energy; 3.8 J in cases/terrain_net at COR 0.3) and pushed the rock
 * back with it. Kinetic + gravity + contact
 * energy may not exceed the start value by more than the integrator's error, 1e-4 of the
 * kinetic energy at impact, at any step (0.2 s: the impact, then rolling). */
static void test_oblique_hunt_crossley_creates_nothing(void **state)
{
    (void)state;
    const char *json =
        "{\"materials\": [{\"name\": \"rock\", \"youngs_modulus_pa\": 1e8, \"poisson_ratio\": 0.25,"
        " \"density_kg_m3\": 2600, \"restitution\": 0.3, \"friction\": 0.6}],"
        " \"particles\": [{\"position\": [-0.150005, 0, 0.25981896], \"radius\": 0.3, \"velocity\": [0, 0, -0.6]}],"
        " \"planes\": [{\"point\": [0, 0, 0], \"normal\": [-0.5, 0, 0.8660254037844386]}],"
        " \"damping\": \"hunt_crossley\", \"gravity\": [0, 0, -9.81], \"dt_s\": 2e-4}";
    dem_sim s;
    dem_test_build(&s, json);
    nc_error err;
    const double e0 = dem_sim_mechanical_energy(&s), e_impact = dem_sim_kinetic_energy(&s);
    double e_kin_max = 0.0, excess_max = -INFINITY, tangential_seen = 0.0;
    for (int k = 0; k < 1000; k++) {
        assert_int_equal(dem_sim_step(&s, 2e-4, &err), 0);
        e_kin_max = fmax(e_kin_max, dem_sim_kinetic_energy(&s));
        excess_max = fmax(excess_max, dem_sim_mechanical_energy(&s) - e0);
        for (size_t c = 0; c < s.contact.list.n; c++) {
            const double *ft = s.contact.list.ft + 3 * c;
            tangential_seen = fmax(tangential_seen, sqrt(ft[0] * ft[0] + ft[1] * ft[1] + ft[2] * ft[2]));
        }
    }
    print_message("oblique Hunt-Crossley impact: kinetic energy at impact %.3f J (%.3f J rolling "
                  "down at the end), largest energy above the start %.3e J, largest tangential spring "
                  "force %.1f N\n", e_impact, e_kin_max, excess_max, tangential_seen);
    assert_below(100.0, e_kin_max);       /* it rolled down the slope */
    assert_below(100.0, tangential_seen); /* its contact loaded the tangential spring */
    assert_below(excess_max, 1e-4 * e_impact);
    dem_sim_free(&s);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_wall_work_balance),
        cmocka_unit_test(test_dashpot_dissipates),
        cmocka_unit_test(test_frictionless_slide_no_tangential_energy),
        cmocka_unit_test(test_oblique_hunt_crossley_creates_nothing),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
