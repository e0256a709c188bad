/* test_element_sliding — the sliding cable (fem_element_sliding.c): one steel rope of 1.26 cm²
 * metallic area (EA = 1.26e7 N, pretension 10 kN) from an anchor over a fixed pulley, through a free
 * shackle carrying 20 kN, over a second pulley to a second anchor. Frictionless: one force N
 * in every segment, the shackle settles where both rope halves make the same angle with the
 * horizontal, 2 N sin(theta) = W, and N = EA (L - L0)/L0 + N_pre on the total length; the
 * closed form (a scalar equation in N, solved here by bisection) gives N, theta and the
 * shackle's position. The pulleys' reactions are N times the sum of the unit vectors to their
 * neighbours. The element tangent and the assembled tangent of a rope through two free
 * shackles (non-neighbour nodes, coupled by the dense material part, which the solver keeps
 * out of its matrix as a rank-one term) match central differences; a static rope end held
 * along the rope by the rope alone converges to equilibrium, and on a straight rope (an
 * exactly zero diagonal in the matrix) to the closed form.
 * Shackle contact (shackle_gap_m): the chain's force and tangent with segments below the gap,
 * taut and slack, against central differences of the force and of the strain energy; a
 * shackle driven along a straight rope into its anchor stops at the gap: undamped, its
 * largest penetration is the energy balance's (the load's work over the run-up equals the
 * contact's energy); damped, it comes to rest at g - P / k_c with the default stiffness
 * k_c = EA / g and with one given, and the anchor takes the load; the assembled step tangent
 * with the contact closed; the set's keys are checked. */
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <setjmp.h>
#include <cmocka.h>
#include "../nc_test_assert.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

#include "../../fem_solver/fem_analysis.h"
#include "../../fem_solver/fem_input.h"
#include "fem_test_util.h"

#define EA_N 1.26e7
#define NPRE_N 1e4
#define W_N 1.2e4
#define Z1 2.0      /* pulley heights (m); the pulleys are 5 m apart */
#define Z2 1.0
#define THETA0 (25.0 * M_PI / 180.0)

/* anchor A (0,0,3), pulley P1 (1,0,2), shackle M, pulley P2 (6,0,1), anchor B (7,0,2); M starts
 * 0.15 m beside the point where the rope halves make 25 degrees with the horizontal (the
 * equilibrium for a load of 2 N_pre sin 25 = 8.45 kN); the load is 12 kN */
static const char *pulley_json(void)
{
    static char text[2048];
    /* 0.15 m off along x, so the shackle has to slide back */
    double z0 = 0.5 * (Z1 + Z2) - 2.5 * tan(THETA0), x0 = 1.0 + (Z1 - z0) / tan(THETA0) + 0.15;
    snprintf(text, sizeof text,
             "{\"nodes\": [[0, 0, 3], [1, 0, %g], [%.17g, 0, %.17g], [6, 0, %g], [7, 0, 2]],\n"
             " \"elements\": [[0, 1], [1, 2], [2, 3], [3, 4]],\n"
             " \"element_sets\": [{\"name\": \"rope\", \"type\": \"sliding_cable\", \"youngs_modulus_pa\": 1e11,\n"
             "   \"area_m2\": 1.26e-4, \"pretension_n\": 10000}],\n"
             " \"supports\": [{\"nodes\": [0, 1, 3, 4], \"dofs\": \"xyz\"}],\n"
             " \"point_loads\": [{\"nodes\": [2], \"force_n\": [0, 0, %g]}],\n"
             " \"gravity_m_s2\": [0, 0, 0],\n"
             " \"analysis\": {\"type\": \"static\", \"max_iterations\": 30}}\n",
             Z1, x0, z0, Z2, -W_N);
    return text;
}

/* the closed form: the middle part spans 5 m between the pulleys at equal angles theta,
 * L = 2 sqrt 2 + 5 / cos(theta), sin(theta) = W / (2 N), N = EA (L - L0)/L0 + N_pre */
static double closed_form_N(double L0)
{
    double lo = W_N / 2.0 * 1.0000001, hi = 1e7;
    for (int it = 0; it < 200; it++) {
        double N = 0.5 * (lo + hi), th = asin(W_N / (2.0 * N));
        double L = 2.0 * sqrt(2.0) + 5.0 / cos(th);
        double g = EA_N * (L - L0) / L0 + NPRE_N - N;
        if (g > 0) lo = N; else hi = N;
    }
    return 0.5 * (lo + hi);
}

