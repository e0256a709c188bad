/* test_net — the coupled net wall (eqs. (13)–(15), consistent nodal loads): a sphere resting on
 * an edge loads both nodes with the lever rule and in total its weight; a shared vertex is one
 * contact; two crossing ropes are touched once each, with the force continuous over the
 * node; the rebound on an edge returns the requested restitution; a small sphere passes
 * between two edges and a large one does not; nodal forces are impulse-consistent; an edge that
 * sweeps from far away into a sphere within one coupling step is found in the sub-step it
 * reaches it; the free-flight check does not trust a net gap beyond near_distance_m. */
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

static void build_one(dem_sim *s, double x, double y, double z, double r, double vz, double e,
                      const char *law, double gz, double dt)
{
    char json[2048];
    snprintf(json, sizeof json,
             "{\"materials\": [{\"name\": \"m\", \"youngs_modulus_pa\": 1e7, \"poisson_ratio\": 0.2,"
             " \"density_kg_m3\": 2500, \"restitution\": %g, \"friction\": 0.3}],"
             " \"particles\": [{\"position\": [%.17g, %.17g, %.17g], \"radius\": %g, \"velocity\": [0, 0, %g]}],"
             " \"net_wall\": {\"youngs_modulus_pa\": 1e7, \"poisson_ratio\": 0.2, \"friction\": 0.3},"
             " \"contact_law\": \"%s\", \"linear\": {\"normal_stiffness_n_per_m\": 1e6},"
             " \"gravity\": [0, 0, %g], \"dt_s\": %g}",
             e, x, y, z, r, vz, law, gz, dt);
    dem_test_build(s, json);
}

/* The net: one fixed edge from (0,0,0) to (1,0,0), nodes 0 and 1. */
static void set_one_edge(dem_sim *s)
{
    double xyz[6] = {0, 0, 0, 1, 0, 0};
    int32_t edges[2] = {0, 1};
    nc_error err;
    assert_int_equal(dem_sim_set_interface(s, 2, NULL, xyz, 1, edges, &err), 0);
}

/* Runs `steps` coupling steps of dt with the net fixed at its reference; force (3n) of the last. */
static void run_fixed(dem_sim *s, int steps, double dt, double *force, dem_coupled_info *info)
{
    double zero[64 * 3];
    memset(zero, 0, sizeof zero);
    nc_error err;
    for (int k = 0; k < steps; k++) {
        assert_int_equal(dem_sim_begin_step(s, &err), 0);
        if (dem_sim_solve_coupled(s, dt, zero, zero, force, info, &err)) {
            print_error("%s\n", err.message);
            fail();
        }
    }
}

static double weight(const dem_sim *s)
{
    return s->model.bod.mass[0] * 9.81;
}

static void test_rest_on_edge_lever_rule(void **state)
{
    (void)state;
    dem_sim s;
    build_one(&s, 0.3, 0.0, 0.1, 0.1, 0.0, 0.3, "hertz_mindlin", -9.81, 1e-5);
    set_one_edge(&s);
    double f[6];
    dem_coupled_info info;
    run_fixed(&s, 1000, 1e-3, f, &info); /* 1 s: the bounce has died out */
    double W = weight(&s);
    print_message("nodes: %.5f %.5f N (weight %.5f N), contacts %ld, substeps %ld\n", f[2], f[5],
                  W, info.contacts, info.substeps);
    assert_int_equal(info.contacts, 1);
    assert_int_equal(info.substeps, 100);
    assert_int_equal(info.near_interface, 1);
    assert_below(info.min_gap_m, 0.0);
    /* the sum is the weight (0.1 %: residual vibration), the split the lever rule 0.7 / 0.3 */
    assert_near_rel(-(f[2] + f[5]), W, 1e-3);
    assert_near(-f[2], 0.7 * W, 1e-3 * W);
    assert_near(-f[5], 0.3 * W, 1e-3 * W);
    assert_below(fabs(f[0]) + fabs(f[1]) + fabs(f[3]) + fabs(f[4]), 1e-6 * W);
    dem_sim_free(&s);
}

