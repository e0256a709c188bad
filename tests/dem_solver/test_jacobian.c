/* test_jacobian — the interface Jacobian of a coupled step (dem_net_jacobian.h): K against
 * central finite differences of the DEM's own returned force, relative agreement 1e-6 of the
 * largest entry, with the particles treated as K treats them: dem_net_jacobian_replay()
 * replays the recorded sub-steps with the particles frozen (DEM_JAC_FROZEN) or responding
 * through their net contacts (DEM_JAC_RESPOND_LOCAL / _RESPOND). Cases: an edge-interior
 * contact (both nodes, off-diagonal blocks), a vertex contact, a sliding contact (Coulomb
 * cap, checked on the returned force), a contact that closes within the step, one whose
 * force drops to the no-tension clamp (Hertz) within the step, a Hunt–Crossley contact that
 * begins in the step and then slows (its impact speed held), Hertz and linear laws, a
 * spinning sphere with history from the previous step, a sphere on two edges, a sphere on two
 * ropes through one node whose two node contacts have different histories; every case has
 * 10 or more sub-steps. The replay at the received displacement reproduces the returned
 * force. With the option off the results are unchanged (memcmp against a run with it on).
 * A cluster on the edge checks the rigid body's response (translation and turn) against the
 * replay, also away from the solve's displacement. The granite sphere on the steel net, and
 * the same rock as a spinning cluster, measure the frozen K against a finite difference of the real step and check the
 * responding K against it. */
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

#include "dem_contact_list.h"
#include "dem_net_jacobian.h"
#include "dem_test_util.h"

typedef struct scenario {
    const char *law;        /* "hertz_mindlin" or "linear" */
    double radius, density, youngs, restitution, friction;
    double net_youngs, net_friction;
    double pos[3], vel[3], omega[3];
    double dt_dem, dt_step;
    const char *net_extra;  /* extra net_wall keys (", \"coupling_force\": ...") */
    int n_nodes;            /* 2: edge (0,0,0)-(1,0,0); 3: plus (2,0,0) */
    double node_motion[3];  /* end-of-step displacement of every node in the tested step */
    int warmup;             /* coupled steps before the tested one (history) */
    int bent;               /* 3 nodes: node 2 at (0, 0.02, 0), the line folds back */
    const char *damping;    /* dem.json "damping" (NULL: the law's default) */
    int cluster;            /* the particle is a cluster: the sphere above plus one of 0.8 its
                               radius at (0.6, 0.3, 0.9) radii from it, off the contact */
    int crossing;           /* 5 nodes: two ropes bent at node 1, 0-1-2 with its apex towards
                               +y and 3-1-4 beside it, its apex towards +y too */
} scenario;

#define NDOF 15 /* 3 per node, 5 nodes at most */