static void test_pulley_chain(void **state)
{
    (void)state;
    fem_model m;
    nc_error err;
    if (fem_input_load(fem_test_write("pulley.json", pulley_json()), &m, &err)) fail_msg("%s", err.message);
    assert_int_equal(m.n_members, 1);
    assert_int_equal(m.max_chain_nodes, 5);
    fem_analysis s;
    assert_int_equal(fem_analysis_init(&s, &m, &err), 0);
    int max_it = 0;
    for (int k = 1; k <= 4; k++) {
        if (fem_analysis_static(&s, 0.25 * k, &err)) fail_msg("%s", err.message);
        max_it = s.stats.iterations > max_it ? s.stats.iterations : max_it;
    }
    double x[15], L = 0, L0 = 0;
    for (int i = 0; i < 15; i++) x[i] = m.X[i] + s.cur.u[i];
    double e[4][3], len[4];
    for (int g = 0; g < 4; g++) {
        double l2 = 0;
        for (int c = 0; c < 3; c++) {
            e[g][c] = x[3 * (g + 1) + c] - x[3 * g + c];
            l2 += e[g][c] * e[g][c];
        }
        len[g] = sqrt(l2);
        for (int c = 0; c < 3; c++) e[g][c] /= len[g];
        L += len[g];
        L0 += m.L0[g];
    }
    double N = s.axial[0];
    double N_cf = closed_form_N(L0), th = asin(W_N / (2.0 * N_cf));
    /* shackle M: l1 sin = Z1 - z, l2 sin = Z2 - z, (l1 + l2) cos = 5 */
    double zM = 0.5 * (Z1 + Z2) - 2.5 * tan(th), xM = 1.0 + (Z1 - zM) / tan(th);
    print_message("N = %.3f N (closed form %.3f), theta %.4f rad, shackle at (%.5f, %.5f) "
                  "(closed form (%.5f, %.5f)), L = %.6f m, L0 = %.6f m, at most %d Newton "
                  "iterations\n", N, N_cf, th, x[6], x[8], xM, zM, L, L0, max_it);
    for (int g = 1; g < 4; g++) assert_near_rel(s.axial[g], N, 1e-14);   /* one force */
    assert_near_rel(N, EA_N * (L - L0) / L0 + NPRE_N, 1e-12);          /* total-length strain */
    assert_near_rel(N, N_cf, 1e-8);
    assert_near(x[6], xM, 1e-8);
    assert_near(x[8], zM, 1e-8);
    assert_true(fabs(x[6] - m.X[6]) > 0.1);   /* the shackle slid along the rope */
    /* frictionless: equal angles on both sides of the shackle */
    assert_near(-e[1][2], e[2][2], 1e-9);
    /* node forces: the support of every chain node takes -N (sum of unit vectors to its
     * neighbours); the shackle's balances the load */
    double f[15];
    fem_analysis_node_balance(&s, 1.0, f);
    for (int j = 0; j < 5; j++)
        for (int c = 0; c < 3; c++) {
            double to_prev = j > 0 ? -e[j - 1][c] : 0.0, to_next = j < 4 ? e[j][c] : 0.0;
            double expect = j == 2 ? 0.0 : -N * (to_prev + to_next);
            assert_near(f[3 * j + c], expect, 1e-9 * N);
        }
    assert_true(max_it <= 8);
    fem_analysis_free(&s);
    fem_model_free(&m);
}

/* anchor, shackle, pulley, shackle, anchor: two free nodes that are not neighbours */
/* A rope end held along the rope by nothing but the rope: anchor 0, node 1 hung from a tie,
 * end node 2 tied only perpendicular to its segment (one tie across the segment in its
 * vertical plane, one along y) and pulled along the segment. The factorised matrix has no
 * stiffness there in that direction (the rope's rank-one term stays out of it, and the
 * unloaded ties carry no geometric stiffness at first): Newton must still converge, to
 * equilibrium at every free node (1e-6 of the load), with the rope carrying the pull. */