static void test_shared_vertex_counted_once(void **state)
{
    (void)state;
    const double xs[2] = {0.0, 0.01};
    for (int c = 0; c < 2; c++) {
        dem_sim s;
        build_one(&s, xs[c], 0.0, 0.1, 0.1, 0.0, 0.3, "hertz_mindlin", -9.81, 1e-5);
        double xyz[9] = {-1, 0, 0, 0, 0, 0, 1, 0, 0};
        int32_t edges[4] = {0, 1, 1, 2};
        nc_error err;
        assert_int_equal(dem_sim_set_interface(&s, 3, NULL, xyz, 2, edges, &err), 0);
        double f[9];
        dem_coupled_info info;
        run_fixed(&s, 1000, 1e-3, f, &info);
        double W = weight(&s), x = s.model.bod.pos[0];
        print_message("x = %.4f: nodes %.5f %.5f %.5f N (weight %.5f), contacts %ld\n", x, f[2],
                      f[5], f[8], W, info.contacts);
        assert_int_equal(info.contacts, 1); /* one contact, not one per edge */
        assert_near_rel(-(f[2] + f[5] + f[8]), W, 1e-3);
        /* lever rule on the edge holding the contact point (node 1 -> 2 for x > 0) */
        assert_near(-f[5], (1.0 - x) * W, 1e-3 * W);
        assert_near(-f[8], x * W, 1e-3 * W);
        assert_near(f[2], 0.0, 1e-9 * W);
        dem_sim_free(&s);
    }
}

/* The vertical force (N) of one short coupling step on a net of n nodes xyz and m edges, and
 * the number of contacts. The sphere starts at rest, without gravity or damping: it moves by
 * about 1e-11 m in the step, and its force depends on its position alone. */
static double static_press(double x, double y, double z, size_t n, const double *xyz, size_t m,
                           const int32_t *edges, long *contacts)
{
    dem_sim s;
    build_one(&s, x, y, z, 0.1, 0.0, 1.0, "hertz_mindlin", 0.0, 1e-7);
    nc_error err;
    assert_int_equal(dem_sim_set_interface(&s, n, NULL, xyz, m, edges, &err), 0);
    double f[3 * 8], zero[3 * 8] = {0};
    dem_coupled_info info;
    assert_int_equal(dem_sim_begin_step(&s, &err), 0);
    assert_int_equal(dem_sim_solve_coupled(&s, 1e-6, zero, zero, f, &info, &err), 0);
    double fz = 0.0;
    for (size_t k = 0; k < n; k++) fz += f[3 * k + 2];
    *contacts = info.contacts;
    dem_sim_free(&s);
    return fz;
}

/* Two ropes crossing at node 2: a sphere pressing on the crossing touches each rope once,
 * whether its centre is over the node, a hair off one rope line or off both (one node contact
 * per node gave half the force over the node and on the rope lines: a jump of 2 over 1e-9 m);
 * a rope bending at a node is one rope; the force of the crossing is twice one rope's; the end
 * of a rope fastened to another adds no contact of its own. */