static void build(dem_sim *s, const scenario *c)
{
    char json[4096], dt[64], damping[64] = "";
    if (c->damping) snprintf(damping, sizeof damping, " \"damping\": \"%s\",", c->damping);
    if (c->dt_dem > 0.0)
        snprintf(dt, sizeof dt, "%.17g", c->dt_dem);
    else
        snprintf(dt, sizeof dt, "\"auto\"");
    char body[1024];
    if (c->cluster)
        snprintf(body, sizeof body,
                 "\"clusters\": [{\"material\": \"m\", \"velocity\": [%.17g, %.17g, %.17g],"
                 " \"angular_velocity\": [%.17g, %.17g, %.17g], \"spheres\": ["
                 "{\"position\": [%.17g, %.17g, %.17g], \"radius\": %.17g},"
                 " {\"position\": [%.17g, %.17g, %.17g], \"radius\": %.17g}]}]",
                 c->vel[0], c->vel[1], c->vel[2], c->omega[0], c->omega[1], c->omega[2], c->pos[0],
                 c->pos[1], c->pos[2], c->radius, c->pos[0] + 0.6 * c->radius,
                 c->pos[1] + 0.3 * c->radius, c->pos[2] + 0.9 * c->radius, 0.8 * c->radius);
    else
        snprintf(body, sizeof body,
                 "\"particles\": [{\"position\": [%.17g, %.17g, %.17g], \"radius\": %.17g,"
                 " \"velocity\": [%.17g, %.17g, %.17g], \"angular_velocity\": [%.17g, %.17g, %.17g]}]",
                 c->pos[0], c->pos[1], c->pos[2], c->radius, c->vel[0], c->vel[1], c->vel[2],
                 c->omega[0], c->omega[1], c->omega[2]);
    snprintf(json, sizeof json,
             "{\"contact_law\": \"%s\",%s \"linear\": {\"normal_stiffness_n_per_m\": 2e6},"
             " \"materials\": [{\"name\": \"m\", \"youngs_modulus_pa\": %.17g, \"poisson_ratio\": 0.25,"
             " \"density_kg_m3\": %.17g, \"restitution\": %.17g, \"friction\": %.17g}], %s,"
             " \"net_wall\": {\"youngs_modulus_pa\": %.17g, \"poisson_ratio\": 0.3, \"friction\": %.17g%s},"
             " \"gravity\": [0, 0, -9.81], \"dt_s\": %s}",
             c->law, damping, c->youngs, c->density, c->restitution, c->friction, body,
             c->net_youngs, c->net_friction, c->net_extra ? c->net_extra : "", dt);
    dem_test_build(s, json);
    double xyz[NDOF] = {0, 0, 0, 1, 0, 0, 2, 0, 0};
    if (c->bent) {
        xyz[6] = 0.0;
        xyz[7] = 0.02;
    }
    int32_t edges[8] = {0, 1, 1, 2, 3, 1, 1, 4};
    size_t n_edges = (size_t)c->n_nodes - 1;
    if (c->crossing) {
        const double cross[NDOF] = {0, -0.3, 0, 1, 0, 0, 2, -0.3, 0, 1.3, -1, 0, 0.7, -1, 0};
        memcpy(xyz, cross, sizeof xyz);
        n_edges = 4;
    }
    nc_error err;
    assert_int_equal(dem_sim_set_interface(s, (size_t)c->n_nodes, NULL, xyz, n_edges, edges, &err),
                     0);
}

/* Runs the warm-up steps (net at rest) and begins the tested step. */
static void warm_up(dem_sim *s, const scenario *c, double *disp)
{
    nc_error err;
    double force[NDOF];
    dem_coupled_info info;
    memset(disp, 0, 3 * (size_t)c->n_nodes * sizeof *disp);
    for (int k = 0; k < c->warmup; k++) {
        assert_int_equal(dem_sim_begin_step(s, &err), 0);
        assert_int_equal(dem_sim_solve_coupled(s, c->dt_step, disp, NULL, force, &info, &err), 0);
    }
    assert_int_equal(dem_sim_begin_step(s, &err), 0);
    for (int n = 0; n < c->n_nodes; n++)
        for (int k = 0; k < 3; k++) disp[3 * n + k] = c->node_motion[k] * (1.0 + 0.3 * n);
}

/* Dense K (3n x 3n) from the blocks; checks the pattern (one node or one edge's nodes). */
static int any_pair; /* the blocks may join nodes of different edges (DEM_JAC_RESPOND) */

static void dense(const dem_net_jacobian *jac, int n, double *K)
{
    memset(K, 0, (size_t)(9 * n * n) * sizeof *K);
    for (size_t b = 0; b < jac->n_blocks; b++) {
        int i = jac->nodes[2 * b], j = jac->nodes[2 * b + 1];
        assert_true(i >= 0 && i < n && j >= 0 && j < n);
        if (!any_pair) assert_true(abs(i - j) <= 1); /* the nodes of one edge of the line */
        for (size_t e = 0; e < b; e++) /* each (i, j) once */
            assert_false(jac->nodes[2 * e] == i && jac->nodes[2 * e + 1] == j);
        for (int r = 0; r < 3; r++)
            for (int c = 0; c < 3; c++) K[(3 * i + r) * 3 * n + 3 * j + c] += jac->K[9 * b + 3 * r + c];
    }
}

static double max_abs(const double *a, size_t n)
{
    double m = 0.0;
    for (size_t k = 0; k < n; k++) m = fmax(m, fabs(a[k]));
    return m;
}

