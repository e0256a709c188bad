/* test_input — dem.json and STL reading: every malformed input is rejected with a message that
 * names the file/field; the engineer's forms (mass_kg for radius, drop_height_m and
 * impact_energy_j for velocity) against hand-computed values; implausible values give
 * warnings naming file and field and nothing else; ASCII and binary STL give the same welded mesh; a sphere resting on
 * triangles sharing an edge or a vertex makes exactly one contact carrying its weight; a
 * sphere starting inside a plane or a mesh is refused, touching is not; an STL spanning
 * kilometres (millimetres read as metres) is warned about. */
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <setjmp.h>
#include <cmocka.h>
#include "../nc_test_assert.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

#include <stdlib.h>

#include "dem_config.h"
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
    expect_error("{" MAT ", \"contact_law\": \"linear\", \"damping\": \"hunt_crossley\","
                 " \"linear\": {\"normal_stiffness_n_per_m\": 1e6}}", "test.json.damping");
    expect_error("{\"materials\": [{\"name\": \"a\", \"youngs_modulus_pa\": -1, \"poisson_ratio\": 0.2,"
                 " \"density_kg_m3\": 1, \"restitution\": 0.5, \"friction\": 0.1}]}",
                 "materials[0].youngs_modulus_pa");
    expect_error("{\"materials\": [{\"name\": \"a\", \"youngs_modulus_pa\": 1, \"poisson_ratio\": 0.2,"
                 " \"density_kg_m3\": 1, \"restitution\": 1.5, \"friction\": 0.1}]}",
                 "materials[0].restitution");
    expect_error("{" MAT ", \"dt_s\": -1}", "dt_s: expected a number > 0 or \"auto\", got -1");
    expect_error("{" MAT ", \"dt_s\": \"soon\"}", "got \"soon\"");
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

/* Builds and prepares `json` with a warning sink; returns the warnings text (caller frees). */
static char *build_with_warnings(dem_sim *s, const char *json)
{
    char *text = NULL;
    size_t size = 0;
    FILE *sink = open_memstream(&text, &size);
    assert_non_null(sink);
    dem_config_options opt = {.warnings = sink};
    nc_error err;
    nc_error_clear(&err);
    dem_sim_init(s);
    int rc = dem_config_parse_string_opt(s, json, "test.json", ".", &opt, &err);
    if (rc == 0) rc = dem_sim_prepare(s, &err);
    fclose(sink);
    if (rc) {
        print_error("build failed: %s\n", err.message);
        free(text);
        fail();
    }
    return text;
}

static double speed_of(const dem_sim *s, size_t b)
{
    const double *v = s->model.bod.vel + 3 * b;
    return sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
}

/* mass_kg ↔ radius: m = 4/3 π r³ ρ. 1000 kg of ρ = 2500 kg/m³ is r = (3·1000 / (4π·2500))^(1/3)
 * = 0.45707814973408 m (hand-computed); the prepared body carries the 1000 kg back. */
static void test_mass_and_radius(void **state)
{
    (void)state;
    dem_sim s;
    dem_test_build(&s, "{" MAT ", \"particles\": [{\"position\": [0,0,0], \"mass_kg\": 1000},"
                       " {\"position\": [5,0,0], \"radius\": 0.45707814973408323, \"mass_kg\": 1000}]}");
    assert_near_rel(s.model.sph.radius[0], 0.45707814973408323, 1e-14);
    assert_near_rel(s.model.bod.mass[0], 1000.0, 1e-13);
    assert_near_rel(s.model.sph.radius[1], 0.45707814973408323, 1e-14);
    dem_sim_free(&s);
    expect_error("{" MAT ", \"particles\": [{\"position\": [0,0,0], \"radius\": 0.45, \"mass_kg\": 1000}]}",
                 "particles[0]: radius 0.45 m and mass_kg 1000 kg disagree");
    expect_error("{" MAT ", \"particles\": [{\"position\": [0,0,0]}]}", "particles[0].radius: missing");
    expect_error("{" MAT ", \"particles\": [{\"position\": [0,0,0], \"mass_kg\": -5}]}",
                 "particles[0].mass_kg");
}

/* drop_height_m ↔ velocity: v = sqrt(2 |g| h) along g. Default gravity, h = 5 m:
 * sqrt(2·9.81·5) = 9.9045444115315 m/s downwards; gravity [0, -3, -4] (|g| = 5), h = 10 m:
 * 10 m/s along (0, -0.6, -0.8). A cluster and a generator take it the same way. */
