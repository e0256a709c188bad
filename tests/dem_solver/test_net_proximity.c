/* test_net_proximity — the nodes a particle in contact may reach in the next step, named by
 * zero Jacobian blocks (dem_net_proximity.h). The granite sphere of test_jacobian (R 0.4 m,
 * 10 m/s) strikes the edge 1-2 of a straight steel rope of 11 nodes at 0.2 m; a second sphere
 * hangs above nodes 8-10 without touching. After a coupled step with the Jacobian:
 *  - the node set named is the one an independent distance computation gives (every node of
 *    an edge within reach + 2 (|v_sphere| + |v_node|) dt of the striking sphere's centre),
 *    with edges on both sides of the limit in the set-up, so that a wrong margin fails;
 *  - the blocks the step computed come first, unchanged bit for bit, and the new ones are
 *    zero diagonal blocks of nodes no block had;
 *  - the sphere without a net contact names nothing (its nodes 8-10 stay out);
 *  - the margin pinned: with the next step's dt_s putting the limit 1 % short of an edge and
 *    1 % beyond it, its far node is named only in the second case;
 *  - with a cap of one node, the one named is the nearest of the full set;
 *  - without any net contact nothing is added. */
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <setjmp.h>
#include <cmocka.h>
#include "../nc_test_assert.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "dem_net_jacobian.h"
#include "dem_net_proximity.h"
#include "dem_sim.h"
#include "dem_test_util.h"

#define N_NODES 11
#define SPACING 0.2
#define DT 1e-3
#define SINK 4e-3   /* every node's end-of-step displacement, down (m) */
#define REACH_M (0.4 + 0.004)   /* the spheres' radius plus the cable's */

/* A coupled step on the rope (rope_begin) and what each test needs of it. */
typedef struct rope {
    dem_sim s;
    dem_net_jacobian jac;
    nc_error err;
    size_t n_step;   /* the blocks the step computed */
} rope;

/* The rope along x at z = 0; the striking sphere at x_strike (over edge 1-2) and z_strike,
 * the idle one over node 9, 16 mm above its reach (6 mm after the step); the coupled step
 * solved with every node sinking by SINK, its Jacobian in jac. */
static void rope_step(dem_sim *s, double x_strike, double z_strike, dem_net_jacobian *jac)
{
    char json[2048];
    snprintf(json, sizeof json,
             "{\"contact_law\": \"hertz_mindlin\","
             " \"materials\": [{\"name\": \"m\", \"youngs_modulus_pa\": 3e10, \"poisson_ratio\": 0.25,"
             " \"density_kg_m3\": 2650, \"restitution\": 0.2, \"friction\": 0.5}],"
             " \"particles\": [{\"position\": [%.17g, 0.0, %.17g], \"radius\": 0.4,"
             " \"velocity\": [0, 0, -10]},"
             " {\"position\": [1.8, 0.0, 0.42], \"radius\": 0.4, \"velocity\": [0, 0, -10]}],"
             " \"net_wall\": {\"youngs_modulus_pa\": 1e11, \"poisson_ratio\": 0.3, \"friction\": 0.5,"
             " \"cable_radius_m\": 0.004},"
             " \"gravity\": [0, 0, -9.81], \"dt_s\": \"auto\"}",
             x_strike, z_strike);
    dem_test_build(s, json);
    double xyz[3 * N_NODES], disp[3 * N_NODES];
    int32_t edges[2 * (N_NODES - 1)];
    for (int n = 0; n < N_NODES; n++) {
        xyz[3 * n] = SPACING * n;
        xyz[3 * n + 1] = xyz[3 * n + 2] = 0.0;
        disp[3 * n] = disp[3 * n + 1] = 0.0;
        disp[3 * n + 2] = -SINK;
    }
    for (int e = 0; e < N_NODES - 1; e++) {
        edges[2 * e] = e;
        edges[2 * e + 1] = e + 1;
    }
    nc_error err;
    assert_int_equal(dem_sim_set_interface(s, N_NODES, NULL, xyz, N_NODES - 1, edges, &err), 0);
    assert_int_equal(dem_sim_begin_step(s, &err), 0);
    dem_net_jacobian_init(jac);
    dem_coupled_info info;
    double F[3 * N_NODES];
    assert_int_equal(dem_sim_solve_coupled_jacobian(s, DT, disp, NULL, F, &info, jac, &err), 0);
}

