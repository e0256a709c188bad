/* test_input — dem.json and STL reading: every malformed input is rejected with a message that
 * names the file/field; ASCII and binary STL give the same welded mesh; a sphere resting on
 * triangles sharing an edge or a vertex makes exactly one contact carrying its weight. */
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <setjmp.h>
#include <cmocka.h>
#include "../nc_test_assert.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

#include "dem_stl.h"
#include "dem_test_util.h"

#define MAT "\"materials\": [{\"name\": \"rock\", \"youngs_modulus_pa\": 1e7, \"poisson_ratio\": 0.2," \
            " \"density_kg_m3\": 2500, \"restitution\": 0.5, \"friction\": 0.5}]"

static void expect_error(const char *json, const char *needle)
{
    dem_sim s;
    nc_error err;
    int rc = dem_test_try_build(&s, json, &err);
    dem_sim_free(&s);
    if (rc == 0) {
        print_error("accepted: %s\n", json);
        fail();
    }
    if (!strstr(err.message, needle)) {
        print_error("message \"%s\" does not contain \"%s\"\n", err.message, needle);
        fail();
    }
}

static void test_malformed_json(void **state)
{
    (void)state;
    expect_error("{\"materials\": [", "malformed JSON");
    expect_error("[1, 2]", "test.json");
    expect_error("{" MAT ", \"particles\": [{\"position\": [0,0,0], \"radius\": -0.1}]}",
                 "particles[0].radius");
    expect_error("{" MAT ", \"particles\": [{\"position\": [0,0], \"radius\": 0.1}]}",
                 "particles[0].position");
    expect_error("{" MAT ", \"particles\": [{\"radius\": 0.1}]}", "particles[0].position");
    expect_error("{" MAT ", \"particles\": [{\"position\": [0,0,0], \"radius\": 0.1, \"colour\": 1}]}",
                 "colour");
    expect_error("{" MAT ", \"particles\": [{\"position\": [0,0,0], \"radius\": 0.1, \"material\": \"ice\"}]}",
                 "ice");
    expect_error("{\"particles\": []}", "materials");
    expect_error("{\"materials\": [{\"name\": \"a\", \"youngs_modulus_pa\": -1, \"poisson_ratio\": 0.2,"
                 " \"density_kg_m3\": 1, \"restitution\": 0.5, \"friction\": 0.1}]}",
                 "materials[0].youngs_modulus_pa");
    expect_error("{\"materials\": [{\"name\": \"a\", \"youngs_modulus_pa\": 1, \"poisson_ratio\": 0.2,"
                 " \"density_kg_m3\": 1, \"restitution\": 1.5, \"friction\": 0.1}]}",
                 "materials[0].restitution");
    expect_error("{" MAT ", \"dt_s\": -1}", "dt_s");
    expect_error("{" MAT ", \"dt_s\": \"soon\"}", "dt_s");
    expect_error("{" MAT ", \"contact_law\": \"hooke\"}", "contact_law");
    expect_error("{" MAT ", \"contact_law\": \"linear\"}", "linear");
    expect_error("{" MAT ", \"particles\": [{\"position\": [0,0,0], \"radius\": 0.1},"
                 " {\"position\": [0.15,0,0], \"radius\": 0.1}]}",
                 "overlap");
    expect_error("{" MAT ", \"generators\": [{\"type\": \"random\", \"min\": [0,0,0], \"max\": [0.3,0.3,0.3],"
                 " \"radius\": 0.1, \"count\": 500}]}",
                 "generators[0]");
    expect_error("{" MAT ", \"generators\": [{\"type\": \"hexagonal\", \"min\": [0,0,0], \"max\": [1,1,1],"
                 " \"radius\": 0.1}]}",
                 "generators[0].type");
    expect_error("{" MAT ", \"planes\": [{\"point\": [0,0,0], \"normal\": [0,0,0]}]}", "planes[0]");
    expect_error("{" MAT ", \"meshes\": [{\"file\": \"/nonexistent/terrain.stl\"}]}",
                 "meshes[0].file");
    expect_error("{" MAT ", \"clusters\": [{\"spheres\": []}]}", "clusters[0].spheres");
    expect_error("{" MAT ", \"net_wall\": {\"youngs_modulus_pa\": 1e7, \"poisson_ratio\": 0.2}}",
                 "net_wall.friction");
}

static const char *ascii_square =
    "solid square\n"
    "facet normal 0 0 1\n outer loop\n  vertex 0 0 0\n  vertex 1 0 0\n  vertex 1 1 0\n endloop\nendfacet\n"
    "facet normal 0 0 1\n outer loop\n  vertex 0 0 0\n  vertex 1 1 0\n  vertex 0 1 0\n endloop\nendfacet\n"
    "endsolid square\n";