static void test_drop_height(void **state)
{
    (void)state;
    dem_sim s;
    dem_test_build(&s, "{" MAT ", \"particles\": [{\"position\": [0,0,0], \"radius\": 0.3, \"drop_height_m\": 5}],"
                       " \"clusters\": [{\"spheres\": [{\"position\": [2,0,0], \"radius\": 0.1},"
                       " {\"position\": [2.2,0,0], \"radius\": 0.1}], \"drop_height_m\": 5}],"
                       " \"generators\": [{\"type\": \"lattice\", \"min\": [5,5,5], \"max\": [5.2,5.2,5.2],"
                       " \"radius\": 0.1, \"drop_height_m\": 5}]}");
    assert_int_equal(s.model.bod.n, 3);
    for (size_t b = 0; b < 3; b++) {
        assert_near(s.model.bod.vel[3 * b + 0], 0.0, 0.0);
        assert_near(s.model.bod.vel[3 * b + 1], 0.0, 0.0);
        assert_near_rel(s.model.bod.vel[3 * b + 2], -9.904544411531507, 1e-14);
    }
    dem_sim_free(&s);
    dem_test_build(&s, "{" MAT ", \"gravity\": [0, -3, -4], \"particles\": [{\"position\": [0,0,0],"
                       " \"radius\": 0.3, \"drop_height_m\": 10}]}");
    assert_near(s.model.bod.vel[0], 0.0, 0.0);
    assert_near(s.model.bod.vel[1], -6.0, 1e-13);
    assert_near(s.model.bod.vel[2], -8.0, 1e-13);
    dem_sim_free(&s);
    expect_error("{" MAT ", \"particles\": [{\"position\": [0,0,0], \"radius\": 0.3, \"drop_height_m\": 5,"
                 " \"velocity\": [0,0,-1]}]}", "particles[0]: give only one of velocity");
    expect_error("{" MAT ", \"gravity\": [0,0,0], \"particles\": [{\"position\": [0,0,0], \"radius\": 0.3,"
                 " \"drop_height_m\": 5}]}", "particles[0].drop_height_m: needs a non-zero gravity");
    expect_error("{" MAT ", \"particles\": [{\"position\": [0,0,0], \"radius\": 0.3, \"drop_height_m\": -1}]}",
                 "particles[0].drop_height_m");
}

/* impact_energy_j ↔ velocity: v = sqrt(2 E / m). 800 kg with 100 kJ: sqrt(250) =
 * 15.811388300842 m/s, along [1, 0, -1] normalised: ±11.180339887499 m/s; default direction
 * along gravity. A cluster of two spheres r = 0.1 m (m = 20.943951023932 kg) given 1 kJ:
 * sqrt(2000 / m) = 9.7720502380584 m/s, i.e. exactly 1 kJ with the mass dem_sim_prepare sums. */
static void test_impact_energy(void **state)
{
    (void)state;
    dem_sim s;
    dem_test_build(&s, "{" MAT ", \"particles\": [{\"position\": [0,0,0], \"mass_kg\": 800,"
                       " \"impact_energy_j\": 1e5, \"impact_direction\": [1, 0, -1]},"
                       " {\"position\": [5,0,0], \"mass_kg\": 800, \"impact_energy_j\": 1e5}],"
                       " \"clusters\": [{\"spheres\": [{\"position\": [9,0,0], \"radius\": 0.1},"
                       " {\"position\": [9.2,0,0], \"radius\": 0.1}], \"impact_energy_j\": 1000}]}");
    assert_near_rel(s.model.bod.vel[0], 11.180339887498947, 1e-14);
    assert_near(s.model.bod.vel[1], 0.0, 0.0);
    assert_near_rel(s.model.bod.vel[2], -11.180339887498947, 1e-14);
    assert_near_rel(s.model.bod.vel[5], -15.811388300841896, 1e-14);
    assert_near_rel(s.model.bod.mass[2], 20.943951023931955, 1e-14);
    assert_near_rel(speed_of(&s, 2), 9.772050238058398, 1e-14);
    assert_near_rel(0.5 * s.model.bod.mass[2] * speed_of(&s, 2) * speed_of(&s, 2), 1000.0, 1e-13);
    dem_sim_free(&s);
    expect_error("{" MAT ", \"particles\": [{\"position\": [0,0,0], \"radius\": 0.3,"
                 " \"impact_direction\": [1,0,0]}]}", "particles[0].impact_direction: only used with impact_energy_j");
    expect_error("{" MAT ", \"particles\": [{\"position\": [0,0,0], \"radius\": 0.3, \"impact_energy_j\": 10,"
                 " \"impact_direction\": [0,0,0]}]}", "particles[0].impact_direction: expected a non-zero vector");
    expect_error("{" MAT ", \"gravity\": [0,0,0], \"particles\": [{\"position\": [0,0,0], \"radius\": 0.3,"
                 " \"impact_energy_j\": 10}]}", "particles[0].impact_direction: missing");
    expect_error("{" MAT ", \"particles\": [{\"position\": [0,0,0], \"radius\": 0.3, \"impact_energy_j\": 10,"
                 " \"drop_height_m\": 2}]}", "particles[0]: give only one of");
}