/* Builds scenario c, runs its warm-up and solves the tested step with the Jacobian (particle
 * response `response`): s, jac, disp (the step's end displacement), force and info. */
static void solve_tested_step(dem_sim *s, const scenario *c, int response, dem_net_jacobian *jac,
                              double *disp, double *force, dem_coupled_info *info)
{
    build(s, c);
    warm_up(s, c, disp);
    dem_net_jacobian_init(jac);
    jac->particle_response = response;
    nc_error err;
    assert_int_equal(dem_sim_solve_coupled_jacobian(s, c->dt_step, disp, NULL, force, info, jac, &err), 0);
}

/* -dF/du of the replay at disp by central differences (step eps, m), nd x nd into fd. */
static void replay_differences(const dem_sim *s, dem_net_jacobian *jac, const double *disp,
                               int nd, double eps, double *fd)
{
    nc_error err;
    for (int col = 0; col < nd; col++) {
        double dp[NDOF], fp[NDOF], fm[NDOF];
        memcpy(dp, disp, (size_t)nd * sizeof *dp);
        dp[col] = disp[col] + eps;
        assert_int_equal(dem_net_jacobian_replay(s, jac, dp, fp, 0, &err), 0);
        dp[col] = disp[col] - eps;
        assert_int_equal(dem_net_jacobian_replay(s, jac, dp, fm, 0, &err), 0);
        for (int row = 0; row < nd; row++) fd[row * nd + col] = -(fp[row] - fm[row]) / (2.0 * eps);
    }
}

/* Solves the tested step with the Jacobian (particles frozen, or responding), checks the
 * replay against the returned force and K against central differences of the replay (step
 * eps, m). K_out (3n x 3n) receives K if not NULL. */
static void check_mode(const scenario *c, int response, double eps, double *K_out, int *n_contacts)
{
    dem_sim s;
    double disp[NDOF], force[NDOF], replayed[NDOF];
    dem_net_jacobian jac;
    dem_coupled_info info;
    nc_error err;
    solve_tested_step(&s, c, response, &jac, disp, force, &info);
    assert_true(info.substeps >= 10);
    if (n_contacts) *n_contacts = (int)jac.n_rec;
    int n = c->n_nodes, nd = 3 * n;
    double fscale = max_abs(force, (size_t)nd);
    assert_true(fscale > 0.0);
    assert_int_equal(dem_net_jacobian_replay(&s, &jac, disp, replayed, 0, &err), 0);
    for (int k = 0; k < nd; k++) assert_near(replayed[k], force[k], 1e-12 * fscale);
    double K[NDOF * NDOF], fd[NDOF * NDOF];
    dense(&jac, n, K);
    replay_differences(&s, &jac, disp, nd, eps, fd);
    double kmax = max_abs(K, (size_t)(nd * nd));
    assert_true(kmax > 0.0);
    if (getenv("JAC_DEBUG"))
        for (int e = 0; e < nd * nd; e++)
            print_message("K[%d][%d] %.10g fd %.10g\n", e / nd, e % nd, K[e], fd[e]);
    for (int e = 0; e < nd * nd; e++) assert_near(K[e], fd[e], 1e-6 * kmax);
    if (K_out) memcpy(K_out, K, (size_t)(nd * nd) * sizeof *K);
    dem_net_jacobian_free(&jac);
    dem_sim_free(&s);
}

/* Both linearisations; K_out: the frozen one. */
static void check_case(const scenario *c, double eps, double *K_out, int *n_contacts)
{
    check_mode(c, DEM_JAC_FROZEN, eps, K_out, n_contacts);
    check_mode(c, DEM_JAC_RESPOND_LOCAL, eps, NULL, NULL);
}

/* A small soft sphere (R 0.1 m) pressing into the edge at t = 0.3 while the net moves too. */
static scenario base_case(void)
{
    scenario c = {"hertz_mindlin", 0.1, 2500.0, 1e7, 0.5, 0.4, 1e7, 0.4, {0.3, 0.004, 0.0995},
                  {0.2, 0.0, -0.5}, {0, 0, 0}, 1e-4, 1e-3, "", 2, {0.0, 0.0, -2e-4}, 0, 0, NULL, 0, 0};
    return c;
}

