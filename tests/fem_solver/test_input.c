/* test_input — fem.json and Gmsh reading: a full valid input, the regular-net generator
 * and node sets, Gmsh 2.2 and 4.1 meshes, and bad inputs whose messages must name the
 * file, the field and the expectation. */
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <setjmp.h>
#include <cmocka.h>
#include "../nc_test_assert.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

#include "../../fem_solver/fem_input.h"
#include "fem_test_util.h"

static const char *valid_net =
    "{\"description\": \"test net\",\n"
    " \"net\": {\"origin_m\": [0,0,1], \"edge1_m\": [2,0,0], \"edge2_m\": [0,1,0], \"count1\": 5, \"count2\": 3, \"set\": \"b\"},\n"
    " \"element_sets\": [{\"name\": \"a\", \"youngs_modulus_pa\": 1e9, \"area_m2\": 1e-4, \"behaviour\": \"truss\"},\n"
    "                  {\"name\": \"b\", \"youngs_modulus_pa\": 2e9, \"area_m2\": 2e-4, \"density_kg_m3\": 7850, \"prestress_pa\": 1e5}],\n"
    " \"node_sets\": {\"mine\": [6, 7, \"corners\"]},\n"
    " \"supports\": [{\"nodes\": \"boundary\"}, {\"nodes\": 7, \"dofs\": \"z\", \"displacement_m\": [0, 0, -0.01]}],\n"
    " \"point_loads\": [{\"nodes\": [\"center\", 6], \"force_n\": [0, 0, -10]}],\n"
    " \"self_weight\": true, \"gravity_m_s2\": [0, -9.81, 0], \"mass\": \"lumped\",\n"
    " \"rayleigh\": {\"tau_per_s\": 5, \"kappa_s\": 0.001},\n"
    " \"monitor_nodes\": [\"center\", 8],\n"
    " \"output\": {\"interval_steps\": 4},\n"
    " \"analysis\": {\"type\": \"dynamic\", \"integrator\": \"bossak\", \"alpha_b\": -0.2, \"dt_s\": 0.002, \"end_time_s\": 0.5, \"max_iterations\": 12}\n"
    "}\n";

static void test_valid_net(void **state)
{
    (void)state;
    fem_model m;
    nc_error err;
    const char *path = fem_test_write("valid.json", valid_net);
    if (fem_input_load(path, &m, &err)) fail_msg("%s", err.message);
    assert_int_equal(m.n_nodes, 15);
    assert_int_equal(m.n_elements, 4 * 3 + 5 * 2);
    assert_int_equal(m.element_set[0], 1);
    assert_near(m.X[3 * 14 + 0], 2.0, 1e-15);
    assert_near(m.X[3 * 14 + 1], 1.0, 1e-15);
    assert_near(m.X[3 * 14 + 2], 1.0, 0.0);
    assert_near(m.EA[0], 2e9 * 2e-4, 1e-3);
    assert_near(m.AS[0], 1e5 * 2e-4, 1e-12);
    /* boundary: 12 nodes fixed in xyz; node 7 (centre) then also given u_z = -0.01 */
    int fixed_nodes = 0;
    for (int i = 0; i < 15; i++) fixed_nodes += m.fixed[3 * i] && m.fixed[3 * i + 1] && m.fixed[3 * i + 2];
    assert_int_equal(fixed_nodes, 12);
    assert_true(m.fixed[3 * 7 + 2] && !m.fixed[3 * 7]);
    assert_near(m.u_prescribed[3 * 7 + 2], -0.01, 0.0);
    assert_near(m.f_point[3 * 7 + 2], -10.0, 0.0);
    assert_near(m.f_point[3 * 6 + 2], -10.0, 0.0);
    assert_true(m.self_weight && m.lumped_mass);
    assert_near(m.gravity[1], -9.81, 0.0);
    assert_near(m.tau_per_s, 5.0, 0.0);
    assert_near(m.kappa_s, 0.001, 0.0);
    assert_int_equal(m.n_monitor, 2);
    assert_int_equal(m.monitor_nodes[0], 7);
    assert_int_equal(m.settings.output_interval, 4);
    assert_int_equal(m.settings.integrator, FEM_BOSSAK);
    assert_near(m.settings.alpha_b, -0.2, 0.0);
    assert_near(m.settings.dt_s, 0.002, 0.0);
    assert_int_equal(m.settings.max_iterations, 12);
    const fem_node_set *mine = fem_model_find_node_set(&m, "mine");
    assert_non_null(mine);
    assert_int_equal(mine->count, 6);
    /* default interface: the cable set "b" = every element, every node */
    assert_int_equal(m.n_iface_elements, 22);
    assert_int_equal(m.n_iface_nodes, 15);
    fem_model_free(&m);
}