static size_t binary_square(unsigned char *buf)
{
    static const float tri[2][9] = {{0, 0, 0, 1, 0, 0, 1, 1, 0}, {0, 0, 0, 1, 1, 0, 0, 1, 0}};
    memset(buf, 0, 84);
    buf[80] = 2;
    size_t at = 84;
    for (int t = 0; t < 2; t++) {
        memset(buf + at, 0, 12);
        memcpy(buf + at + 12, tri[t], 36); /* little-endian host assumed (x86-64, aarch64) */
        buf[at + 48] = buf[at + 49] = 0;
        at += 50;
    }
    return at;
}

static void test_stl_ascii_and_binary(void **state)
{
    (void)state;
    char path[512];
    nc_error err;
    dem_mesh a, b;
    memset(&a, 0, sizeof a);
    memset(&b, 0, sizeof b);
    dem_test_write_file(path, sizeof path, "square_ascii.stl", ascii_square, strlen(ascii_square));
    assert_int_equal(dem_stl_load(&a, path, &err), 0);
    unsigned char bin[184];
    size_t len = binary_square(bin);
    dem_test_write_file(path, sizeof path, "square_binary.stl", bin, len);
    assert_int_equal(dem_stl_load(&b, path, &err), 0);
    /* two triangles of a square: 4 welded vertices, 5 edges (the diagonal shared) */
    assert_int_equal(a.n_triangles, 2);
    assert_int_equal(a.n_vertices, 4);
    assert_int_equal(a.n_edges, 5);
    assert_int_equal(b.n_vertices, 4);
    assert_int_equal(b.n_edges, 5);
    assert_memory_equal(a.vertices, b.vertices, 12 * sizeof(double));
    dem_mesh_free(&a);
    dem_mesh_free(&b);

    /* malformed files */
    const char *bad_ascii = "solid x\nfacet normal 0 0 1\n outer loop\n vertex 0 0 zero\n";
    dem_test_write_file(path, sizeof path, "bad1.stl", bad_ascii, strlen(bad_ascii));
    assert_int_equal(dem_stl_load(&a, path, &err), -1);
    assert_non_null(strstr(err.message, "vertex"));
    const char *short_ascii = "solid x\nfacet normal 0 0 1\n outer loop\n vertex 0 0 0\n vertex 1 0 0\n endloop\nendfacet\nendsolid\n";
    dem_test_write_file(path, sizeof path, "bad2.stl", short_ascii, strlen(short_ascii));
    assert_int_equal(dem_stl_load(&a, path, &err), -1);
    assert_non_null(strstr(err.message, "facet 1: expected 'vertex'")); /* its third vertex */
    dem_test_write_file(path, sizeof path, "bad3.stl", bin, len - 20); /* truncated binary */
    assert_int_equal(dem_stl_load(&a, path, &err), -1);
    assert_non_null(strstr(err.message, "not an STL"));
    const char *degenerate = "solid d\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 2 0 0\nendloop\nendfacet\nendsolid d\n";
    dem_test_write_file(path, sizeof path, "bad4.stl", degenerate, strlen(degenerate));
    assert_int_equal(dem_stl_load(&a, path, &err), -1);
    assert_non_null(strstr(err.message, "degenerate"));
    const char *empty = "solid e\nendsolid e\n";
    dem_test_write_file(path, sizeof path, "bad5.stl", empty, strlen(empty));
    assert_int_equal(dem_stl_load(&a, path, &err), -1);
    assert_non_null(strstr(err.message, "no triangles"));
}

/* A sphere resting on the square mesh at (x, y): number of contacts and vertical wall force. */
static void rest_on_mesh(double x, double y, size_t *contacts, double *force_ratio)
{
    char path[512], json[2048];
    dem_test_write_file(path, sizeof path, "floor.stl", ascii_square, strlen(ascii_square));
    snprintf(json, sizeof json,
             "{" MAT ", \"particles\": [{\"position\": [%g, %g, 0.1], \"radius\": 0.1}],"
             " \"meshes\": [{\"file\": \"%s\"}], \"dt_s\": 2e-5}", x, y, path);
    dem_sim s;
    dem_test_build(&s, json);
    nc_error err;
    for (int k = 0; k < 25000; k++) assert_int_equal(dem_sim_step(&s, 2e-5, &err), 0); /* 0.5 s */
    *contacts = s.contact.list.n;
    *force_ratio = -s.wall_force[2] / (s.model.bod.mass[0] * 9.81);
    dem_sim_free(&s);
}

static void test_mesh_shared_features_once(void **state)
{
    (void)state;
    size_t n;
    double ratio;
    const double where[3][2] = {{0.3, 0.6}, {0.5, 0.5}, {0.0, 0.0}}; /* face, shared edge, vertex */
    for (int c = 0; c < 3; c++) {
        rest_on_mesh(where[c][0], where[c][1], &n, &ratio);
        print_message("sphere at (%.1f, %.1f): %zu contact(s), wall force / weight = %.5f\n",
                      where[c][0], where[c][1], n, ratio);
        assert_int_equal(n, 1);
        assert_near(ratio, 1.0, 1e-3); /* at rest: the weight, counted once (0.1 %) */
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_malformed_json),
        cmocka_unit_test(test_stl_ascii_and_binary),
        cmocka_unit_test(test_mesh_shared_features_once),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