static void test_edge_interior_hertz(void **state)
{
    (void)state;
    scenario c = base_case();
    double K[36];
    check_case(&c, 1e-8, K, NULL);
    /* both nodes coupled: the off-diagonal blocks are not zero */
    assert_true(fabs(K[2 * 6 + 5]) > 1e-3 * fabs(K[2 * 6 + 2]));
    assert_true(fabs(K[5 * 6 + 2]) > 1e-3 * fabs(K[2 * 6 + 2]));
}

static void test_edge_interior_linear(void **state)
{
    (void)state;
    scenario c = base_case();
    c.law = "linear";
    check_case(&c, 1e-8, NULL, NULL);
}

/* The Hunt–Crossley dashpot on a contact that began in the warm-up step (its impact speed is
 * history, constant in the tested step while the approach slows). */
static void test_hunt_crossley_with_history(void **state)
{
    (void)state;
    scenario c = base_case();
    c.damping = "hunt_crossley";
    c.pos[2] = 0.1002; /* touches in the middle of the warm-up step */
    c.warmup = 1;
    check_case(&c, 1e-8, NULL, NULL);
}

/* The Hunt–Crossley dashpot on a contact that begins in the tested step: its first sub-step
 * sets the impact speed v0 = δ̇, so ξ δ̇ = c(ε) there and the force (1 + c) times the elastic
 * one, whose derivative has no rate term; later sub-steps hold v0. */
static void test_hunt_crossley_first_touch(void **state)
{
    (void)state;
    scenario c = base_case();
    c.damping = "hunt_crossley";
    c.pos[2] = 0.1001; /* 0.18 mm above contact, closing at 0.3 m/s: touches after ~6 sub-steps */
    int n = 0;
    check_case(&c, 1e-9, NULL, &n);
    assert_true(n > 0 && n < 10);
}

/* The Hunt–Crossley dashpot on a contact that begins in the tested step and then slows: the
 * sub-step of the first touch sets v0 = δ̇, which depends on the end displacement through the
 * wall's velocity, and the later sub-steps hold it while the stiffer contact brakes the
 * approach, so their force depends on the displacement through v0 as well. */
static void test_hunt_crossley_held_impact_speed(void **state)
{
    (void)state;
    scenario c = base_case();
    c.damping = "hunt_crossley";
    c.youngs = c.net_youngs = 1e9;
    c.pos[2] = 0.10005; /* touches in sub-step 6 of 10 */
    check_case(&c, 1e-9, NULL, NULL);
    /* what the case is for: the contact begins in the step (no history, after sub-step 0)
     * and its approach slows afterwards (the sphere's downward speed falls while the wall
     * moves at one speed), so the v0 its first sub-step set is held in the later ones */
    dem_sim s;
    double disp[9], force[9];
    dem_net_jacobian jac;
    dem_coupled_info info;
    solve_tested_step(&s, &c, DEM_JAC_FROZEN, &jac, disp, force, &info);
    assert_true(jac.n_rec >= 3);
    const dem_jac_record *first = &jac.rec[0], *last = &jac.rec[jac.n_rec - 1];
    assert_true(first->sub > 0 && !first->has_prev);
    print_message("held v0: first touch in sub-step %d at v_z %.4f m/s, last at %.4f m/s\n",
                  (int)first->sub, first->v[2], last->v[2]);
    assert_true(last->v[2] > first->v[2] + 1e-3); /* measured 2.9e-3 of 0.31 m/s */
    dem_net_jacobian_free(&jac);
    dem_sim_free(&s);
}

static void test_spinning_with_history(void **state)
{
    (void)state;
    scenario c = base_case();
    c.omega[0] = 20.0;
    c.omega[1] = -7.0;
    c.pos[2] = 0.1005; /* touches during the warm-up step: history at the start of the test */
    c.warmup = 1;
    check_case(&c, 1e-8, NULL, NULL);
}

