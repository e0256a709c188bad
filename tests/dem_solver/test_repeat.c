/* test_repeat — determinism: restoring a saved state and repeating a step gives bit-identical
 * results (positions, velocities, tangential history, nodal forces), and the result does not
 * depend on the number of OpenMP threads. Also checks the cell-list neighbour search against an
 * all-pairs count. */
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

#include "dem_neighbor_grid.h"
#include "dem_test_util.h"

/* a frictional granular pile with a cluster, settling in a box: many contacts with history */
static const char *pile_json =
    "{\"materials\": [{\"name\": \"m\", \"youngs_modulus_pa\": 5e6, \"poisson_ratio\": 0.25,"
    " \"density_kg_m3\": 2000, \"restitution\": 0.4, \"friction\": 0.5}],"
    " \"generators\": [{\"type\": \"random\", \"min\": [0,0,0], \"max\": [0.5,0.5,0.4], \"radius\": 0.02,"
    "   \"radius_max\": 0.03, \"count\": 600, \"seed\": 3, \"velocity\": [0.2, 0, -1.0]}],"
    " \"clusters\": [{\"spheres\": [{\"position\": [0.25,0.25,0.48], \"radius\": 0.04},"
    "   {\"position\": [0.3,0.25,0.48], \"radius\": 0.03}], \"angular_velocity\": [0, 4, 1]}],"
    " \"planes\": [{\"point\": [0,0,0], \"normal\": [0,0,1]}, {\"point\": [0,0,0], \"normal\": [1,0,0]},"
    "   {\"point\": [0.5,0.5,0], \"normal\": [-1,0,0]}, {\"point\": [0,0,0], \"normal\": [0,1,0]},"
    "   {\"point\": [0.5,0.5,0], \"normal\": [0,-1,0]}],"
    " \"dt_s\": 2e-5, \"threads\": %d}";

static void build_pile(dem_sim *s, int threads)
{
    char json[4096];
    snprintf(json, sizeof json, pile_json, threads);
    dem_test_build(s, json);
}

static void run(dem_sim *s, int steps)
{
    nc_error err;
    for (int k = 0; k < steps; k++) assert_int_equal(dem_sim_step(s, s->model.prm.dt_s, &err), 0);
}

static void assert_same_state(const dem_sim *a, const dem_sim *b)
{
    assert_int_equal(a->model.sph.n, b->model.sph.n);
    assert_memory_equal(a->model.sph.pos, b->model.sph.pos, 3 * a->model.sph.n * sizeof(double));
    assert_memory_equal(a->model.bod.vel, b->model.bod.vel, 3 * a->model.bod.n * sizeof(double));
    assert_memory_equal(a->model.bod.omega, b->model.bod.omega, 3 * a->model.bod.n * sizeof(double));
    assert_memory_equal(a->model.bod.quat, b->model.bod.quat, 4 * a->model.bod.n * sizeof(double));
    assert_int_equal(a->contact.list.n, b->contact.list.n);
    assert_memory_equal(a->contact.list.ft, b->contact.list.ft, 3 * a->contact.list.n * sizeof(double));
    assert_memory_equal(a->contact.list.j, b->contact.list.j, a->contact.list.n * sizeof(int32_t));
}

static void test_save_restore_bit_identical(void **state)
{
    (void)state;
    dem_sim s;
    build_pile(&s, 0);
    run(&s, 8000); /* the pile has landed: contacts carry tangential history */
    print_message("%zu contacts\n", s.contact.list.n);
    assert_true(s.contact.list.n > 200);
    nc_error err;
    assert_int_equal(dem_sim_begin_step(&s, &err), 0);
    run(&s, 300);
    size_t n = s.model.sph.n, nc = s.contact.list.n;
    double *pos = malloc(3 * n * sizeof *pos), *ft = malloc(3 * nc * sizeof *ft);
    memcpy(pos, s.model.sph.pos, 3 * n * sizeof *pos);
    memcpy(ft, s.contact.list.ft, 3 * nc * sizeof *ft);
    double t = s.time_s;
    assert_int_equal(dem_sim_restore(&s, &err), 0);
    run(&s, 300);
    assert_true(s.time_s == t);
    assert_int_equal(s.contact.list.n, nc);
    assert_memory_equal(s.model.sph.pos, pos, 3 * n * sizeof *pos);
    assert_memory_equal(s.contact.list.ft, ft, 3 * nc * sizeof *ft);
    free(pos);
    free(ft);
    dem_sim_free(&s);
}

static void test_threads_do_not_change_results(void **state)
{
    (void)state;
    dem_sim a, b, c;
    build_pile(&a, 1);
    build_pile(&b, 2);
    build_pile(&c, 3); /* 3 ranges: spheres summed across range boundaries (random order) */
    assert_true(a.model.sph.n >= DEM_PARALLEL_MIN); /* large enough to run in parallel */
    assert_int_equal(a.work.n_buffers, 1);
    assert_int_equal(b.work.n_buffers, 2);
    assert_int_equal(c.work.n_buffers, 3);
    run(&a, 2000);
    run(&b, 2000);
    run(&c, 2000);
    assert_same_state(&a, &b);
    assert_same_state(&a, &c);
    assert_memory_equal(a.wall_force, b.wall_force, 3 * a.n_walls * sizeof(double));
    assert_memory_equal(a.wall_force, c.wall_force, 3 * a.n_walls * sizeof(double));
    dem_sim_free(&a);
    dem_sim_free(&b);
    dem_sim_free(&c);
}

