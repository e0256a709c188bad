/* test_compliance — a coupled step solved with the structure's compliance
 * (dem_compliance.h): the granite sphere of test_jacobian (R 0.4 m, 710 kg, 10 m/s) strikes
 * an edge of a steel net whose two nodes yield by S (m/N, a node's own and a coupling
 * term). The returned wall end satisfies u_e = u + S (F - F_ref) with F the force returned,
 * to the solve's tolerance; F and the particle's state are those of an independent plain
 * step to u_e, bit for bit; the yielding net takes less force than the rigid one of the plain
 * step; a contact that begins in the step (none where the search starts, MN at Newton's first
 * step) is solved instead of cycling; no compliance nodes is the plain step; a bad
 * node index, a compliance or force that is not finite, is an error naming it. */
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

#include "dem_compliance.h"
#include "dem_sim.h"
#include "dem_test_util.h"

#define N_NODES 2

/* The granite sphere just above the edge (0,0,0)-(1,0,0) of a steel net, falling at 10 m/s;
 * the step begun, the nodes' end-of-step displacement in disp (4 mm down). */
static void granite_step(dem_sim *s, double *disp)
{
    dem_test_build(s, "{\"contact_law\": \"hertz_mindlin\","
                      " \"materials\": [{\"name\": \"m\", \"youngs_modulus_pa\": 3e10, \"poisson_ratio\": 0.25,"
                      " \"density_kg_m3\": 2650, \"restitution\": 0.2, \"friction\": 0.5}],"
                      " \"particles\": [{\"position\": [0.3, 0.0, 0.4002], \"radius\": 0.4,"
                      " \"velocity\": [0, 0, -10]}],"
                      " \"net_wall\": {\"youngs_modulus_pa\": 1e11, \"poisson_ratio\": 0.3, \"friction\": 0.5},"
                      " \"gravity\": [0, 0, -9.81], \"dt_s\": \"auto\"}");
    const double xyz[3 * N_NODES] = {0, 0, 0, 1, 0, 0};
    const int32_t edges[2] = {0, 1};
    nc_error err;
    assert_int_equal(dem_sim_set_interface(s, N_NODES, NULL, xyz, 1, edges, &err), 0);
    assert_int_equal(dem_sim_begin_step(s, &err), 0);
    for (int n = 0; n < N_NODES; n++) {
        disp[3 * n] = disp[3 * n + 1] = 0.0;
        disp[3 * n + 2] = -4e-3;
    }
}

#define DT 1e-3

/* The begun step of s solved with cmp (dem_sim_solve_with_compliance, its Jacobian
 * discarded): its return value, F, the wall's end and the search's statistics. */
static int solve_with(dem_sim *s, const double *disp, const dem_compliance *cmp, double *F,
                      double *wall, dem_compliance_stats *st, nc_error *err)
{
    dem_net_jacobian jac;
    dem_net_jacobian_init(&jac);
    dem_coupled_info info;
    const int rc = dem_sim_solve_with_compliance(s, DT, disp, NULL, cmp, F, wall, &info, &jac, st,
                                                 err);
    dem_net_jacobian_free(&jac);
    return rc;
}
/* a node's own compliance (m/N) and the coupling between the two (a few centimetres under
 * the rock's 1e5-1e6 N, as a light steel net yields within a coupling step) */
#define S_OWN 4e-8
#define S_PAIR 1e-8

/* The compliance of the two nodes: S_OWN on a node's own directions, S_PAIR between them. */
static void two_node_compliance(double *S)
{
    for (int a = 0; a < 6; a++)
        for (int b = 0; b < 6; b++)
            S[6 * a + b] = a % 3 != b % 3 ? 0.0 : a == b ? S_OWN : S_PAIR;
}

/* cmp solved on the begun step of s from disp within DEM_COMPLIANCE_MAX_EVALUATIONS; F and
 * the particle are those of an independent plain step to the wall's end, bit for bit.
 * Returns the largest nodal force. */