static const char *const rope_end_json =
    "{\"nodes\": [[0, 0, 0], [2, 0, -0.5], [4, 0, 0], [2, 0, -2.5], [3.514928749927, 0, 1.940285000291],"
    " [4, 2, 0]],\n"
    " \"elements\": [[0, 1], [1, 2], {\"nodes\": [1, 3], \"set\": \"ties\"},"
    " {\"nodes\": [2, 4], \"set\": \"ties\"}, {\"nodes\": [2, 5], \"set\": \"ties\"}],\n"
    " \"element_sets\": [{\"name\": \"rope\", \"type\": \"sliding_cable\", \"youngs_modulus_pa\": 1e11,"
    " \"area_m2\": 1.26e-4, \"pretension_n\": 1000, \"density_kg_m3\": 7850},\n"
    "  {\"name\": \"ties\", \"behaviour\": \"truss\", \"youngs_modulus_pa\": 1e11, \"area_m2\": 1.26e-4,"
    " \"density_kg_m3\": 7850}],\n"
    " \"supports\": [{\"nodes\": [0, 3, 4, 5], \"dofs\": \"xyz\"}],\n"
    " \"point_loads\": [{\"nodes\": [2], \"force_n\": [4850.712500727, 0, 1212.678125182]}],\n"
    " \"gravity_m_s2\": [0, 0, 0], \"analysis\": {\"type\": \"static\"}}\n";

/* Loads `json` (written to `name`), which has one sliding rope, and solves it statically. */
static void solve_static_rope(const char *name, const char *json, fem_model *m, fem_analysis *s)
{
    nc_error err;
    if (fem_input_load(fem_test_write(name, json), m, &err)) fail_msg("%s", err.message);
    assert_int_equal(fem_analysis_init(s, m, &err), 0);
    assert_int_equal(s->lr_members, 1);
    if (fem_analysis_static(s, 1.0, &err)) fail_msg("%s", err.message);
}

static void test_rope_end_held_by_rope(void **state)
{
    (void)state;
    fem_model m;
    fem_analysis s;
    solve_static_rope("rope_end.json", rope_end_json, &m, &s);
    double f[18], worst = 0;
    fem_analysis_node_balance(&s, 1.0, f);
    for (int d = 3; d < 9; d++) worst = fmax(worst, fabs(f[d]));   /* nodes 1 and 2 */
    print_message("rope end held by the rope: %d Newton iterations, end node moved %.6e m, "
                  "rope force %.3f N, largest force imbalance %.3e N\n", s.stats.iterations,
                  sqrt(s.cur.u[6] * s.cur.u[6] + s.cur.u[7] * s.cur.u[7] + s.cur.u[8] * s.cur.u[8]),
                  s.axial[0], worst);
    assert_true(worst < 1e-6 * 5000.0);
    /* the pull goes into the rope: the ties across it take a share only through their
     * rotation (1.5 mm over 2 m) */
    assert_near_rel(s.axial[0], 5000.0, 1e-5);
    fem_analysis_free(&s);
    fem_model_free(&m);
}

/* The same, exactly: a straight rope along x, its end free only along it and pulled there.
 * The matrix has an exactly zero diagonal for that dof (no geometric stiffness along a
 * straight rope, the stretch in the rank-one term), which the factorisation cannot take; the
 * solver puts the term's diagonal there for the preconditioner (fem_analysis.c
 * rank_one_shift). Closed form: N = 5000 N, the end moves (N - N_pre) L0 / EA. */
static const char *const straight_end_json =
    "{\"nodes\": [[0, 0, 0], [2, 0, 0], [4, 0, 0]],\n"
    " \"elements\": [[0, 1], [1, 2]],\n"
    " \"element_sets\": [{\"name\": \"rope\", \"type\": \"sliding_cable\", \"youngs_modulus_pa\": 1e11,"
    " \"area_m2\": 1.26e-4, \"pretension_n\": 1000, \"density_kg_m3\": 7850}],\n"
    " \"supports\": [{\"nodes\": [0, 1], \"dofs\": \"xyz\"}, {\"nodes\": [2], \"dofs\": \"yz\"}],\n"
    " \"point_loads\": [{\"nodes\": [2], \"force_n\": [5000, 0, 0]}],\n"
    " \"gravity_m_s2\": [0, 0, 0], \"analysis\": {\"type\": \"static\"}}\n";

static void test_straight_rope_end(void **state)
{
    (void)state;
    fem_model m;
    fem_analysis s;
    solve_static_rope("straight_end.json", straight_end_json, &m, &s);
    const double EA = 1e11 * 1.26e-4, u_end = (5000.0 - 1000.0) * 4.0 / EA;
    print_message("straight rope end: %d Newton iterations, end moved %.9e m (closed form "
                  "%.9e), rope force %.6f N\n", s.stats.iterations, s.cur.u[6], u_end, s.axial[0]);
    assert_near_rel(s.axial[0], 5000.0, 1e-9);
    assert_near_rel(s.cur.u[6], u_end, 1e-9);
    fem_analysis_free(&s);
    fem_model_free(&m);
}