static void test_crossing_ropes_each_touched_once(void **state)
{
    (void)state;
    const double z = 0.099; /* 1 mm overlap */
    double cross[15] = {-1, 0, 0, 1, 0, 0, 0, 0, 0, 0, -1, 0, 0, 1, 0};
    int32_t cross_edges[8] = {0, 2, 2, 1, 3, 2, 2, 4};
    long c1, c;
    double one = static_press(0.0, 0.0, z, 5, cross, 2, cross_edges, &c1); /* rope along x */
    assert_int_equal(c1, 1);
    assert_below(one, 0.0);
    const double at[4][2] = {{0, 0}, {1e-9, 0}, {0, 1e-9}, {1e-9, 1e-9}};
    for (int k = 0; k < 4; k++) {
        double both = static_press(at[k][0], at[k][1], z, 5, cross, 4, cross_edges, &c);
        print_message("crossing, centre at (%g, %g): %.9g N in %ld contacts (one rope %.9g N)\n",
                      at[k][0], at[k][1], both, c, one);
        assert_int_equal(c, 2);
        assert_near_rel(both, 2.0 * one, 1e-6);
    }
    /* a rope bending by 90 degrees at node 1, the sphere beyond the bend: one contact, the
     * force of one rope's end at the same distance */
    double bend[9] = {1, 0, 0, 0, 0, 0, 0, 1, 0};
    int32_t bend_edges[4] = {0, 1, 1, 2};
    double d = 0.005, outside = static_press(-d, -d, z, 3, bend, 2, bend_edges, &c);
    double end = static_press(-d, -d, z, 3, bend, 1, bend_edges, &c1);
    assert_int_equal(c, 1);
    assert_int_equal(c1, 1);
    assert_near_rel(outside, end, 1e-12);
    /* a rope (3-1) ending on a border rope (0-1-2) at node 1, the sphere beyond the border:
     * the border rope alone is touched, over its node as beside it */
    double tee[12] = {-1, 0, 0, 0, 0, 0, 1, 0, 0, 0, 1, 0};
    int32_t tee_edges[6] = {0, 1, 1, 2, 3, 1};
    const double beyond[2] = {0.0, 0.003};
    for (int k = 0; k < 2; k++) {
        double with_end = static_press(beyond[k], -d, z, 4, tee, 3, tee_edges, &c);
        double border = static_press(beyond[k], -d, z, 4, tee, 2, tee_edges, &c1);
        assert_int_equal(c, 1);
        assert_int_equal(c1, 1);
        assert_near_rel(with_end, border, 1e-12);
    }
}

static double edge_bounce(const char *law, double e)
{
    dem_sim s;
    build_one(&s, 0.4, 0.0, 0.1005, 0.1, -1.0, e, law, 0.0, 2e-6);
    set_one_edge(&s);
    double f[6];
    dem_coupled_info info;
    int was = 0;
    for (int k = 0; k < 200; k++) {
        run_fixed(&s, 1, 1e-3, f, &info);
        if (info.contacts) was = 1;
        if (was && !info.contacts && s.model.bod.vel[2] > 0) break;
    }
    double v = s.model.bod.vel[2];
    dem_sim_free(&s);
    return v;
}

static void test_rebound_on_edge(void **state)
{
    (void)state;
    const double eps[] = {0.8, 0.5, 0.2};
    for (int k = 0; k < 3; k++) {
        double h = edge_bounce("hertz_mindlin", eps[k]);
        double l = edge_bounce("linear", eps[k]);
        print_message("edge rebound: requested %.2f, hertz+fit %.4f, linear+a7 %.4f\n", eps[k], h, l);
        assert_near_rel(h, eps[k], 0.03); /* 3 % */
        assert_near_rel(l, eps[k], 0.01); /* 1 % */
    }
}

/* Two parallel cables at y = ±0.15 (gap 0.3 m between the lines) */
static double drop_between(double r)
{
    dem_sim s;
    build_one(&s, 0.0, 0.0, 0.3, r, 0.0, 0.3, "hertz_mindlin", -9.81, 1e-5);
    double xyz[18] = {-1, -0.15, 0, 0, -0.15, 0, 1, -0.15, 0, -1, 0.15, 0, 0, 0.15, 0, 1, 0.15, 0};
    int32_t edges[8] = {0, 1, 1, 2, 3, 4, 4, 5};
    nc_error err;
    assert_int_equal(dem_sim_set_interface(&s, 6, NULL, xyz, 4, edges, &err), 0);
    double f[18];
    dem_coupled_info info;
    run_fixed(&s, 800, 1e-3, f, &info);
    double z = s.model.bod.pos[2];
    dem_sim_free(&s);
    return z;
}