static void test_vertex(void **state)
{
    (void)state;
    scenario c = base_case();
    c.n_nodes = 3;
    c.pos[0] = 2.005; /* beyond the end node 2 */
    c.pos[2] = 0.099;
    c.vel[0] = 0.1;
    double K[81];
    check_case(&c, 1e-8, K, NULL);
    /* only node 2 carries stiffness */
    for (int r = 0; r < 9; r++)
        for (int col = 0; col < 9; col++)
            if (r < 6 || col < 6) assert_near(K[r * 9 + col], 0.0, 0.0);
}

static void test_sliding(void **state)
{
    (void)state;
    scenario c = base_case();
    c.vel[1] = 3.0; /* fast across the cable: the tangential spring reaches the cap */
    c.friction = c.net_friction = 0.2;
    c.net_extra = ", \"coupling_force\": \"end_of_step\"";
    check_case(&c, 1e-8, NULL, NULL);
    /* the last sub-step's force is on the Coulomb cone: |F_t| = mu |F_n| (normal ~ z) */
    dem_sim s;
    build(&s, &c);
    double disp[9], force[9];
    warm_up(&s, &c, disp);
    dem_coupled_info info;
    nc_error err;
    assert_int_equal(dem_sim_solve_coupled(&s, c.dt_step, disp, NULL, force, &info, &err), 0);
    const dem_contacts *l = &s.contact.list;
    assert_int_equal(l->n, 1);
    const double *nrm = l->normal;
    double fsum[3] = {force[0] + force[3], force[1] + force[4], force[2] + force[5]};
    double fnm = fsum[0] * nrm[0] + fsum[1] * nrm[1] + fsum[2] * nrm[2];
    double ft[3] = {fsum[0] - fnm * nrm[0], fsum[1] - fnm * nrm[1], fsum[2] - fnm * nrm[2]};
    assert_near_rel(sqrt(ft[0] * ft[0] + ft[1] * ft[1] + ft[2] * ft[2]), 0.2 * fabs(fnm), 1e-9);
    dem_sim_free(&s);
}

static void test_closes_within_step(void **state)
{
    (void)state;
    scenario c = base_case();
    c.pos[2] = 0.1001; /* 0.18 mm above contact, closing at 0.3 m/s: touches after ~6 sub-steps */
    c.law = "linear"; /* the linear spring is smooth at first touch (Hertz: sqrt(δ)) */
    int n = 0;
    check_case(&c, 1e-9, NULL, &n);
    assert_true(n > 0 && n < 10); /* not in every sub-step */
}

static void test_separates_with_clamp(void **state)
{
    (void)state;
    scenario c = base_case();
    /* overlap 5e-5 m, light dashpot (COR 0.9), the net moving away at 0.022 m/s: after the
     * first sub-step the dashpot pulls harder than the spring and Hertz clamps the force to
     * 0 (no tension) for the rest of the step */
    c.restitution = 0.9;
    c.vel[0] = c.vel[2] = 0.0;
    c.pos[2] = 0.0998699;
    c.node_motion[2] = -2.2e-5;
    int n = 0;
    check_case(&c, 1e-11, NULL, &n);
    print_message("separating contact: in %d of 10 sub-steps\n", n);
    assert_true(n > 0);
}

/* A sphere in the fold touches both edges: with DEM_JAC_RESPOND_LOCAL it stays frozen (the
 * blocks of a responding particle would join nodes 0 and 2, which share no element); with
 * DEM_JAC_RESPOND it responds and K has those blocks. */
static void test_two_edges(void **state)
{
    (void)state;
    scenario c = base_case();
    c.n_nodes = 3;
    c.bent = 1;
    c.pos[1] = 0.005;
    c.pos[2] = 0.099;
    int n = 0;
    double K0[81], K1[81];
    check_mode(&c, DEM_JAC_FROZEN, 1e-8, K0, &n);
    assert_true(n >= 20); /* both edges in every sub-step */
    check_mode(&c, DEM_JAC_RESPOND_LOCAL, 1e-8, K1, NULL);
    assert_memory_equal(K0, K1, sizeof K0);
    assert_near(K0[2 * 9 + 8], 0.0, 0.0); /* node 0 force, node 2 motion */
    any_pair = 1;
    check_mode(&c, DEM_JAC_RESPOND, 1e-8, K1, NULL);
    any_pair = 0;
    assert_true(fabs(K1[2 * 9 + 8]) > 0.0);
}