static void test_coupled_restore_identical_forces(void **state)
{
    (void)state;
    const char *json =
        "{\"materials\": [{\"name\": \"m\", \"youngs_modulus_pa\": 1e7, \"poisson_ratio\": 0.2,"
        " \"density_kg_m3\": 2500, \"restitution\": 0.5, \"friction\": 0.4}],"
        " \"particles\": [{\"position\": [0.3, 0.0, 0.0998], \"radius\": 0.1, \"velocity\": [0.3, 0, 0]},"
        "   {\"position\": [0.6, 0.0, 0.35], \"radius\": 0.12, \"velocity\": [0, 0.1, 0]}],"
        " \"net_wall\": {\"youngs_modulus_pa\": 1e7, \"poisson_ratio\": 0.2, \"friction\": 0.3},"
        " \"dt_s\": 1e-5}";
    dem_sim s;
    dem_test_build(&s, json);
    double xyz[9] = {0, 0, 0, 0.5, 0, 0, 1, 0, 0};
    int32_t edges[4] = {0, 1, 1, 2};
    nc_error err;
    assert_int_equal(dem_sim_set_interface(&s, 3, NULL, xyz, 2, edges, &err), 0);
    double disp[9] = {0}, vel[9] = {0}, f1[9], f2[9], f3[9];
    dem_coupled_info info;
    for (int k = 0; k < 30; k++) {
        assert_int_equal(dem_sim_begin_step(&s, &err), 0);
        disp[5] = -1e-5 * k; /* the net sags slowly under the sphere */
        vel[5] = -0.01;
        assert_int_equal(dem_sim_solve_coupled(&s, 1e-3, disp, vel, f1, &info, &err), 0);
    }
    assert_true(info.contacts > 0);
    assert_below(f1[5], 0.0);
    /* iteration 1, then restore and iteration 2 with the same input: identical */
    assert_int_equal(dem_sim_begin_step(&s, &err), 0);
    disp[5] -= 1e-5;
    assert_int_equal(dem_sim_solve_coupled(&s, 1e-3, disp, vel, f1, &info, &err), 0);
    double p1[6];
    memcpy(p1, s.model.sph.pos, sizeof p1);
    assert_int_equal(dem_sim_restore(&s, &err), 0);
    assert_int_equal(dem_sim_solve_coupled(&s, 1e-3, disp, vel, f2, &info, &err), 0);
    print_message("forces z: %g %g %g, contacts %ld\n", f1[2], f1[5], f1[8], info.contacts);
    assert_memory_equal(f1, f2, sizeof f1);
    assert_memory_equal(p1, s.model.sph.pos, sizeof p1);
    /* a different interface position gives a different answer (the test can fail) */
    assert_int_equal(dem_sim_restore(&s, &err), 0);
    disp[5] -= 2e-5;
    assert_int_equal(dem_sim_solve_coupled(&s, 1e-3, disp, vel, f3, &info, &err), 0);
    assert_true(memcmp(f1, f3, sizeof f1) != 0);
    dem_sim_free(&s);
}

/* The cell list finds exactly the pairs an all-pairs loop finds. */
static void test_cell_grid_pairs(void **state)
{
    (void)state;
    size_t n = 2000;
    double *pos = malloc(3 * n * sizeof *pos);
    uint64_t x = 12345;
    for (size_t k = 0; k < 3 * n; k++) {
        x = x * 6364136223846793005ULL + 1442695040888963407ULL;
        pos[k] = (double)(x >> 11) / 9007199254740992.0 * (k % 3 == 2 ? 0.3 : 1.0);
    }
    double cut = 0.05;
    long brute = 0, grid = 0;
    for (size_t i = 0; i < n; i++)
        for (size_t j = i + 1; j < n; j++) {
            double d2 = 0;
            for (int k = 0; k < 3; k++) d2 += (pos[3 * i + k] - pos[3 * j + k]) * (pos[3 * i + k] - pos[3 * j + k]);
            brute += d2 < cut * cut;
        }
    dem_cell_grid g;
    memset(&g, 0, sizeof g);
    nc_error err;
    assert_int_equal(dem_cell_grid_build(&g, n, pos, cut, &err), 0);
    for (size_t i = 0; i < n; i++) {
        int c[3];
        dem_cell_grid_coords(&g, pos + 3 * i, c);
        for (int dz = -1; dz <= 1; dz++)
            for (int dy = -1; dy <= 1; dy++)
                for (int dx = -1; dx <= 1; dx++) {
                    int a = c[0] + dx, b = c[1] + dy, z = c[2] + dz;
                    if (a < 0 || b < 0 || z < 0 || a >= g.dims[0] || b >= g.dims[1] || z >= g.dims[2]) continue;
                    size_t cell = ((size_t)z * (size_t)g.dims[1] + (size_t)b) * (size_t)g.dims[0] + (size_t)a;
                    for (int32_t q = g.cell_start[cell]; q < g.cell_start[cell + 1]; q++) {
                        size_t j = (size_t)g.cell_items[q];
                        if (j <= i) continue;
                        double d2 = 0;
                        for (int k = 0; k < 3; k++) d2 += (pos[3 * i + k] - pos[3 * j + k]) * (pos[3 * i + k] - pos[3 * j + k]);
                        grid += d2 < cut * cut;
                    }
                }
    }
    print_message("pairs: all-pairs %ld, cell list %ld\n", brute, grid);
    assert_true(brute > 100);
    assert_int_equal(brute, grid);
    dem_cell_grid_free(&g);
    free(pos);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_save_restore_bit_identical),
        cmocka_unit_test(test_threads_do_not_change_results),
        cmocka_unit_test(test_coupled_restore_identical_forces),
        cmocka_unit_test(test_cell_grid_pairs),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