static void test_pass_between_edges(void **state)
{
    (void)state;
    double z_small = drop_between(0.1), z_big = drop_between(0.2);
    print_message("after 0.8 s: small sphere z = %.3f m, large sphere z = %.3f m\n", z_small, z_big);
    assert_below(z_small, -1.0); /* fell through freely: 0.3 - ½ g t² ≈ -2.8 m */
    /* caught: rests with its centre sqrt(0.2² - 0.15²) = 0.132 m above the cables */
    assert_near(z_big, sqrt(0.2 * 0.2 - 0.15 * 0.15), 0.005);
}

/* Over one coupling step: m Δv = (m g - Σ nodal forces) Δt, so the returned time-averaged
 * forces carry exactly the impulse the particle received (1e-9 relative). */
static void test_impulse_consistent(void **state)
{
    (void)state;
    dem_sim s;
    build_one(&s, 0.37, 0.0, 0.1005, 0.1, -0.8, 0.5, "hertz_mindlin", -9.81, 1e-5);
    double xyz[9] = {0, 0, 0, 1, 0, 0, 1, 1, 0};
    int32_t edges[4] = {0, 1, 1, 2};
    nc_error err;
    assert_int_equal(dem_sim_set_interface(&s, 3, NULL, xyz, 2, edges, &err), 0);
    double f[9], disp[9] = {0, 0, 0, 0, 0, -0.001, 0, 0, 0}, vel[9] = {0};
    dem_coupled_info info;
    double dt = 2e-3;
    for (int k = 0; k < 5; k++) {
        double v0 = s.model.bod.vel[2];
        assert_int_equal(dem_sim_begin_step(&s, &err), 0);
        disp[5] -= 0.0005; /* the middle node moves down during the steps */
        assert_int_equal(dem_sim_solve_coupled(&s, dt, disp, vel, f, &info, &err), 0);
        double m = s.model.bod.mass[0];
        double lhs = m * (s.model.bod.vel[2] - v0);
        double rhs = (-m * 9.81 - (f[2] + f[5] + f[8])) * dt;
        assert_near(lhs, rhs, 1e-9 * (fabs(lhs) + m * 9.81 * dt));
    }
    dem_sim_free(&s);
}

/* Algorithm 1's larger step: while the sphere is far from the net a coupling step is one exact
 * ballistic step; near it the DEM sub-steps; the trajectory matches the all-sub-stepped run. */
static void test_free_flight_far_from_net(void **state)
{
    (void)state;
    double z_end[2];
    for (int c = 0; c < 2; c++) {
        char json[2048];
        snprintf(json, sizeof json,
                 "{\"materials\": [{\"name\": \"m\", \"youngs_modulus_pa\": 1e7, \"poisson_ratio\": 0.2,"
                 " \"density_kg_m3\": 2500, \"restitution\": 0.5, \"friction\": 0.3}],"
                 " \"particles\": [{\"position\": [0.3, 0, 1.0], \"radius\": 0.1}],"
                 " \"net_wall\": {\"youngs_modulus_pa\": 1e7, \"poisson_ratio\": 0.2, \"friction\": 0.3},"
                 " \"dt_s\": 1e-5, \"free_flight\": %s}", c == 0 ? "true" : "false");
        dem_sim s;
        dem_test_build(&s, json);
        set_one_edge(&s);
        nc_error err;
        double f[6], zero[6] = {0};
        dem_coupled_info info;
        long flights = 0, substepped = 0;
        for (int k = 0; k < 50; k++) { /* 0.5 s of 0.01 s coupling steps: falls 0.9 m, lands */
            assert_int_equal(dem_sim_begin_step(&s, &err), 0);
            assert_int_equal(dem_sim_solve_coupled(&s, 1e-2, zero, zero, f, &info, &err), 0);
            if (info.substeps == 1) flights++;
            else substepped++;
            if (c == 0 && k == 0) { /* exact: z = 1 - ½ g t² */
                assert_near(s.model.bod.pos[2], 1.0 - 0.5 * 9.81 * 1e-4, 1e-12);
                assert_int_equal(info.substeps, 1);
            }
        }
        print_message("free_flight %s: %ld ballistic steps, %ld sub-stepped, z = %.6f m\n",
                      c == 0 ? "on" : "off", flights, substepped, s.model.bod.pos[2]);
        if (c == 0) assert_true(flights > 10 && substepped >= 3); /* the bounce is sub-stepped */
        else assert_int_equal(flights, 0);
        z_end[c] = s.model.bod.pos[2];
        dem_sim_free(&s);
    }
    /* same landing: the sub-stepped symplectic Euler differs from the exact flight by O(dt) */
    assert_near(z_end[0], z_end[1], 1e-3);
}