static const char *const two_shackles_json =
    "{\"nodes\": [[0, 0, 0], [2, 0.3, -0.5], [4, 0, 0.5], [6, -0.2, -0.3], [8, 0, 0]],\n"
    " \"elements\": [[0, 1], [1, 2], [2, 3], [3, 4]],\n"
    " \"element_sets\": [{\"name\": \"rope\", \"type\": \"sliding_cable\", \"youngs_modulus_pa\": 1e11,\n"
    "   \"area_m2\": 1.26e-4, \"pretension_n\": 10000, \"density_kg_m3\": 7850}],\n"
    " \"supports\": [{\"nodes\": [0, 2, 4], \"dofs\": \"xyz\"}],\n"
    " \"gravity_m_s2\": [0, 0, 0],\n"
    " \"analysis\": {\"type\": \"static\"}}\n";

/* The assembled step tangent (c_m M + c_k K_T: the matrix plus the rope's rank-one term,
 * which alone couples the two shackles, not neighbours) against central differences of the
 * step residual; again
 * with stiffness-proportional damping (kappa 1e-3 s, c_c C_K with C_K = kappa K_T at the start
 * of the step, the rope's dense blocks included), whose tangent must differ from the first
 * by more than 5 % of its largest entry, so the damping's blocks are checked too; and again
 * with shackle contact closed on three segments (gap 2.2 m, set past the input check),
 * differing from the second by more than 5 % as well. */
static void test_two_shackles(void **state)
{
    (void)state;
    double K_before[36];
    for (int pass = 0; pass < 3; pass++) {
        fem_model m;
        nc_error err;
        if (fem_input_load(fem_test_write("shackles.json", two_shackles_json), &m, &err))
            fail_msg("%s", err.message);
        m.settings.type = FEM_DYNAMIC;
        m.kappa_s = pass ? 1e-3 : 0.0;
        if (pass == 2) m.set_types[0].param[0] = 2.2;
        fem_analysis s;
        assert_int_equal(fem_analysis_init(&s, &m, &err), 0);
        /* the rope's dense rank-one term stays out of the matrix: no pairs of shackles that
         * are not neighbours in it, the term applied besides (fem_analysis_tangent_apply) */
        assert_int_equal(s.n_chain_pairs, 0);
        assert_int_equal(s.lr_members, 1);
        const int nd = s.ndof, ne = s.neq;
        assert_int_equal(ne, 6);
        double u[15], r[15], rp[15], rm[15], x[6], y[6], kmax = 0;
        /* a general state, the shackles pulled down 5 cm so the rope is taut */
        for (int i = 0; i < nd; i++) u[i] = 0.003 * sin(1.3 * i);
        u[5] -= 0.05;
        u[11] -= 0.05;
        double K[36];
        for (int q = 0; q < ne; q++) {
            assert_int_equal(fem_analysis_step_residual(&s, 1e-3, u, r, &err), 0);
            memset(x, 0, sizeof x);
            x[q] = 1;
            fem_analysis_tangent_apply(&s, x, y);
            for (int p = 0; p < ne; p++) {
                K[6 * p + q] = y[p];
                kmax = fmax(kmax, fabs(y[p]));
            }
        }
        for (int q = 0; q < ne; q++) {
            int d = s.dof_of_eq[q];
            double h = 1e-7;
            u[d] += h;
            fem_analysis_step_residual(&s, 1e-3, u, rp, &err);
            u[d] -= 2 * h;
            fem_analysis_step_residual(&s, 1e-3, u, rm, &err);
            u[d] += h;
            for (int p = 0; p < ne; p++)
                assert_near(K[6 * p + q], -(rp[s.dof_of_eq[p]] - rm[s.dof_of_eq[p]]) / (2 * h), 1e-7 * kmax);
        }
        /* the shackles (nodes 1 and 3) are coupled: the rope's force depends on both */
        double coupling = 0, change = 0;
        for (int p = 0; p < 3; p++)
            for (int q = 3; q < 6; q++) coupling = fmax(coupling, fabs(K[6 * p + q]));
        if (pass)
            for (int i = 0; i < 36; i++) change = fmax(change, fabs(K[i] - K_before[i]));
        memcpy(K_before, K, sizeof K);
        print_message("kappa %g s, gap %g m: largest shackle-shackle entry %.3e N/m of %.3e N/m, "
                      "largest change from the pass before %.3e N/m\n", m.kappa_s,
                      m.set_types[0].param[0], coupling, kmax, change);
        assert_true(coupling > 1e-2 * kmax);
        if (pass) assert_true(change > 5e-2 * kmax);
        fem_analysis_free(&s);
        fem_model_free(&m);
    }
}