static void expect_warning(const char *warnings, const char *needle)
{
    if (!strstr(warnings, needle)) {
        print_error("warnings \"%s\" do not contain \"%s\"\n", warnings, needle);
        fail();
    }
}

/* The unit mistakes of a new user (a 500 m sphere, E = 100 Pa, ρ = 2.65 kg/m³, 150 m/s) are
 * read, with one warning each naming file and field; a realistic rock gives none. */
static void test_plausibility_warnings(void **state)
{
    (void)state;
    dem_sim s;
    char *w = build_with_warnings(&s,
        "{\"materials\": [{\"name\": \"rock\", \"youngs_modulus_pa\": 100, \"poisson_ratio\": 0.2,"
        " \"density_kg_m3\": 2.65, \"restitution\": 0.5, \"friction\": 0.5}],"
        " \"particles\": [{\"position\": [0,0,0], \"radius\": 500},"
        " {\"position\": [2000,0,0], \"radius\": 0.5, \"velocity\": [150, 0, 0]},"
        " {\"position\": [4000,0,0], \"mass_kg\": 1e-9}],"
        " \"net_wall\": {\"youngs_modulus_pa\": 1e13, \"poisson_ratio\": 0.3, \"friction\": 0.3}}");
    print_message("%s", w);
    expect_warning(w, "warning: test.json: materials[0].youngs_modulus_pa: 100 Pa is outside the plausible range 1e5..1e12 Pa");
    expect_warning(w, "warning: test.json: materials[0].density_kg_m3: 2.65 kg/m³ is outside the plausible range 100..25000");
    expect_warning(w, "warning: test.json: particles[0].radius: 500 m is outside the plausible range 1e-3..20 m for a rock");
    expect_warning(w, "warning: test.json: particles[1].velocity: gives a speed of 150 m/s, above the plausible 100 m/s");
    expect_warning(w, "warning: test.json: particles[2].mass_kg: gives a radius of 0.000448286 m, outside the plausible range");
    expect_warning(w, "warning: test.json: net_wall.youngs_modulus_pa: 1e+13 Pa");
    int lines = 0;
    for (const char *c = w; *c; c++) lines += *c == '\n';
    assert_int_equal(lines, 6);
    assert_int_equal(s.model.sph.n, 3);    /* warnings do not stop the reading */
    free(w);
    dem_sim_free(&s);
    w = build_with_warnings(&s,
        "{\"materials\": [{\"name\": \"rock\", \"youngs_modulus_pa\": 3e10, \"poisson_ratio\": 0.2,"
        " \"density_kg_m3\": 2650, \"restitution\": 0.3, \"friction\": 0.5}],"
        " \"particles\": [{\"position\": [0,0,0], \"mass_kg\": 800, \"impact_energy_j\": 1e5}],"
        " \"clusters\": [{\"spheres\": [{\"position\": [3,0,0], \"radius\": 0.3}], \"drop_height_m\": 20}],"
        " \"net_wall\": {\"youngs_modulus_pa\": 1e11, \"poisson_ratio\": 0.3, \"friction\": 0.3}}");
    assert_string_equal(w, "");
    free(w);
    dem_sim_free(&s);
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

/* A sphere may not start inside a plane or a mesh (it would be thrown out by the force of the
 * whole overlap); touching is allowed, and so is a centre far behind a one-sided plane (no
 * contact acts there). The unit square floor.stl at z = 0 and a plane z = 0, radius 0.1 m. */
static void test_start_inside_walls(void **state)
{
    (void)state;
    char path[512], json[2048];
    const char *plane = "\"planes\": [{\"point\": [0,0,0], \"normal\": [0,0,1]}]";
    snprintf(json, sizeof json, "{" MAT ", \"particles\": [{\"position\": [0.3,0.6,0.05], "
             "\"radius\": 0.1}], %s}", plane);
    expect_error(json, "test.json: particle 0 starts 0.05 m inside planes[0] (its centre 0.05 m "
                       "in front of the plane, radius 0.1 m)");
    snprintf(json, sizeof json, "{" MAT ", \"particles\": [{\"position\": [0.3,0.6,-0.05], "
             "\"radius\": 0.1}], %s}", plane);
    expect_error(json, "starts 0.15 m inside planes[0] (its centre 0.05 m behind the plane");
    dem_sim s;
    const double allowed_z[2] = {0.1, -0.5};   /* touching; far behind */
    for (int k = 0; k < 2; k++) {
        snprintf(json, sizeof json, "{" MAT ", \"particles\": [{\"position\": [0.3,0.6,%g], "
                 "\"radius\": 0.1}], %s}", allowed_z[k], plane);
        dem_test_build(&s, json);
        dem_sim_free(&s);
    }
    dem_test_write_file(path, sizeof path, "floor.stl", ascii_square, strlen(ascii_square));
    const double inside_z[2] = {0.095, -0.05};   /* meshes are two-sided */
    const char *said[2] = {"starts 0.005 m inside meshes[0]", "starts 0.05 m inside meshes[0]"};
    for (int k = 0; k < 2; k++) {
        snprintf(json, sizeof json, "{" MAT ", \"particles\": [{\"position\": [0.3,0.6,%g], "
                 "\"radius\": 0.1}], \"meshes\": [{\"file\": \"%s\"}]}", inside_z[k], path);
        expect_error(json, said[k]);
        expect_error(json, "floor.stl");
    }
    snprintf(json, sizeof json, "{" MAT ", \"particles\": [{\"position\": [0.3,0.6,0.1], "
             "\"radius\": 0.1}], \"meshes\": [{\"file\": \"%s\"}]}", path);
    dem_test_build(&s, json);
    dem_sim_free(&s);
}

/* An STL spanning more than 5 km (a slope exported in millimetres) is named in a warning; a
 * metre-sized one is not. */
static void test_mesh_extent_warning(void **state)
{
    (void)state;
    static const char *big =
        "solid big\nfacet normal 0 0 1\n outer loop\n  vertex 0 0 0\n  vertex 22000 0 0\n"
        "  vertex 0 22000 0\n endloop\nendfacet\nendsolid big\n";
    char path[512], json[2048];
    const char *names[2] = {"slope_mm.stl", "floor.stl"};
    const char *texts[2] = {big, ascii_square};
    for (int k = 0; k < 2; k++) {
        dem_test_write_file(path, sizeof path, names[k], texts[k], strlen(texts[k]));
        snprintf(json, sizeof json, "{" MAT ", \"particles\": [{\"position\": [0.3,0.6,0.5], "
                 "\"radius\": 0.1}], \"meshes\": [{\"file\": \"%s\"}]}", path);
        dem_sim s;
        char *w = build_with_warnings(&s, json);
        print_message("%s: %s\n", names[k], w[0] ? w : "(no warning)");
        if (k == 0) {
            expect_warning(w, "test.json: meshes[0].file:");
            expect_warning(w, " spans 22000 m, above the plausible 5000 m");
            expect_warning(w, "slope_mm.stl");
        } else {
            assert_null(strstr(w, "spans"));
        }
        free(w);
        dem_sim_free(&s);
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_malformed_json),
        cmocka_unit_test(test_mass_and_radius),
        cmocka_unit_test(test_drop_height),
        cmocka_unit_test(test_impact_energy),
        cmocka_unit_test(test_plausibility_warnings),
        cmocka_unit_test(test_stl_ascii_and_binary),
        cmocka_unit_test(test_mesh_shared_features_once),
        cmocka_unit_test(test_start_inside_walls),
        cmocka_unit_test(test_mesh_extent_warning),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