static const char *msh2 =
    "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n"
    "$PhysicalNames\n2\n0 1 \"anchors\"\n1 2 \"stiff\"\n$EndPhysicalNames\n"
    "$Nodes\n4\n10 0 0 0\n20 1 0 0\n30 2 0 0\n40 3 0 0\n$EndNodes\n"
    "$Elements\n5\n1 15 2 1 1 10\n2 15 2 1 4 40\n3 1 2 0 1 10 20\n4 1 2 2 2 20 30\n5 1 2 0 3 30 40\n$EndElements\n";

static const char *msh4 =
    "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n"
    "$PhysicalNames\n2\n0 1 \"anchors\"\n1 2 \"stiff\"\n$EndPhysicalNames\n"
    "$Entities\n2 2 0 0\n1 0 0 0 1 1\n2 3 0 0 1 1\n1 0 0 0 2 0 0 0 2 1 2\n2 2 0 0 3 0 0 1 2 2 1 2\n$EndEntities\n"
    "$Nodes\n2 4 1 4\n1 1 0 2\n1\n4\n0 0 0\n3 0 0\n1 2 0 2\n2\n3\n1 0 0\n2 0 0\n$EndNodes\n"
    "$Elements\n4 5 1 5\n0 1 15 1\n1 1\n0 2 15 1\n2 4\n1 1 1 2\n3 1 2\n5 3 4\n1 2 1 1\n4 2 3\n$EndElements\n";

static const char *msh_json =
    "{\"mesh\": {\"file\": \"%s\", \"set\": \"soft\"},\n"
    " \"element_sets\": [{\"name\": \"soft\", \"youngs_modulus_pa\": 1e5, \"area_m2\": 1e-4},\n"
    "                  {\"name\": \"stiff\", \"youngs_modulus_pa\": 1e9, \"area_m2\": 1e-4}],\n"
    " \"supports\": [{\"nodes\": \"anchors\"}], \"analysis\": {\"type\": \"static\"}}\n";

/* The paper's 7.1 cable as a Gmsh mesh: physical line "stiff" picks the element set of
 * that name, physical point group "anchors" becomes a node set usable in supports. */
static void test_gmsh(void **state)
{
    (void)state;
    const char *texts[2] = {msh2, msh4};
    for (int v = 0; v < 2; v++) {
        char name[32], json[1024];
        snprintf(name, sizeof name, "cable%d.msh", v);
        const char *mpath = fem_test_write(name, texts[v]);
        const char *base = strrchr(mpath, '/') + 1;
        snprintf(json, sizeof json, msh_json, base);
        snprintf(name, sizeof name, "gmsh%d.json", v);
        const char *jpath = fem_test_write(name, json);
        fem_model m;
        nc_error err;
        if (fem_input_load(jpath, &m, &err)) fail_msg("gmsh %d: %s", v, err.message);
        if (m.n_nodes != 4 || m.n_elements != 3)
            fail_msg("gmsh %d: %d nodes, %d elements (expected 4, 3)", v, m.n_nodes, m.n_elements);
        double length = 0;
        for (int e = 0; e < 3; e++) length += m.L0[e];
        assert_near(length, 3.0, 1e-12);
        int stiff = fem_model_find_set(&m, "stiff"), n_stiff = 0;
        for (int e = 0; e < 3; e++) n_stiff += m.element_set[e] == stiff;
        assert_int_equal(n_stiff, 1);
        int fixed = 0;
        for (int i = 0; i < 12; i++) fixed += m.fixed[i];
        assert_int_equal(fixed, 6);
        /* the fixed nodes are the ends, x = 0 and x = 3 */
        for (int i = 0; i < 4; i++)
            assert_int_equal(m.fixed[3 * i], m.X[3 * i] == 0.0 || m.X[3 * i] == 3.0);
        fem_model_free(&m);
    }
}

typedef struct bad_case {
    const char *name, *text;
    const char *expect[3];   /* substrings of the message */
} bad_case;

static const char *SETS = "\"element_sets\": [{\"name\": \"a\", \"youngs_modulus_pa\": 1e9, \"area_m2\": 1e-4}]";