/* chain force and tangent against central differences of the force (every entry of the
 * tangent, which is symmetric) and of the strain energy (f = dE/du) */
static void check_chain(const fem_element_ops *ops, fem_element_ctx *c, double *u, int expect_slack)
{
    double f[15], K[225], fp[15], fm[15], ax[4];
    assert_int_equal(ops->chain_response(c, f, K, ax), expect_slack);
    double kmax = 0, fmax_n = 0;
    for (int i = 0; i < 225; i++) kmax = fmax(kmax, fabs(K[i]));
    for (int i = 0; i < 15; i++) fmax_n = fmax(fmax_n, fabs(f[i]));
    assert_true(fmax_n > 0.0);
    for (int j = 0; j < 15; j++) {
        double h = 1e-7;
        u[j] += h;
        ops->chain_response(c, fp, NULL, ax);
        double ep = ops->strain_energy(c);
        u[j] -= 2 * h;
        ops->chain_response(c, fm, NULL, ax);
        double em = ops->strain_energy(c);
        u[j] += h;
        assert_near(f[j], (ep - em) / (2 * h), 1e-6 * fmax_n);
        for (int i = 0; i < 15; i++) {
            assert_near(K[15 * i + j], (fp[i] - fm[i]) / (2 * h), 1e-6 * kmax);
            assert_near(K[15 * i + j], K[15 * j + i], 1e-9 * kmax);
        }
    }
}

/* near_blocks_only (fem_element.h): the same force, and in the blocks of neighbouring nodes
 * the whole tangent less the rank-one term (to 1e-12 of its largest entry); returns k. */
static double check_near_blocks(const fem_element_ops *ops, const fem_element_ctx *c)
{
    enum { N = 5, DIM = 3 * N };
    assert_int_equal(c->count + 1, N);
    double f[DIM], K[DIM * DIM], fn[DIM], Kn[DIM * DIM], g[DIM], ax[N - 1], big = 0.0;
    ops->chain_response(c, f, K, ax);
    const double k = ops->chain_rank_one(c, g);
    fem_element_ctx near = *c;
    near.near_blocks_only = 1;
    for (int i = 0; i < DIM * DIM; i++) Kn[i] = NAN;   /* the other blocks: not read */
    ops->chain_response(&near, fn, Kn, ax);
    for (int i = 0; i < DIM * DIM; i++) big = fmax(big, fabs(K[i]));
    for (int i = 0; i < DIM; i++) assert_true(fn[i] == f[i]);
    for (int a = 0; a < DIM; a++)
        for (int b = 0; b < DIM; b++) {
            if (abs(a / 3 - b / 3) > 1) continue;
            const double want = K[a * DIM + b] - k * g[a] * g[b];
            if (fabs(Kn[a * DIM + b] - want) > 1e-12 * big)
                fail_msg("near blocks: K[%d][%d] = %.17g, the whole tangent less k g g^T %.17g",
                         a, b, Kn[a * DIM + b], want);
        }
    return k;
}

/* The rope alone; a slack rope carries nothing. Then shackle contact: segments 2.08, 2.26,
 * 2.16, 2.03 m at rest, a gap of 2.2 m (set here, past the input check that a loaded model
 * would fail) puts three of them in contact; taut, then slack with the contact still pushing. */
