/* test_stl — the STL reader decides binary or ASCII by the real file size and the facet
 * count, and accounts for every facet: the terrain of cases/terrain_net (1360 facets) loads
 * whole; with a NUL byte at byte 1035 it is refused (it used to load 4 facets, and the rock fell
 * through the terrain); truncated, oversized, non-finite and miscounted files are refused with
 * messages naming the file and the facet. */
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <setjmp.h>
#include <cmocka.h>

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "dem_stl.h"
#include "dem_test_util.h"

static char *read_terrain(size_t *size)
{
    const char *root = getenv("NC_ROOT");
    char path[1024];
    snprintf(path, sizeof path, "%s/cases/terrain_net/terrain.stl", root ? root : ".");
    FILE *f = fopen(path, "rb");
    if (!f) fail_msg("cannot open %s", path);
    fseek(f, 0, SEEK_END);
    long n = ftell(f);
    rewind(f);
    char *text = malloc((size_t)n + 1);
    assert_non_null(text);
    assert_int_equal(fread(text, 1, (size_t)n, f), (size_t)n);
    fclose(f);
    *size = (size_t)n;
    return text;
}

/* Loads bytes written to NC_TMP/name: 0 and the mesh, or -1 and the message checked for the
 * file name and each piece. */
static int load(const char *name, const void *bytes, size_t size, dem_mesh *mesh,
                const char *const *pieces)
{
    char path[512];
    nc_error err;
    memset(mesh, 0, sizeof *mesh);
    dem_test_write_file(path, sizeof path, name, bytes, size);
    int rc = dem_stl_load(mesh, path, &err);
    if (pieces) {
        if (rc == 0) fail_msg("%s: accepted (%zu facets)", name, mesh->n_triangles);
        if (!strstr(err.message, name)) fail_msg("%s: message does not name the file: %s", name, err.message);
        for (const char *const *p = pieces; *p; p++)
            if (!strstr(err.message, *p)) fail_msg("%s: message lacks \"%s\": %s", name, *p, err.message);
    } else if (rc) {
        fail_msg("%s: %s", name, err.message);
    }
    return rc;
}

static void test_terrain_every_facet(void **state)
{
    (void)state;
    size_t size;
    char *text = read_terrain(&size);
    dem_mesh mesh;
    load("terrain.stl", text, size, &mesh, NULL);
    assert_int_equal(mesh.n_triangles, 1360);
    dem_mesh_free(&mesh);
    char saved = text[1035];
    text[1035] = '\0';
    static const char *const nul[] = {"byte 1035", "NUL", "facet 5", NULL};
    load("terrain_nul.stl", text, size, &mesh, nul);
    text[1035] = saved;
    /* cut in the middle of a facet, and cut after a facet (no endsolid) */
    static const char *const cut[] = {"truncated", NULL};
    load("terrain_cut.stl", text, size / 2, &mesh, cut);
    const char *last = strstr(text, "endsolid");
    assert_non_null(last);
    load("terrain_noend.stl", text, (size_t)(last - text), &mesh, cut);
    free(text);
}

/* 84-byte header (starting with `head`) + n facets of a square's two triangles. */
static size_t binary(unsigned char *buf, const char *head, uint32_t announced, int n)
{
    static const float tri[2][9] = {{0, 0, 0, 1, 0, 0, 1, 1, 0}, {0, 0, 0, 1, 1, 0, 0, 1, 0}};
    memset(buf, 0, 84);
    memcpy(buf, head, strlen(head));
    for (int k = 0; k < 4; k++) buf[80 + k] = (unsigned char)(announced >> (8 * k));
    size_t at = 84;
    for (int t = 0; t < n; t++) {
        memset(buf + at, 0, 50);
        for (int k = 0; k < 9; k++) {
            uint32_t bits;
            memcpy(&bits, &tri[t % 2][k], 4);
            for (int b = 0; b < 4; b++) buf[at + 12 + 4 * (size_t)k + (size_t)b] = (unsigned char)(bits >> (8 * b));
        }
        at += 50;
    }
    return at;
}

static void test_binary_by_size(void **state)
{
    (void)state;
    unsigned char buf[84 + 50 * 4 + 16];
    dem_mesh mesh;
    /* header starting with "solid" (as many exporters write it), size exactly 84 + 50 n */
    size_t len = binary(buf, "solid exported by a CAD program", 2, 2);
    load("solid_header.stl", buf, len, &mesh, NULL);
    assert_int_equal(mesh.n_triangles, 2);
    dem_mesh_free(&mesh);
    /* count disagreeing with the size: refused, saying both */
    len = binary(buf, "binary", 3, 2);
    static const char *const miscount[] = {"3 facets", "234", "184", NULL};
    load("miscount.stl", buf, len, &mesh, miscount);
    len = binary(buf, "solid but binary", 3, 2);
    load("miscount_solid.stl", buf, len, &mesh, miscount);
    /* oversized: 16 bytes after the last facet */
    len = binary(buf, "binary", 2, 2);
    memset(buf + len, 0, 16);
    static const char *const over[] = {"2 facets", "184", "200", NULL};
    load("oversized.stl", buf, len + 16, &mesh, over);
    /* a NaN and an infinite coordinate */
    len = binary(buf, "binary", 2, 2);
    float bad = NAN;
    memcpy(buf + 84 + 50 + 12 + 4 * 4, &bad, 4); /* facet 2, vertex 2, y */
    static const char *const nan[] = {"facet 2 of 2", "vertex 2", "coordinate y", "not finite", NULL};
    load("nan.stl", buf, len, &mesh, nan);
    const char *inf = "solid s\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 inf\n"
                      "vertex 1 1 0\nendloop\nendfacet\nendsolid s\n";
    static const char *const ainf[] = {":5:", "facet 1", "coordinate z", "not finite", NULL};
    load("inf.stl", inf, strlen(inf), &mesh, ainf);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_terrain_every_facet),
        cmocka_unit_test(test_binary_by_size),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