static void test_bad_inputs(void **state)
{
    (void)state;
    char t[12][700];
    snprintf(t[0], 700, "{\"nodes\": [[0,0,0],[1,0,0]], \"elements\": [[0,1]], %s", SETS); /* unterminated */
    snprintf(t[1], 700, "{\"nodes\": [[0,0,0],[1,0,0]], \"elements\": [[0,1]], \"element_sets\": [{\"area_m2\": 1e-4}]}");
    snprintf(t[2], 700, "{\"nodes\": [[0,0,0],[1,0,0]], \"elements\": [[0,1]], \"element_sets\": [{\"youngs_modulus_pa\": -3, \"area_m2\": 1e-4}]}");
    snprintf(t[3], 700, "{\"nodes\": [[0,0,0],[1,0,0]], \"elements\": [[0,1],[1,2]], %s}", SETS);
    snprintf(t[4], 700, "{\"nodes\": [[0,0,0],[1,0,0]], \"elements\": [[0,1]], \"suports\": [], %s}", SETS);
    snprintf(t[5], 700, "{\"nodes\": [[0,0,0],[1,0,0]], \"elements\": [[0,1]], \"supports\": [{\"nodes\": \"edge\"}], %s}", SETS);
    snprintf(t[6], 700, "{\"nodes\": [[0,0,0],[1,0,\"a\"]], \"elements\": [[0,1]], %s}", SETS);
    snprintf(t[7], 700, "{\"nodes\": [[0,0,0],[0,0,0]], \"elements\": [[0,1]], %s}", SETS);
    snprintf(t[8], 700, "{\"net\": {\"origin_m\": [0,0,0], \"edge1_m\": [1,0,0], \"edge2_m\": [2,0,0], \"count1\": 3, \"count2\": 3}, %s}", SETS);
    snprintf(t[9], 700, "{\"nodes\": [[0,0,0],[1,0,0]], \"elements\": [[0,1]], \"analysis\": {\"type\": \"statics\"}, %s}", SETS);
    snprintf(t[10], 700, "{\"mesh\": {\"file\": \"does-not-exist.msh\"}, %s}", SETS);
    snprintf(t[11], 700, "{\"nodes\": [[0,0,0],[1,0,0],[2,0,0]], \"elements\": [[0,1]], %s}", SETS);
    bad_case cases[] = {
        {"malformed.json", t[0], {"malformed.json", "malformed JSON", NULL}},
        {"missing.json", t[1], {"element_sets[0].youngs_modulus_pa", "missing", NULL}},
        {"negative.json", t[2], {"element_sets[0].youngs_modulus_pa", "> 0", "-3"}},
        {"badindex.json", t[3], {"elements[1]", "out of range", NULL}},
        {"typo.json", t[4], {"suports", NULL, NULL}},
        {"nodeset.json", t[5], {"supports[0].nodes", "unknown node set", "edge"}},
        {"nodecoord.json", t[6], {"nodes[1]", "finite numbers", NULL}},
        {"zerolength.json", t[7], {"elements[0]", "coincide", NULL}},
        {"parallel.json", t[8], {"net.edge2_m", "not parallel", NULL}},
        {"choice.json", t[9], {"analysis.type", "statics", NULL}},
        {"nomesh.json", t[10], {"mesh.file", "does-not-exist.msh", "cannot open"}},
        {"unconnected.json", t[11], {"node 2", "not connected", NULL}},
    };
    for (size_t i = 0; i < sizeof cases / sizeof *cases; i++) {
        const char *path = fem_test_write(cases[i].name, cases[i].text);
        fem_model m;
        nc_error err;
        nc_error_clear(&err);
        int rc = fem_input_load(path, &m, &err);
        print_message("%-18s -> %s\n", cases[i].name, err.message);
        assert_int_equal(rc, -1);
        assert_non_null(strstr(err.message, cases[i].name));   /* names the file */
        for (int k = 0; k < 3 && cases[i].expect[k]; k++)
            if (!strstr(err.message, cases[i].expect[k]))
                fail_msg("%s: message lacks \"%s\": %s", cases[i].name, cases[i].expect[k], err.message);
        fem_model_free(&m);
    }
    /* a missing file */
    fem_model m;
    nc_error err;
    assert_int_equal(fem_input_load("/nonexistent/fem.json", &m, &err), -1);
    assert_non_null(strstr(err.message, "/nonexistent/fem.json"));
    fem_model_free(&m);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_valid_net),
        cmocka_unit_test(test_gmsh),
        cmocka_unit_test(test_bad_inputs),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