/* The free-flight check may only trust the net gap within near_distance_m: the grid finds
 * every edge whose clearance is below it, but beyond it the nearest edge may be missing from
 * the sphere's cell while a farther one is there. Here edge A (a long diagonal, clearance
 * 0.34 m) shares the sphere's cell and edge B (6 cm below the sphere falling at 10 m/s) does
 * not: the 0.1 m the sphere travels in the step exceed B's clearance, so the step must be
 * sub-stepped and the sphere must hit B, not fly through it. */
static void test_free_flight_gap_beyond_near_distance(void **state)
{
    (void)state;
    const double pz = -0.02, r = 0.1;
    char json[2048];
    snprintf(json, sizeof json,
             "{\"materials\": [{\"name\": \"m\", \"youngs_modulus_pa\": 1e7, \"poisson_ratio\": 0.2,"
             " \"density_kg_m3\": 2500, \"restitution\": 0.5, \"friction\": 0.3}],"
             " \"particles\": [{\"position\": [0, 0, %g], \"radius\": %g, \"velocity\": [0, 0, -10]}],"
             " \"net_wall\": {\"youngs_modulus_pa\": 1e7, \"poisson_ratio\": 0.2, \"friction\": 0.3,"
             " \"near_distance_m\": 0.01, \"cable_radius_m\": 0},"
             " \"gravity\": [0, 0, 0], \"dt_s\": 1e-5, \"free_flight\": true}", pz, r);
    dem_sim s;
    dem_test_build(&s, json);
    /* A: (-0.4, 0, 1) - (1.6, 0, -1); B: (-0.05, 0, pz - 0.16) - (0.05, 0, pz - 0.16); and 100
     * short edges far away, which make the grid's cells small (dem_neighbor_grid.c) */
    enum { FILL = 100, NODES = 4 + 2 * FILL, EDGES = 2 + FILL };
    static double xyz[3 * NODES];
    static int32_t edges[2 * EDGES];
    const double a_b[12] = {-0.4, 0, 1.0, 1.6, 0, -1.0, -0.05, 0, pz - 0.16, 0.05, 0, pz - 0.16};
    memcpy(xyz, a_b, sizeof a_b);
    for (int k = 0; k < FILL; k++) {
        double *q = xyz + 3 * (4 + 2 * k);
        q[0] = 10.0 + 0.3 * k, q[1] = 0, q[2] = 0;
        q[3] = q[0] + 0.01, q[4] = 0, q[5] = 0;
    }
    for (int e = 0; e < EDGES; e++) edges[2 * e] = 2 * e, edges[2 * e + 1] = 2 * e + 1;
    nc_error err;
    assert_int_equal(dem_sim_set_interface(&s, NODES, NULL, xyz, EDGES, edges, &err), 0);
    /* the set-up this test needs: the sphere's cell holds A but not B */
    const int32_t *items;
    size_t count = dem_item_grid_query(s.model.net.grid, s.model.sph.pos, &items);
    int has_a = 0, has_b = 0;
    for (size_t c = 0; c < count; c++) has_a |= items[c] == 0, has_b |= items[c] == 1;
    assert_true(has_a && !has_b);

    static double force[3 * NODES], zero[3 * NODES];
    dem_coupled_info info;
    assert_int_equal(dem_sim_begin_step(&s, &err), 0);
    assert_int_equal(dem_sim_solve_coupled(&s, 1e-2, zero, zero, force, &info, &err), 0);
    double fb = force[3 * 2 + 2] + force[3 * 3 + 2];
    print_message("sub-steps %ld, sphere z %.4f m, vz %.3f m/s, force on B %.3e N\n",
                  info.substeps, s.model.bod.pos[2], s.model.bod.vel[2], fb);
    assert_true(info.substeps > 1);
    assert_true(fb < 0.0);                       /* the sphere pushed B down */
    assert_true(s.model.bod.vel[2] > -10.0);     /* and was slowed by it */
    dem_sim_free(&s);
}