/* Two ropes through node 1, each bent there: the sphere touches the node once per rope. It
 * slides in friction from the interior of edge 1-2 to beyond rope 0-1-2's bend within the step,
 * so that rope's contact becomes a node contact without history beside rope 3-1-4's node
 * contact with it: the replay must keep the two apart (they differ only in their strand). */
static void test_crossing_node_per_rope(void **state)
{
    (void)state;
    scenario c = base_case();
    c.n_nodes = 5;
    c.crossing = 1;
    c.pos[0] = 1.008;
    c.pos[1] = 0.01;
    c.pos[2] = 0.099;
    c.vel[0] = -3.0;
    c.vel[2] = 0.0;
    c.node_motion[2] = -2e-5; /* slower than the base case's, which ends the contact */
    c.warmup = 1;
    dem_sim s;
    dem_net_jacobian jac;
    double disp[NDOF], force[NDOF];
    dem_coupled_info info;
    solve_tested_step(&s, &c, DEM_JAC_FROZEN, &jac, disp, force, &info);
    int edge_first = 0, two_nodes_last = 0;
    for (size_t r = 0; r < jac.n_rec; r++) {
        const dem_jac_record *x = &jac.rec[r];
        if (x->sub == 0 && x->kind == DEM_CONTACT_NET_EDGE) edge_first = 1;
        if (x->sub + 1 == (int32_t)info.substeps && x->kind == DEM_CONTACT_NET_NODE) two_nodes_last++;
    }
    dem_net_jacobian_free(&jac);
    dem_sim_free(&s);
    assert_true(edge_first);
    assert_int_equal(two_nodes_last, 2);
    check_case(&c, 1e-8, NULL, NULL);
}

/* Option off: the same step without the Jacobian gives the same bits. */
static void test_off_unchanged(void **state)
{
    (void)state;
    scenario c = base_case();
    c.warmup = 1;
    c.pos[2] = 0.1005;
    dem_sim a, b;
    build(&a, &c);
    build(&b, &c);
    double da[9], db[9], fa[9], fb[9];
    warm_up(&a, &c, da);
    warm_up(&b, &c, db);
    dem_net_jacobian jac;
    dem_net_jacobian_init(&jac);
    dem_coupled_info ia, ib;
    nc_error err;
    assert_int_equal(dem_sim_solve_coupled(&a, c.dt_step, da, NULL, fa, &ia, &err), 0);
    assert_int_equal(dem_sim_solve_coupled_jacobian(&b, c.dt_step, db, NULL, fb, &ib, &jac, &err), 0);
    assert_true(jac.n_blocks > 0);
    assert_memory_equal(fa, fb, 6 * sizeof *fa);
    assert_memory_equal(a.model.sph.pos, b.model.sph.pos, 3 * sizeof(double));
    assert_memory_equal(a.model.sph.vel, b.model.sph.vel, 3 * sizeof(double));
    assert_memory_equal(a.model.bod.omega, b.model.bod.omega, 3 * sizeof(double));
    assert_memory_equal(a.contact.list.ft, b.contact.list.ft, 3 * sizeof(double));
    assert_int_equal(ia.substeps, ib.substeps);
    dem_net_jacobian_free(&jac);
    dem_sim_free(&a);
    dem_sim_free(&b);
}

/* The granite sphere (R 0.4 m, rho 2650, E 3e10, nu 0.25, COR 0.2, mu 0.5) at 10 m/s on a
 * steel net (E 1e11), coupling dt 1e-3 s, in the step where it hits. */
static scenario granite(void)
{
    scenario c = {"hertz_mindlin", 0.4, 2650.0, 3e10, 0.2, 0.5, 1e11, 0.5, {0.3, 0.0, 0.4002},
                  {0.0, 0.0, -10.0}, {0, 0, 0}, 0.0, 1e-3, "", 2, {0.0, 0.0, -4e-3}, 0, 0, NULL, 0, 0};
    return c;
}