static void rope_begin(rope *r, double x_strike, double z_strike)
{
    rope_step(&r->s, x_strike, z_strike, &r->jac);
    r->n_step = r->jac.n_blocks;
}

static void rope_end(rope *r)
{
    dem_net_jacobian_free(&r->jac);
    dem_sim_free(&r->s);
}

/* The striking sphere's speed plus the wall's over the step: the margin's relative travel. */
static double relative_speed(const dem_sim *s)
{
    const double *v = s->model.sph.vel;
    return sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]) + SINK / DT;
}

/* Distance from p to the rope's edge e at the step's end (the rope is straight and every node
 * sank by SINK: the edge is x in [0.2 e, 0.2 (e + 1)] at z = -SINK). */
static double edge_distance(const double *p, int e)
{
    const double x = fmin(fmax(p[0], SPACING * e), SPACING * (e + 1));
    return sqrt((p[0] - x) * (p[0] - x) + p[1] * p[1] + (p[2] + SINK) * (p[2] + SINK));
}

/* Distance from p to node i at the step's end. */
static double node_distance(const double *p, int32_t i)
{
    return sqrt((SPACING * i - p[0]) * (SPACING * i - p[0]) + p[1] * p[1] +
                (p[2] + SINK) * (p[2] + SINK));
}

static void test_names_reachable_nodes(void **state)
{
    (void)state;
    rope r;
    rope_begin(&r, 0.3, 0.3998);
    dem_net_jacobian *jac = &r.jac;
    const size_t n_step = r.n_step;
    assert_true(n_step > 0);
    int32_t *nodes_step = malloc(2 * n_step * sizeof *nodes_step);
    double *K_step = malloc(9 * n_step * sizeof *K_step);
    memcpy(nodes_step, jac->nodes, 2 * n_step * sizeof *nodes_step);
    memcpy(K_step, jac->K, 9 * n_step * sizeof *K_step);
    int in_step[N_NODES] = {0};
    for (size_t b = 0; b < 2 * n_step; b++) in_step[nodes_step[b]] = 1;

    size_t added = 0;
    assert_int_equal(
        dem_net_jacobian_add_proximity(&r.s, jac, DT, DEM_PROXIMITY_MAX_NODES, &added, &r.err), 0);

    /* independently: the striking sphere's reach over the next step */
    const double *p = r.s.model.sph.pos;
    const double gap = REACH_M + 2.0 * relative_speed(&r.s) * DT;
    int expect[N_NODES] = {0}, inside = 0, outside = 0;
    for (int e = 0; e < N_NODES - 1; e++) {
        const double d = edge_distance(p, e);
        print_message("edge %d-%d: %.4f m from the sphere's centre (limit %.4f m)\n", e, e + 1, d,
                      gap);
        if (d < gap) {
            expect[e] = expect[e + 1] = 1;
            inside += !(in_step[e] && in_step[e + 1]);
        } else if (d < gap + SPACING) {
            outside++;
        }
    }
    assert_true(inside > 0 && outside > 0);   /* edges on both sides of the limit */
    size_t want = 0;
    for (int n = 0; n < N_NODES; n++) want += expect[n] && !in_step[n];
    assert_int_equal(added, want);
    assert_int_equal(jac->n_blocks, n_step + want);
    /* the step's blocks first and unchanged, then zero (i, i) blocks of new nodes */
    assert_memory_equal(jac->nodes, nodes_step, 2 * n_step * sizeof *nodes_step);
    assert_memory_equal(jac->K, K_step, 9 * n_step * sizeof *K_step);
    int named[N_NODES] = {0};
    for (size_t b = n_step; b < jac->n_blocks; b++) {
        const int32_t i = jac->nodes[2 * b];
        assert_int_equal(jac->nodes[2 * b + 1], i);
        assert_true(i >= 0 && i < N_NODES);
        assert_true(expect[i] && !in_step[i] && !named[i]);
        named[i] = 1;
        for (int k = 0; k < 9; k++) assert_true(jac->K[9 * b + k] == 0.0);
    }
    /* the idle sphere over node 9 (within its own reach-plus-travel) names nothing */
    for (int n = 8; n < N_NODES; n++) assert_false(named[n] || in_step[n]);
    free(nodes_step);
    free(K_step);
    rope_end(&r);
}