static void test_tangent(void **state)
{
    (void)state;
    fem_model m;
    nc_error err;
    if (fem_input_load(fem_test_write("shackles2.json", two_shackles_json), &m, &err))
        fail_msg("%s", err.message);
    const fem_element_ops *ops = fem_element_type(m.set_types[0].type);
    double u[15], f[15], K[225], ax[4], plain[15];
    for (int i = 0; i < 15; i++) u[i] = 0.01 * sin(1.7 * i + 0.3);
    fem_element_ctx c = {&m, &m.sets[0], m.set_types[0].param, 0, 0, 4, u, NULL, 0};
    check_chain(ops, &c, u, 0);
    ops->chain_response(&c, plain, NULL, ax);
    m.set_types[0].param[0] = 2.2;
    check_chain(ops, &c, u, 0);
    ops->chain_response(&c, f, NULL, ax);
    double change = 0;
    for (int i = 0; i < 15; i++) change = fmax(change, fabs(f[i] - plain[i]));
    print_message("contact changes the chain force by up to %.3e N\n", change);
    assert_true(change > 1e4);   /* k_c = EA / g = 5.7e6 N/m, about 0.1 m deep */
    assert_true(check_near_blocks(ops, &c) > 0.0);   /* taut, in contact */
    for (int i = 0; i < 15; i++) u[i] = -0.05 * m.X[i] + 0.01 * sin(1.1 * i);
    check_chain(ops, &c, u, 1);
    assert_true(check_near_blocks(ops, &c) == 0.0);  /* slack: no term, the contact's blocks */
    /* without contact a shortened rope carries nothing */
    m.set_types[0].param[0] = 0.0;
    for (int i = 0; i < 15; i++) u[i] = -0.2 * m.X[i];
    assert_int_equal(ops->chain_response(&c, f, K, ax), 1);
    assert_near(ax[0], 0.0, 0.0);
    for (int i = 0; i < 15; i++) assert_near(f[i], 0.0, 0.0);
    fem_model_free(&m);
}

/* A straight steel rope (A = 1.26 cm², EA = 1.26e7 N, pretension 10 kN) from anchor A (0,0,0)
 * to anchor B (10,0,0) through a free shackle S at (1,0,0), loaded with P = 5 kN towards A;
 * gap g = 0.5 m, k_c = EA / g = 2.52e7 N/m by default. Along the rope S has no stiffness until
 * it meets the contact. set_keys: the set's shackle keys; rest: the model's keys after it. */
#define SHACKLE_P_N 5000.0
#define SHACKLE_GAP_M 0.5

static const char *straight_rope_json(const char *set_keys, const char *rest)
{
    static char text[1024];
    snprintf(text, sizeof text,
             "{\"nodes\": [[0, 0, 0], [1, 0, 0], [10, 0, 0]],\n"
             " \"elements\": [[0, 1], [1, 2]],\n"
             " \"element_sets\": [{\"name\": \"rope\", \"type\": \"sliding_cable\", \"youngs_modulus_pa\": 1e11,\n"
             "   \"area_m2\": 1.26e-4, \"pretension_n\": 10000, \"density_kg_m3\": 7850%s}],\n"
             " \"supports\": [{\"nodes\": [0, 2], \"dofs\": \"xyz\"}],\n%s}\n", set_keys, rest);
    return text;
}

/* runs the shackle of straight_rope_json with damping tau (1/s) and contact stiffness kc (0:
 * the default) to t_end; the closest it came to A and where it ended */
static void run_shackle(double tau, double kc, double t_end, double *min_len, double *end_len,
                        fem_model *m, fem_analysis *s)
{
    char keys[128], rest[512];
    snprintf(keys, sizeof keys, ", \"shackle_gap_m\": %g", SHACKLE_GAP_M);
    if (kc > 0) snprintf(keys + strlen(keys), sizeof keys - strlen(keys), ", \"shackle_stiffness_n_per_m\": %g", kc);
    snprintf(rest, sizeof rest,
             " \"point_loads\": [{\"nodes\": [1], \"force_n\": [%g, 0, 0]}],\n"
             " \"gravity_m_s2\": [0, 0, 0], \"rayleigh\": {\"tau_per_s\": %g},\n"
             " \"analysis\": {\"type\": \"dynamic\", \"dt_s\": 1e-4, \"end_time_s\": 1}",
             -SHACKLE_P_N, tau);
    nc_error err;
    if (fem_input_load(fem_test_write("shackle_anchor.json", straight_rope_json(keys, rest)), m, &err))
        fail_msg("%s", err.message);
    assert_int_equal(fem_analysis_init(s, m, &err), 0);
    assert_int_equal(fem_analysis_initial_acceleration(s, &err), 0);
    *min_len = 1.0;
    int steps = (int)(t_end / 1e-4 + 0.5);
    for (int k = 0; k < steps; k++) {
        if (fem_analysis_step(s, 1e-4, &err)) fail_msg("step %d: %s", k, err.message);
        double x = m->X[3] + s->cur.u[3];
        *min_len = fmin(*min_len, x);
        assert_true(x > 0.0);   /* never past the anchor */
    }
    *end_len = m->X[3] + s->cur.u[3];
}