/* K of scenario c's step against a central difference of the real step (particles
 * responding) and of the replay (particles as K treats them), for the motion of both nodes:
 * the largest differences relative to max |K|, printed. */
static void real_step_case(const scenario *cs, int response, double *rel_real, double *rel_replay)
{
    scenario c = *cs;
    dem_sim s;
    build(&s, &c);
    double disp[9], force[9];
    warm_up(&s, &c, disp);
    dem_net_jacobian jac;
    dem_net_jacobian_init(&jac);
    jac.particle_response = response;
    dem_coupled_info info;
    nc_error err;
    assert_int_equal(dem_sim_solve_coupled_jacobian(&s, c.dt_step, disp, NULL, force, &info, &jac, &err), 0);
    assert_true(jac.n_rec > 0);
    double K[36];
    dense(&jac, 2, K);
    double eps = 1e-7, worst = 0.0, kmax = max_abs(K, 36), worst_replay = 0.0;
    for (int col = 0; col < 6; col++) {
        double dp[6], fp[6], fm[6], rp[6], rm[6];
        memcpy(dp, disp, sizeof dp);
        dp[col] = disp[col] + eps;
        assert_int_equal(dem_sim_restore(&s, &err), 0);
        assert_int_equal(dem_sim_solve_coupled(&s, c.dt_step, dp, NULL, fp, &info, &err), 0);
        assert_int_equal(dem_net_jacobian_replay(&s, &jac, dp, rp, 0, &err), 0);
        dp[col] = disp[col] - eps;
        assert_int_equal(dem_sim_restore(&s, &err), 0);
        assert_int_equal(dem_sim_solve_coupled(&s, c.dt_step, dp, NULL, fm, &info, &err), 0);
        assert_int_equal(dem_net_jacobian_replay(&s, &jac, dp, rm, 0, &err), 0);
        for (int row = 0; row < 6; row++) {
            double real = -(fp[row] - fm[row]) / (2.0 * eps), replay = -(rp[row] - rm[row]) / (2.0 * eps);
            worst = fmax(worst, fabs(K[row * 6 + col] - real));
            worst_replay = fmax(worst_replay, fabs(K[row * 6 + col] - replay));
            if ((row == 2 || row == 5) && (col == 2 || col == 5))
                print_message("%s K[%d][%d] %.6g, FD of the real step %.6g\n",
                              response ? "responding" : "frozen", row, col, K[row * 6 + col], real);
        }
    }
    *rel_real = worst / kmax;
    *rel_replay = worst_replay / kmax;
    print_message("granite %s on steel, %s: %zu net contact records, %ld sub-steps, "
                  "max |K| %.4g N/m; |K - FD(real step)| / max|K| = %.3g, "
                  "|K - FD(replay)| / max|K| = %.3g\n", c.cluster ? "cluster" : "sphere",
                  response ? "responding" : "frozen", jac.n_rec, info.substeps, kmax, *rel_real,
                  *rel_replay);
    dem_net_jacobian_free(&jac);
    dem_sim_free(&s);
}

static void test_granite_on_steel(void **state)
{
    (void)state;
    double real, replay;
    scenario c = granite();
    /* frozen: the replay is what K linearises; the real step differs by the particle's
     * response (K dt² / m ~ 1.4 here: the rock's whole impact lasts about one coupling
     * step), measured 0.6 of max |K| (the real step's K is 0.4 of the frozen one) */
    real_step_case(&c, DEM_JAC_FROZEN, &real, &replay);
    assert_below(replay, 1e-6);
    assert_below(real, 0.7);
    /* responding: the rock touches only the net, so the response through its net contacts
     * is the whole real step */
    real_step_case(&c, DEM_JAC_RESPOND_LOCAL, &real, &replay);
    assert_below(replay, 1e-6);
    assert_below(real, 1e-6);
}

/* K of a replay away from the solve's displacement (shifted by `shift` m in z at every
 * node; there the responding particle has moved and turned) against central differences of
 * the replay there. */
