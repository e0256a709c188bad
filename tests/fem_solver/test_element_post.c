/* test_element_post — a hinged post held by a guy rope (types "post" and "cable" read from
 * fem.json): a 4 m steel post (E 2.1e11 Pa, A 5.4e-3 m^2), base hinge pinned, top held by a
 * 16 mm guy rope at 45 degrees to its anchor, a horizontal 50 kN load on the top. The post's
 * compression, the guy's tension and the support reactions against statics by hand (in the
 * deformed geometry to 1e-9, and the small-deflection hand values C = P, T = P sqrt 2 to
 * 1 %); plus the input's errors for element types. */
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

#define P_N 5e4

/* behaviour "cable" on the post set on purpose: the post type carries compression anyway */
static const char *const post_json =
    "{\"nodes\": [[0, 0, 0], [0, 0, 4], [-4, 0, 0]],\n"
    " \"elements\": [{\"nodes\": [0, 1], \"set\": \"post\"}, {\"nodes\": [1, 2], \"set\": \"guy\"}],\n"
    " \"element_sets\": [\n"
    "  {\"name\": \"post\", \"type\": \"post\", \"youngs_modulus_pa\": 2.1e11, \"area_m2\": 5.4e-3,\n"
    "   \"density_kg_m3\": 7850, \"behaviour\": \"cable\"},\n"
    "  {\"name\": \"guy\", \"youngs_modulus_pa\": 1e11, \"area_m2\": 1.26e-4, \"pretension_n\": 5000}],\n"
    " \"supports\": [{\"nodes\": [0, 2], \"dofs\": \"xyz\"}, {\"nodes\": [1], \"dofs\": \"y\"}],\n"
    " \"point_loads\": [{\"nodes\": [1], \"force_n\": [50000, 0, 0]}],\n"
    " \"gravity_m_s2\": [0, 0, 0],\n"
    " \"analysis\": {\"type\": \"static\", \"load_steps\": 4}}\n";

static void test_guyed_post(void **state)
{
    (void)state;
    fem_model m;
    nc_error err;
    if (fem_input_load(fem_test_write("post.json", post_json), &m, &err)) fail_msg("%s", err.message);
    assert_int_equal(m.set_types[0].type, fem_element_find("post"));
    assert_int_equal(m.set_types[1].type, FEM_TYPE_CABLE);
    fem_analysis s;
    assert_int_equal(fem_analysis_init(&s, &m, &err), 0);
    for (int k = 1; k <= 4; k++)
        if (fem_analysis_static(&s, 0.25 * k, &err)) fail_msg("%s", err.message);
    double C = -s.axial[0], T = s.axial[1];
    /* statics of the top in the deformed geometry: C e_down + T e_guy + P x = 0 */
    double top[3], ep[3], eg[3], lp = 0, lg = 0;
    for (int c = 0; c < 3; c++) {
        top[c] = m.X[3 + c] + s.cur.u[3 + c];
        ep[c] = top[c] - m.X[c];             /* base -> top */
        eg[c] = m.X[6 + c] - top[c];         /* top -> anchor */
        lp += ep[c] * ep[c];
        lg += eg[c] * eg[c];
    }
    for (int c = 0; c < 3; c++) { ep[c] /= sqrt(lp); eg[c] /= sqrt(lg); }
    /* x: C ep_x + T eg_x + P = 0, z: C ep_z + T eg_z = 0 (post pushes the top away from base) */
    double det = ep[0] * eg[2] - ep[2] * eg[0];
    double C_hand = (-P_N * eg[2]) / det, T_hand = (P_N * ep[2]) / det;
    print_message("post compression %.2f N (hand %.2f, small deflection %.0f), guy %.2f N (hand "
                  "%.2f, small deflection %.2f), top moved %.4f m in x\n", C, C_hand, P_N, T,
                  T_hand, P_N * sqrt(2.0), s.cur.u[3]);
    assert_near_rel(C, C_hand, 1e-9);
    assert_near_rel(T, T_hand, 1e-9);
    assert_near_rel(C, P_N, 1e-2);
    assert_near_rel(T, P_N * sqrt(2.0), 1e-2);
    assert_true(C > 0.9 * P_N);     /* compression carried, though behaviour says "cable" */
    /* reactions: base takes the post's thrust, the anchor the guy's pull, all of it balances P */
    double f[9];
    fem_analysis_node_balance(&s, 1.0, f);
    for (int c = 0; c < 3; c++) {
        assert_near(f[c], C * ep[c], 1e-9 * P_N);        /* support pushes the post up */
        assert_near(f[6 + c], T * eg[c], 1e-9 * P_N);    /* anchor holds the guy back */
    }
    assert_near(f[0] + f[6] + P_N, 0.0, 1e-8 * P_N);
    assert_near(f[2] + f[8], 0.0, 1e-8 * P_N);
    assert_near(f[3], 0.0, 1e-6);                         /* top: free in x, z */
    assert_near(f[5], 0.0, 1e-6);
    fem_analysis_free(&s);
    fem_model_free(&m);
}