static double solve_and_check(dem_sim *s, const double *disp, const dem_compliance *cmp,
                              double *F, double *wall, dem_compliance_stats *st)
{
    nc_error err;
    assert_int_equal(solve_with(s, disp, cmp, F, wall, st, &err), 0);
    double f_max = 0.0;
    for (int i = 0; i < 3 * N_NODES; i++) f_max = fmax(f_max, fabs(F[i]));
    print_message("compliance: %d evaluations, mismatch %.3g N -> %.3g N, largest nodal force %.4g N, "
                  "node 0 moved %.4g m\n", st->evaluations, st->first_mismatch_n, st->last_mismatch_n,
                  f_max, wall[2] - disp[2]);
    assert_true(st->evaluations > 1 && st->evaluations <= DEM_COMPLIANCE_MAX_EVALUATIONS);
    dem_coupled_info info;
    double vel[3], G[3 * N_NODES];
    memcpy(vel, s->model.sph.vel, sizeof vel);
    assert_int_equal(dem_sim_restore(s, &err), 0);
    assert_int_equal(dem_sim_solve_coupled(s, DT, wall, NULL, G, &info, &err), 0);
    assert_memory_equal(F, G, sizeof G);
    assert_memory_equal(vel, s->model.sph.vel, sizeof vel);
    return f_max;
}

static void test_fixed_point(void **state)
{
    (void)state;
    dem_sim s;
    double disp[3 * N_NODES], F[3 * N_NODES], wall[3 * N_NODES], plain[3 * N_NODES];
    granite_step(&s, disp);
    const int32_t nodes[N_NODES] = {0, 1};
    double S[36], fref[3 * N_NODES] = {0};
    two_node_compliance(S);
    const dem_compliance cmp = {N_NODES, nodes, S, fref};
    dem_compliance_stats st;
    const double f_max = solve_and_check(&s, disp, &cmp, F, wall, &st);
    assert_true(st.evaluations < DEM_COMPLIANCE_MAX_EVALUATIONS);
    assert_below(st.last_mismatch_n, DEM_COMPLIANCE_TOLERANCE * f_max);
    /* u_e = u + S (F - F_ref): the wall ended where the yielding net puts it */
    for (int a = 0; a < 6; a++) {
        double move = 0.0;
        for (int b = 0; b < 6; b++) move += S[6 * a + b] * (F[b] - fref[b]);
        assert_near(wall[a] - disp[a], move, 1e-8 * S_OWN * f_max);
    }
    assert_below(1e-3, disp[2] - wall[2]);   /* pushed down by millimetres at least */
    /* the rigid net (the plain step to u) takes more of the rock */
    nc_error err;
    dem_coupled_info info;
    assert_int_equal(dem_sim_restore(&s, &err), 0);
    assert_int_equal(dem_sim_solve_coupled(&s, DT, disp, NULL, plain, &info, &err), 0);
    print_message("compliance: the net's resultant %.4g N yielding, %.4g N rigid\n",
                  fabs(F[2] + F[5]), fabs(plain[2] + plain[5]));
    assert_below(fabs(F[2] + F[5]), fabs(plain[2] + plain[5]));
    dem_sim_free(&s);
}

/* A contact that begins in the step: where the coupler put the wall (12 mm down, under the
 * force F_ref of 1e5 N per node) the rock does not reach it, and the net freed of that force
 * (S F_ref = 5 mm up) meets it millimetres deep, at MN. Newton from the contact-free start
 * knows no contact stiffness and overshoots into that depth; halving back towards the start
 * alone lands on contact-free points again, whose Newton step returns to the deep one: a
 * cycle that ended 4.1 % of the largest nodal force away from the fixed point. The search
 * brackets the root along the step instead. The step's force is only piecewise smooth in
 * the wall's end (each sub-step a contact gains adds a cusp: along z its rise per 0.02 mm
 * varies 7–19 kN, its K 3.7e8–8.9e8 N/m): the search takes 14 evaluations to
 * DEM_COMPLIANCE_TOLERANCE (with at most 12 it stopped 155 N, 0.27 %, away). */