/* Bad interface data and commands in the wrong order are errors naming the problem. */
static void test_interface_errors(void **state)
{
    (void)state;
    dem_sim s;
    build_one(&s, 0.3, 0.0, 0.5, 0.1, 0.0, 0.3, "hertz_mindlin", -9.81, 1e-5);
    nc_error err;
    double f[6], zero[6] = {0};
    dem_coupled_info info;
    assert_int_equal(dem_sim_solve_coupled(&s, 1e-3, zero, zero, f, &info, &err), -1);
    assert_non_null(strstr(err.message, "interface"));
    assert_int_equal(dem_sim_restore(&s, &err), -1);
    assert_non_null(strstr(err.message, "restore"));
    double xyz[6] = {0, 0, 0, 1, 0, 0};
    int32_t out_of_range[2] = {0, 2}, self[2] = {1, 1}, ok[2] = {0, 1};
    assert_int_equal(dem_sim_set_interface(&s, 2, NULL, xyz, 1, out_of_range, &err), -1);
    assert_non_null(strstr(err.message, "elements[0]"));
    assert_int_equal(dem_sim_set_interface(&s, 2, NULL, xyz, 1, self, &err), -1);
    assert_non_null(strstr(err.message, "itself"));
    xyz[4] = NAN;
    assert_int_equal(dem_sim_set_interface(&s, 2, NULL, xyz, 1, ok, &err), -1);
    assert_non_null(strstr(err.message, "coordinates[1]"));
    xyz[4] = 0.0;
    assert_int_equal(dem_sim_set_interface(&s, 2, NULL, xyz, 1, ok, &err), 0);
    assert_int_equal(dem_sim_solve_coupled(&s, 0.0, zero, zero, f, &info, &err), -1);
    assert_non_null(strstr(err.message, "dt_s"));
    double bad[6] = {0, 0, INFINITY, 0, 0, 0};
    assert_int_equal(dem_sim_solve_coupled(&s, 1e-3, bad, zero, f, &info, &err), -1);
    assert_non_null(strstr(err.message, "node 0"));
    dem_sim_free(&s);

    /* the coupled wall needs its material */
    const char *json =
        "{\"materials\": [{\"name\": \"m\", \"youngs_modulus_pa\": 1e7, \"poisson_ratio\": 0.2,"
        " \"density_kg_m3\": 2500, \"restitution\": 0.5, \"friction\": 0.3}]}";
    dem_test_build(&s, json);
    assert_int_equal(dem_sim_set_interface(&s, 2, NULL, xyz, 1, ok, &err), -1);
    assert_non_null(strstr(err.message, "net_wall"));
    dem_sim_free(&s);
}

/* A cable has no inside: when the net moves so fast that the line would cross the centre of a
 * sphere lying on it within one coupling step, the ongoing contact keeps its side and throws
 * the sphere up instead of letting it through. */
