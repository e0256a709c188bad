/* test_input — fem.json and Gmsh reading: a full valid input, the regular-net generator
 * and node sets, Gmsh 2.2 and 4.1 meshes, bad inputs whose messages must name the
 * file, the field and the expectation; a rope given by diameter and pretension force against
 * hand-computed area and prestress; implausible values warned about by file and field. */
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
    char t[15][700];
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
    snprintf(t[12], 700, "{\"nodes\": [[0,0,0],[1,0,0]], \"elements\": [[0,1]], \"analysis\": {\"type\": \"static\", \"initial_state\": \"static\"}, %s}", SETS);
    snprintf(t[13], 700, "{\"nodes\": [[0,0,0],[1,0,0]], \"elements\": [[0,1]], \"analysis\": {\"initial_state\": \"static\", \"load_ramp_s\": 0.1}, %s}", SETS);
    snprintf(t[14], 700, "{\"nodes\": [[0,0,0],[1,0,0]], \"elements\": [[0,1]], \"analysis\": {\"initial_state\": \"settled\"}, %s}", SETS);
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
        {"initialstatic.json", t[12], {"analysis", "initial_state", "dynamic analysis"}},
        {"initialramp.json", t[13], {"initial_state", "load_ramp_s 0.1", "one or the other"}},
        {"initialchoice.json", t[14], {"analysis.initial_state", "settled", NULL}},
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

#define LINE "\"nodes\": [[0,0,0],[1,0,0],[2,0,0]], \"elements\": [[0,1], {\"nodes\": [1,2], \"set\": \"b\"}], " \
             "\"supports\": [{\"nodes\": [0, 2]}], \"analysis\": {\"type\": \"static\"}, "

/* Loads `text` as `name` with a warning sink; returns the warnings (caller frees) and the
 * status in *rc; the error message, if any, in err. */
static char *load_with_warnings(const char *name, const char *text, fem_model *m, int *rc,
                                nc_error *err)
{
    char *warnings = NULL;
    size_t size = 0;
    FILE *sink = open_memstream(&warnings, &size);
    assert_non_null(sink);
    fem_input_options opt = {.warnings = sink};
    nc_error_clear(err);
    *rc = fem_input_load_opt(fem_test_write(name, text), m, &opt, err);
    fclose(sink);
    return warnings;
}

/* diameter_m ↔ area_m2: A = f π d² / 4. A 20 mm rope with the default f = 0.58:
 * 0.58 π 0.02² / 4 = 1.82212373908e-4 m²; with f = 0.75: 2.35619449019e-4 m² (hand-computed).
 * pretension_n ↔ prestress_pa: S_pre = N / A, so A S_pre (the model's AS) is N itself. */
static void test_rope_by_diameter_and_pretension(void **state)
{
    (void)state;
    fem_model m;
    nc_error err;
    int rc;
    char *w = load_with_warnings("rope.json",
        "{" LINE "\"element_sets\": ["
        "{\"name\": \"a\", \"youngs_modulus_pa\": 1e11, \"diameter_m\": 0.02, \"pretension_n\": 10000,"
        " \"breaking_load_n\": 250000, \"density_kg_m3\": 7850},"
        "{\"name\": \"b\", \"youngs_modulus_pa\": 1.2e11, \"diameter_m\": 0.02, \"metallic_area_factor\": 0.75,"
        " \"prestress_pa\": 5e7}]}", &m, &rc, &err);
    if (rc) fail_msg("%s", err.message);
    assert_string_equal(w, "");   /* a realistic rope: no warnings */
    free(w);
    assert_near_rel(m.sets[0].area_m2, 1.82212373908208e-4, 1e-13);
    assert_near_rel(m.sets[1].area_m2, 2.3561944901923448e-4, 1e-13);
    assert_near_rel(m.EA[0], 1e11 * 1.82212373908208e-4, 1e-13);
    assert_near_rel(m.EA[1], 1.2e11 * 2.3561944901923448e-4, 1e-13);
    assert_near_rel(m.sets[0].prestress_pa, 10000.0 / 1.82212373908208e-4, 1e-13);
    assert_near_rel(m.AS[0], 10000.0, 1e-13);
    assert_near_rel(m.AS[1], 5e7 * 2.3561944901923448e-4, 1e-13);
    assert_near(m.sets[0].breaking_load_n, 250000.0, 0.0);
    assert_near(m.sets[1].breaking_load_n, 0.0, 0.0);
    assert_near_rel(m.rhoA[0], 7850 * 1.82212373908208e-4, 1e-13);
    fem_model_free(&m);

    const char *bad[][2] = {
        {"{" LINE "\"element_sets\": [{\"youngs_modulus_pa\": 1e11, \"diameter_m\": 0.02, \"area_m2\": 1e-4}]}",
         "element_sets[0]: give either area_m2 or diameter_m, not both"},
        {"{" LINE "\"element_sets\": [{\"youngs_modulus_pa\": 1e11, \"area_m2\": 1e-4, \"metallic_area_factor\": 0.6}]}",
         "element_sets[0].metallic_area_factor: only used with diameter_m"},
        {"{" LINE "\"element_sets\": [{\"youngs_modulus_pa\": 1e11, \"diameter_m\": 0.02, \"metallic_area_factor\": 1.5}]}",
         "element_sets[0].metallic_area_factor"},
        {"{" LINE "\"element_sets\": [{\"youngs_modulus_pa\": 1e11, \"diameter_m\": -0.02}]}",
         "element_sets[0].diameter_m"},
        {"{" LINE "\"element_sets\": [{\"youngs_modulus_pa\": 1e11, \"area_m2\": 1e-4, \"pretension_n\": 1,"
         " \"prestress_pa\": 1}]}", "element_sets[0]: give either prestress_pa or pretension_n, not both"},
        {"{" LINE "\"element_sets\": [{\"youngs_modulus_pa\": 1e11, \"area_m2\": 1e-4, \"breaking_load_n\": 0}]}",
         "element_sets[0].breaking_load_n: expected a number > 0"},
        {"{" LINE "\"element_sets\": [{\"youngs_modulus_pa\": 1e11}]}", "element_sets[0].area_m2: missing"},
    };
    for (size_t k = 0; k < sizeof bad / sizeof *bad; k++) {
        w = load_with_warnings("badrope.json", bad[k][0], &m, &rc, &err);
        free(w);
        print_message("%s\n", err.message);
        assert_int_equal(rc, -1);
        if (!strstr(err.message, "badrope.json") || !strstr(err.message, bad[k][1]))
            fail_msg("case %zu: message lacks \"%s\": %s", k, bad[k][1], err.message);
        fem_model_free(&m);
    }
}