static int load_text(const char *name, const char *text, fem_model *m, nc_error *err)
{
    return fem_input_load(fem_test_write(name, text), m, err);
}

/* Every element type's keys: unknown type, a key of another type, a missing brake key. */
static void test_type_errors(void **state)
{
    (void)state;
    static const struct {
        const char *set, *message;
    } cases[] = {
        {"{\"name\": \"a\", \"type\": \"spring\", \"youngs_modulus_pa\": 1e11, \"area_m2\": 1e-4}",
         "element_sets[0].type: unknown element type \"spring\" (expected one of cable, post, brake, sliding_cable"},
        {"{\"name\": \"a\", \"youngs_modulus_pa\": 1e11, \"area_m2\": 1e-4, \"activation_force_n\": 5e4}",
         "activation_force_n"},
        {"{\"name\": \"a\", \"type\": \"brake\", \"elastic_stiffness_n_per_m\": 2e6, \"activation_force_n\": 5e4,"
         " \"locking_stiffness_n_per_m\": 2e7}",
         "element_sets[0].max_stroke_m"},
        {"{\"name\": \"a\", \"type\": \"brake\", \"elastic_stiffness_n_per_m\": 2e6, \"activation_force_n\": -5,"
         " \"max_stroke_m\": 1, \"locking_stiffness_n_per_m\": 2e7}",
         "element_sets[0].activation_force_n"},
        {"{\"name\": \"a\", \"type\": \"post\", \"area_m2\": 1e-4}", "element_sets[0].youngs_modulus_pa"},
    };
    for (size_t i = 0; i < sizeof cases / sizeof *cases; i++) {
        char text[1024];
        snprintf(text, sizeof text,
                 "{\"nodes\": [[0, 0, 0], [1, 0, 0]], \"elements\": [[0, 1]], \"element_sets\": [%s],"
                 " \"supports\": [{\"nodes\": [0, 1], \"dofs\": \"xyz\"}], \"analysis\": {\"type\": \"static\"}}",
                 cases[i].set);
        fem_model m;
        nc_error err;
        int rc = load_text("types.json", text, &m, &err);
        fem_model_free(&m);
        assert_int_not_equal(rc, 0);
        if (!strstr(err.message, cases[i].message))
            fail_msg("case %zu: \"%s\" does not contain \"%s\"", i, err.message, cases[i].message);
    }
    /* a brake set without a section is valid (massless device) */
    const char *brake =
        "{\"nodes\": [[0, 0, 0], [0.5, 0, 0], [5.5, 0, 0]], \"elements\": [{\"nodes\": [0, 1], \"set\": \"b\"},"
        " {\"nodes\": [1, 2], \"set\": \"r\"}], \"element_sets\": [{\"name\": \"r\", \"youngs_modulus_pa\": 1e11,"
        " \"area_m2\": 1.26e-4}, {\"name\": \"b\", \"type\": \"brake\", \"elastic_stiffness_n_per_m\": 2e6,"
        " \"activation_force_n\": 5e4, \"max_stroke_m\": 1, \"locking_stiffness_n_per_m\": 2e7}],"
        " \"supports\": [{\"nodes\": [0, 2], \"dofs\": \"xyz\"}, {\"nodes\": [1], \"dofs\": \"yz\"}],"
        " \"analysis\": {\"type\": \"static\"}}";
    fem_model m;
    nc_error err;
    if (load_text("brake.json", brake, &m, &err)) fail_msg("%s", err.message);
    assert_int_equal(m.history_count, 2);
    assert_int_equal(m.n_members, 2);
    assert_near(m.set_types[1].param[0], 2e6, 0.0);
    assert_near(m.rhoA[0], 0.0, 0.0);
    /* the default interface: only the plain cable set */
    assert_int_equal(m.n_iface_elements, 1);
    fem_model_free(&m);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_guyed_post),
        cmocka_unit_test(test_type_errors),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