/* The margin itself: the next step's dt_s chosen so that the limit reach + 2 (|v_sphere| +
 * |v_node|) dt_s falls 1 % of its distance short of edge 3-4 (0.500 m), then 1 % beyond it;
 * node 4 is named in the second call only. A margin 5 % off its formula fails one of them
 * (the test above has no edge within 86 mm outside its limit). */
static void test_margin(void **state)
{
    (void)state;
    rope r;
    rope_begin(&r, 0.3, 0.3998);
    const double d34 = edge_distance(r.s.model.sph.pos, 3);
    const double shares[2] = {0.99, 1.01};
    for (int k = 0; k < 2; k++) {
        const double dt_next = (shares[k] * d34 - REACH_M) / (2.0 * relative_speed(&r.s));
        r.jac.n_blocks = r.n_step;
        size_t added = 0;
        assert_int_equal(dem_net_jacobian_add_proximity(&r.s, &r.jac, dt_next,
                                                        DEM_PROXIMITY_MAX_NODES, &added, &r.err), 0);
        int node4 = 0;
        for (size_t b = r.n_step; b < r.jac.n_blocks; b++) node4 |= r.jac.nodes[2 * b] == 4;
        print_message("limit %.4f m (edge 3-4 at %.4f m): %zu named, node 4 %s\n", shares[k] * d34,
                      d34, added, node4 ? "among them" : "not");
        assert_int_equal(node4, k == 1);
    }
    rope_end(&r);
}

/* At most max_nodes, the nearest to the sphere's surface first: the sphere 3 mm off the edge's
 * middle towards node 3 names nodes 0 and 3, node 0 first (edge 0-1 comes first); with a cap
 * of one node it is node 3, the nearer (0.4984 against 0.5020 m). */
static void test_nearest_first(void **state)
{
    (void)state;
    rope r;
    rope_begin(&r, 0.303, 0.3998);
    dem_net_jacobian *jac = &r.jac;
    const size_t n_step = r.n_step;
    size_t added = 0;
    assert_int_equal(dem_net_jacobian_add_proximity(&r.s, jac, DT, DEM_PROXIMITY_MAX_NODES, &added,
                                                    &r.err), 0);
    assert_int_equal(added, 2);
    assert_int_equal(jac->nodes[2 * n_step], 0);   /* found first */
    assert_int_equal(jac->nodes[2 * n_step + 2], 3);
    /* the nearest of the nodes the full call named */
    const double *p = r.s.model.sph.pos;
    double best_d = INFINITY;
    for (size_t b = n_step; b < jac->n_blocks; b++) {
        best_d = fmin(best_d, node_distance(p, jac->nodes[2 * b]));
    }
    jac->n_blocks = n_step;   /* the step's own blocks again */
    assert_int_equal(dem_net_jacobian_add_proximity(&r.s, jac, DT, 1, &added, &r.err), 0);
    assert_int_equal(added, 1);
    assert_int_equal(jac->n_blocks, n_step + 1);
    const int32_t i = jac->nodes[2 * n_step];
    assert_int_equal(jac->nodes[2 * n_step + 1], i);
    assert_near(node_distance(p, i), best_d, 1e-9);
    assert_int_equal(i, 3);
    rope_end(&r);
}

static void test_nothing_without_contact(void **state)
{
    (void)state;
    rope r;
    rope_begin(&r, 0.3, 0.45);   /* 5 cm above reach: 1 cm of travel does not close it */
    assert_int_equal(r.n_step, 0);
    size_t added = 1;
    assert_int_equal(dem_net_jacobian_add_proximity(&r.s, &r.jac, DT, DEM_PROXIMITY_MAX_NODES,
                                                    &added, &r.err), 0);
    assert_int_equal(added, 0);
    assert_int_equal(r.jac.n_blocks, 0);
    rope_end(&r);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_names_reachable_nodes),
        cmocka_unit_test(test_margin),
        cmocka_unit_test(test_nearest_first),
        cmocka_unit_test(test_nothing_without_contact),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