static void test_net_does_not_pass_through_resting_sphere(void **state)
{
    (void)state;
    dem_sim s;
    build_one(&s, 0.3, 0.0, 0.1, 0.1, 0.0, 0.3, "hertz_mindlin", -9.81, 1e-5);
    set_one_edge(&s);
    nc_error err;
    double f[6], disp[6] = {0}, vel[6] = {0};
    dem_coupled_info info;
    run_fixed(&s, 300, 1e-3, f, &info); /* resting */
    assert_int_equal(dem_sim_begin_step(&s, &err), 0);
    /* the cable jumps 0.15 m up (more than R = 0.1) in 1 ms: far too fast for the contact to
     * accelerate the sphere, so the line reaches past the centre during the sub-steps */
    disp[2] = disp[5] = 0.15;
    assert_int_equal(dem_sim_solve_coupled(&s, 1e-3, disp, vel, f, &info, &err), 0);
    for (int k = 0; k < 100; k++) {
        assert_int_equal(dem_sim_begin_step(&s, &err), 0);
        assert_int_equal(dem_sim_solve_coupled(&s, 1e-3, disp, vel, f, &info, &err), 0);
    }
    print_message("sphere centre z = %.4f m, cable at z = 0.15 m, vz = %.3f m/s\n", s.model.bod.pos[2], s.model.bod.vel[2]);
    assert_true(s.model.bod.pos[2] > 0.15); /* still on top of the cable */
    dem_sim_free(&s);
}

/* The contact search of a coupling step uses one grid of the edges' boxes over the whole step
 * (dem_coupling.c): an edge that starts 1.95 m below a sphere, far beyond any search distance,
 * and ends 5 cm into it must still be found in the last sub-steps. The same motion as 100
 * coupling steps of one sub-step each is the reference: same sub-step positions, total
 * impulse equal within 1e-9 relative. */
static void test_edge_sweeping_into_sphere(void **state)
{
    (void)state;
    dem_sim big, small;
    build_one(&big, 0.5, 0.0, 2.0, 0.1, 0.0, 0.3, "hertz_mindlin", 0.0, 1e-5);
    build_one(&small, 0.5, 0.0, 2.0, 0.1, 0.0, 0.3, "hertz_mindlin", 0.0, 1e-5);
    set_one_edge(&big);
    set_one_edge(&small);
    nc_error err;
    double f[6], disp[6] = {0}, vel[6] = {0}, impulse_small = 0.0;
    dem_coupled_info info;
    const double rise_m = 1.95, dt = 1e-3;
    const int n = 100;
    vel[2] = vel[5] = rise_m / dt;
    for (int k = 1; k <= n; k++) {
        disp[2] = disp[5] = rise_m * k / n;
        assert_int_equal(dem_sim_begin_step(&small, &err), 0);
        assert_int_equal(dem_sim_solve_coupled(&small, dt / n, disp, vel, f, &info, &err), 0);
        impulse_small += (f[2] + f[5]) * dt / n;
    }
    assert_int_equal(dem_sim_begin_step(&big, &err), 0);
    assert_int_equal(dem_sim_solve_coupled(&big, dt, disp, vel, f, &info, &err), 0);
    double impulse_big = (f[2] + f[5]) * dt;
    print_message("impulse on the edge: one step %.9e N s, 100 steps %.9e N s; sphere vz %.4f m/s\n",
                  impulse_big, impulse_small, big.model.bod.vel[2]);
    assert_true(impulse_big < 0.0);              /* the sphere pushes the edge back down */
    assert_true(big.model.bod.vel[2] > 0.0);     /* and is pushed up */
    assert_near_rel(impulse_big, impulse_small, 1e-9);
    dem_sim_free(&big);
    dem_sim_free(&small);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_rest_on_edge_lever_rule),
        cmocka_unit_test(test_shared_vertex_counted_once),
        cmocka_unit_test(test_crossing_ropes_each_touched_once),
        cmocka_unit_test(test_rebound_on_edge),
        cmocka_unit_test(test_pass_between_edges),
        cmocka_unit_test(test_impulse_consistent),
        cmocka_unit_test(test_free_flight_far_from_net),
        cmocka_unit_test(test_free_flight_gap_beyond_near_distance),
        cmocka_unit_test(test_interface_errors),
        cmocka_unit_test(test_net_does_not_pass_through_resting_sphere),
        cmocka_unit_test(test_edge_sweeping_into_sphere),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