static void test_contact_onset(void **state)
{
    (void)state;
    dem_sim s;
    double disp[3 * N_NODES], F[3 * N_NODES], wall[3 * N_NODES];
    granite_step(&s, disp);
    disp[2] = disp[5] = -12e-3;
    const int32_t nodes[N_NODES] = {0, 1};
    double S[36], fref[3 * N_NODES] = {0, 0, -1e5, 0, 0, -1e5};
    two_node_compliance(S);
    const dem_compliance cmp = {N_NODES, nodes, S, fref};
    dem_compliance_stats st;
    const double f_max = solve_and_check(&s, disp, &cmp, F, wall, &st);
    /* no contact where the search began, contact where it ended, less than F_ref's push */
    assert_near(st.first_mismatch_n, sqrt(2.0) * 1e5, 1e-6);
    assert_below(F[2], 0.0);
    assert_below(-1e5, F[2]);
    assert_below(st.last_mismatch_n, DEM_COMPLIANCE_TOLERANCE * f_max);
    dem_sim_free(&s);
}

static void test_no_nodes_is_plain(void **state)
{
    (void)state;
    dem_sim s;
    double disp[3 * N_NODES], F[3 * N_NODES], wall[3 * N_NODES], G[3 * N_NODES];
    granite_step(&s, disp);
    double fref[3 * N_NODES] = {0};
    const dem_compliance cmp = {0, NULL, NULL, fref};
    dem_compliance_stats st;
    nc_error err;
    assert_int_equal(solve_with(&s, disp, &cmp, F, wall, &st, &err), 0);
    assert_int_equal(st.evaluations, 1);
    assert_memory_equal(wall, disp, sizeof wall);
    dem_coupled_info info;
    assert_int_equal(dem_sim_restore(&s, &err), 0);
    assert_int_equal(dem_sim_solve_coupled(&s, DT, disp, NULL, G, &info, &err), 0);
    assert_memory_equal(F, G, sizeof F);
    dem_sim_free(&s);
}

static void test_bad_node(void **state)
{
    (void)state;
    dem_sim s;
    double disp[3 * N_NODES], F[3 * N_NODES], wall[3 * N_NODES];
    granite_step(&s, disp);
    const int32_t nodes[1] = {7};
    double S[9] = {S_OWN, 0, 0, 0, S_OWN, 0, 0, 0, S_OWN}, fref[3 * N_NODES] = {0};
    const dem_compliance cmp = {1, nodes, S, fref};
    dem_compliance_stats st;
    nc_error err;
    nc_error_clear(&err);
    assert_int_equal(solve_with(&s, disp, &cmp, F, wall, &st, &err), -1);
    assert_non_null(strstr(err.message, "compliance_nodes row 0: 7 is not an interface node"));
    /* a compliance or force that is not a number */
    const int32_t node0[1] = {0};
    S[4] = NAN;
    const dem_compliance nan_s = {1, node0, S, fref};
    assert_int_equal(solve_with(&s, disp, &nan_s, F, wall, &st, &err), -1);
    assert_non_null(strstr(err.message, "compliance: entry (1, 1) is not finite"));
    S[4] = S_OWN;
    fref[5] = INFINITY;
    const dem_compliance inf_f = {1, node0, S, fref};
    assert_int_equal(solve_with(&s, disp, &inf_f, F, wall, &st, &err), -1);
    assert_non_null(strstr(err.message, "compliance_force: node 1 is not finite"));
    dem_sim_free(&s);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_fixed_point),
        cmocka_unit_test(test_contact_onset),
        cmocka_unit_test(test_no_nodes_is_plain),
        cmocka_unit_test(test_bad_node),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