static void test_shackle_stops_at_anchor(void **state)
{
    (void)state;
    const double EA = 1e11 * 1.26e-4, P = SHACKLE_P_N;
    double kc = EA / SHACKLE_GAP_M;
    /* undamped: P (1 - g + delta) = k_c delta^2 / 2 at the deepest point */
    const double delta = (P + sqrt(P * P + 2.0 * kc * P * (1.0 - SHACKLE_GAP_M))) / kc;
    fem_model m;
    fem_analysis s;
    double min_len, end_len;
    run_shackle(0.0, 0.0, 0.03, &min_len, &end_len, &m, &s);
    double deepest = SHACKLE_GAP_M - min_len;
    print_message("undamped: deepest %.5f m into the gap (energy balance %.5f m), rope force "
                  "%.1f N\n", deepest, delta, s.axial[0]);
    /* the steps sample the motion, so they may miss the deepest point but not pass it */
    assert_true(deepest <= delta * (1.0 + 1e-3));
    assert_true(deepest >= delta * (1.0 - 0.03));
    assert_near_rel(s.axial[0], 1e4, 1e-6);   /* a straight rope: its length is unchanged */
    fem_analysis_free(&s);
    fem_model_free(&m);
    /* damped to rest: k_c (g - l) = P, with the default stiffness and with one given */
    for (int pass = 0; pass < 2; pass++) {
        if (pass) kc = 4e6;
        run_shackle(200.0, pass ? kc : 0.0, 0.3, &min_len, &end_len, &m, &s);
        double f[9];
        fem_analysis_node_balance(&s, 1.0, f);
        double kinetic, strain;
        fem_analysis_energy(&s, &kinetic, &strain);
        const double rest = SHACKLE_GAP_M - P / kc;
        print_message("damped, k_c %.3g N/m: at rest %.7f m from the anchor (closed form %.7f m), "
                      "anchor reaction %.2f N, contact energy %.4f J (closed form %.4f J)\n", kc,
                      end_len, rest, f[0], strain, 0.5 * P * P / kc);
        assert_near(end_len, rest, 1e-3 * (P / kc));
        assert_near_rel(-f[0], P, 1e-3);
        assert_near_rel(strain, 0.5 * P * P / kc, 1e-2);
        assert_below(kinetic, 1e-6 * strain);
        fem_analysis_free(&s);
        fem_model_free(&m);
    }
}

static void expect_load_error(const char *set_keys, const char *message)
{
    fem_model m;
    nc_error err;
    const char *json = straight_rope_json(set_keys, " \"analysis\": {\"type\": \"static\"}");
    assert_int_equal(fem_input_load(fem_test_write("shackle_bad.json", json), &m, &err), -1);
    fem_model_free(&m);   /* what was read before the error */
    print_message("%s\n", err.message);
    assert_non_null(strstr(err.message, message));
}

static void test_contact_input(void **state)
{
    (void)state;
    expect_load_error(", \"shackle_stiffness_n_per_m\": 1e8", "shackle_stiffness_n_per_m: given without shackle_gap_m");
    expect_load_error(", \"shackle_gap_m\": 0.1, \"shackle_stiffness_n_per_m\": 0", "shackle_stiffness_n_per_m: expected a number > 0");
    expect_load_error(", \"shackle_gap_m\": -0.1", "shackle_gap_m: expected a number >= 0, got -0.1");
    expect_load_error(", \"shackle_gap_m\": 1e-305", "the shackle contact's stiffness (inf N/m) is not a positive finite number");
    expect_load_error(", \"shackle_gap_m\": 1.5",
                      "elements[0] (nodes 0-1 of sliding_cable set \"rope\") is 1 m long at rest, "
                      "shorter than the set's shackle_gap_m 1.5 m");
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_pulley_chain),
        cmocka_unit_test(test_two_shackles),
        cmocka_unit_test(test_rope_end_held_by_rope),
        cmocka_unit_test(test_straight_rope_end),
        cmocka_unit_test(test_tangent),
        cmocka_unit_test(test_shackle_stops_at_anchor),
        cmocka_unit_test(test_contact_input),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