/* The unit mistakes of a new user (a cable area of 30 m², E = 100 Pa, a diameter in mm,
 * a prestress above yield, a pretension above the breaking load, a breaking load in kN) are
 * read, with one warning each naming file and field. */
static void test_plausibility_warnings(void **state)
{
    (void)state;
    fem_model m;
    nc_error err;
    int rc;
    char *w = load_with_warnings("units.json",
        "{" LINE "\"element_sets\": ["
        "{\"name\": \"a\", \"youngs_modulus_pa\": 100, \"area_m2\": 30, \"density_kg_m3\": 7.85},"
        "{\"name\": \"b\", \"youngs_modulus_pa\": 1e11, \"diameter_m\": 20, \"prestress_pa\": 3e9,"
        " \"breaking_load_n\": 250}]}", &m, &rc, &err);
    if (rc) fail_msg("%s", err.message);
    print_message("%s", w);
    const char *expect[] = {
        "units.json: element_sets[0].area_m2: 30 m² is outside the plausible range 1e-7..1e-2 m²",
        "units.json: element_sets[0].youngs_modulus_pa: 100 Pa is outside the plausible range 1e5..1e12 Pa",
        "units.json: element_sets[0].density_kg_m3: 7.85 kg/m³ is outside the plausible range 100..25000",
        "units.json: element_sets[1].diameter_m: 20 m gives an area of 182.212 m², outside",
        "units.json: element_sets[1].prestress_pa: a prestress of 3e+09 Pa is above 2e9 Pa",
        "units.json: element_sets[1].breaking_load_n: 250 N over the area 182.212 m²",
        "units.json: element_sets[1].prestress_pa: the pretension 5.46637e+11 N exceeds breaking_load_n 250 N",
    };
    for (size_t k = 0; k < sizeof expect / sizeof *expect; k++)
        if (!strstr(w, expect[k])) fail_msg("warnings lack \"%s\":\n%s", expect[k], w);
    int lines = 0;
    for (const char *c = w; *c; c++) lines += *c == '\n';
    assert_int_equal(lines, 7);
    for (const char *c = w; *c; c = strchr(c, '\n') + 1)   /* each line: "warning: <file>: ..." */
        assert_int_equal(strncmp(c, "warning: ", 9), 0);
    free(w);
    assert_int_equal(m.n_elements, 2);   /* warnings do not stop the reading */
    fem_model_free(&m);
    w = load_with_warnings("pretension.json",
        "{" LINE "\"element_sets\": [{\"youngs_modulus_pa\": 1e11, \"diameter_m\": 0.016, \"name\": \"b\","
        " \"pretension_n\": 2e5, \"breaking_load_n\": 1.5e5}]}", &m, &rc, &err);
    if (rc) fail_msg("%s", err.message);
    if (!strstr(w, "pretension.json: element_sets[0].pretension_n: the pretension 200000 N "
                   "exceeds breaking_load_n 150000 N"))
        fail_msg("warnings: %s", w);
    free(w);
    fem_model_free(&m);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_valid_net),
        cmocka_unit_test(test_gmsh),
        cmocka_unit_test(test_bad_inputs),
        cmocka_unit_test(test_rope_by_diameter_and_pretension),
        cmocka_unit_test(test_plausibility_warnings),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