static void check_shifted(const scenario *c, int response, double shift, double eps)
{
    dem_sim s;
    double disp[9], force[9];
    dem_net_jacobian jac;
    dem_coupled_info info;
    nc_error err;
    solve_tested_step(&s, c, response, &jac, disp, force, &info);
    int n = c->n_nodes, nd = 3 * n;
    for (int k = 2; k < nd; k += 3) disp[k] += shift;
    assert_int_equal(dem_net_jacobian_replay(&s, &jac, disp, NULL, 1, &err), 0);
    double K[NDOF * NDOF], fd[NDOF * NDOF];
    dense(&jac, n, K);
    replay_differences(&s, &jac, disp, nd, eps, fd);
    double kmax = max_abs(K, (size_t)(nd * nd));
    assert_true(kmax > 0.0);
    for (int e = 0; e < nd * nd; e++) assert_near(K[e], fd[e], 1e-6 * kmax);
    dem_net_jacobian_free(&jac);
    dem_sim_free(&s);
}

/* A cluster on the edge (base_case's sphere plus a smaller one off the contact, spinning):
 * K against central differences of the replay, the cluster frozen and responding as one
 * rigid body (translation and rotation through the offset of the touching sphere). */
static void test_cluster(void **state)
{
    (void)state;
    scenario c = base_case();
    c.cluster = 1;
    c.omega[0] = 3.0;
    c.omega[1] = -2.0;
    c.omega[2] = 1.0;
    double K0[36], K1[36];
    check_mode(&c, DEM_JAC_FROZEN, 1e-8, K0, NULL);
    check_mode(&c, DEM_JAC_RESPOND_LOCAL, 1e-8, K1, NULL);
    any_pair = 1;
    check_mode(&c, DEM_JAC_RESPOND, 1e-8, NULL, NULL);
    any_pair = 0;
    /* the body's response softens K (measured 2e-2 of max |K| here) */
    double diff = 0.0;
    for (int e = 0; e < 36; e++) diff = fmax(diff, fabs(K1[e] - K0[e]));
    print_message("cluster: |K(responding) - K(frozen)| / max|K| = %.3g\n", diff / max_abs(K0, 36));
    assert_true(diff > 1e-3 * max_abs(K0, 36));
}

/* The granite rock as a cluster (the sphere plus one of 0.32 m off the contact: the impact
 * turns it), spinning: the rigid body's response makes K the real step's derivative but for
 * the terms of order |ω| dt the rotation's linearisation leaves out (dem_net_jacobian.h). */
static void test_granite_cluster(void **state)
{
    (void)state;
    double real, replay;
    scenario c = granite();
    c.cluster = 1;
    c.omega[0] = 2.0;
    c.omega[1] = -3.0;
    c.omega[2] = 1.0;
    real_step_case(&c, DEM_JAC_FROZEN, &real, &replay);
    assert_below(replay, 1e-6);
    assert_true(real > 0.3);
    real_step_case(&c, DEM_JAC_RESPOND_LOCAL, &real, &replay);
    assert_below(replay, 1e-6);
    assert_below(real, 5e-4); /* measured 5.0e-5; |ω| dt = 3.7e-3 */
    /* 1 mm deeper than the solve: the rock turns by ~1e-3 rad more in the replay, and K must
     * still be its derivative (the torque of the turned offsets changes with the force too) */
    check_shifted(&c, DEM_JAC_RESPOND_LOCAL, -1e-3, 1e-7);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_edge_interior_hertz),
        cmocka_unit_test(test_edge_interior_linear),
        cmocka_unit_test(test_hunt_crossley_with_history),
        cmocka_unit_test(test_hunt_crossley_first_touch),
        cmocka_unit_test(test_hunt_crossley_held_impact_speed),
        cmocka_unit_test(test_spinning_with_history),
        cmocka_unit_test(test_vertex),
        cmocka_unit_test(test_sliding),
        cmocka_unit_test(test_closes_within_step),
        cmocka_unit_test(test_separates_with_clamp),
        cmocka_unit_test(test_two_edges),
        cmocka_unit_test(test_crossing_node_per_rope),
        cmocka_unit_test(test_off_unchanged),
        cmocka_unit_test(test_granite_on_steel),
        cmocka_unit_test(test_cluster),
        cmocka_unit_test(test_granite_cluster),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
