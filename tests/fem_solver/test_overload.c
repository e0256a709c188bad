/* test_overload — each element set's largest axial force and the elements above its
 * breaking_load_n (fem_output_monitor, every step), against a closed form.
 *
 * Model: a straight truss of 4 elements along x (nodes 0..4, 1 m each, E A = 1e7 N), node 0
 * fixed, the others held in y and z, a load P = 10 kN along +x on each of nodes 1..4.
 * Whatever the stretch, node equilibrium gives element j the axial force (4 - j) λ P at load
 * factor λ: 40, 30, 20, 10 kN at λ = 1. Elements 0 and 1 are set "rope", 2 is "tail"
 * (breaking load 25 kN, never reached), 3 is "plain" (no breaking load). Four load steps.
 *  - rope 25 kN: element 0 exceeds it first at λ = 0.75 (30 kN), element 1 at λ = 1 (30 kN):
 *    2 elements, first at 0.75; peak 40 kN in element 0 at λ = 1, 1.6x.
 *  - rope 40 kN (1 - 1e-6): only element 0, at λ = 1; rope 40 kN (1 + 1e-6): none.
 * The peaks equal the hand values to 1e-9 relative (Newton solves to 1e-8 N absolute); the
 * exceedance counts and times are exact. Through fem_run_standalone, so fem.h5's
 * /element_sets datasets and root attributes and the run summary are checked too.
 * Then a dynamic run of the same truss under the sudden load (element 0 overshoots to nearly
 * 2 x 40 kN; rope breaking load 50 kN) is checkpointed at 1.4 ms, between the first
 * exceedances and the peak, and resumed in a fresh analysis and output (fem_checkpoint_load,
 * fem_output_reopen): the per-set peaks and exceedance times equal the uninterrupted run's
 * at the checkpoint and at the end, bit for bit.
 */
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <setjmp.h>
#include <cmocka.h>
#include "../nc_test_assert.h"

#include <hdf5.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "../../fem_solver/fem_analysis.h"
#include "../../fem_solver/fem_checkpoint.h"
#include "../../fem_solver/fem_output.h"
#include "../../fem_solver/fem_run.h"
#include "fem_test_util.h"
#include "nc_file.h"

#define P_N 1e4
#define TAIL_BREAK_N 25e3

/* The truss; rope_break_n: the breaking load of set rope. */
static void build(fem_model *m, double rope_break_n, fem_analysis_type type)
{
    nc_error err;
    fem_test_line(m, 4, 4.0, 1e11, 1e-4, 7850, 0.0, FEM_TRUSS, 0);
    snprintf(m->sets[0].name, sizeof m->sets[0].name, "rope");
    m->sets[0].breaking_load_n = rope_break_n;
    fem_element_set set = m->sets[0];
    snprintf(set.name, sizeof set.name, "tail");
    set.breaking_load_n = TAIL_BREAK_N;
    assert_int_equal(fem_model_add_set(m, &set, &err), 1);
    snprintf(set.name, sizeof set.name, "plain");
    set.breaking_load_n = 0.0;
    assert_int_equal(fem_model_add_set(m, &set, &err), 2);
    m->element_set[2] = 1;
    m->element_set[3] = 2;
    for (int c = 0; c < 3; c++) m->fixed[c] = 1;
    for (int i = 1; i <= 4; i++) {
        m->fixed[3 * i + 1] = m->fixed[3 * i + 2] = 1;
        m->f_point[3 * i] = P_N;
    }
    m->settings.type = type;
    m->settings.load_steps = 4;
    m->settings.residual_tol_n = 1e-8;
    m->settings.dt_s = 1e-4;
    m->settings.end_time_s = 2e-2;
    if (fem_model_finalize(m, &err)) fail_msg("%s", err.message);
}

static void out_dir(const char *tag, char *dir, size_t size)
{
    const char *tmp = getenv("NC_TMP");
    if (!tmp || !*tmp) tmp = "/tmp";
    snprintf(dir, size, "%s/%d-overload-%s", tmp, (int)getpid(), tag);
    nc_error err;
    assert_int_equal(nc_file_make_dirs(dir, &err), 0);
}

static void read_f64(hid_t f, const char *path, double *out)
{
    hid_t d = H5Dopen2(f, path, H5P_DEFAULT);
    assert_true(d >= 0);
    assert_true(H5Dread(d, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, out) >= 0);
    H5Dclose(d);
}

static void read_int(hid_t f, const char *path, int *out)
{
    hid_t d = H5Dopen2(f, path, H5P_DEFAULT);
    assert_true(d >= 0);
    assert_true(H5Dread(d, H5T_NATIVE_INT, H5S_ALL, H5S_ALL, H5P_DEFAULT, out) >= 0);
    H5Dclose(d);
}

static void test_static_closed_form(void **state)
{
    (void)state;
    const struct {
        double rope_break_n;
        int exceeded;        /* elements of rope above its breaking load */
        double first;        /* load factor of the first exceedance, -1 none */
    } cases[] = {{25e3, 2, 0.75}, {4 * P_N * (1 - 1e-6), 1, 1.0}, {4 * P_N * (1 + 1e-6), 0, -1.0}};
    for (size_t c = 0; c < sizeof cases / sizeof *cases; c++) {
        fem_model m;
        build(&m, cases[c].rope_break_n, FEM_STATIC);
        char dir[600];
        char tag[16];
        snprintf(tag, sizeof tag, "static%zu", c);
        out_dir(tag, dir, sizeof dir);
        fem_set_overload r[3];
        fem_run_summary sum;
        memset(&sum, 0, sizeof sum);
        sum.overload = r;
        nc_error err;
        if (fem_run_standalone(&m, dir, NULL, NULL, &sum, &err)) fail_msg("%s", err.message);
        assert_ptr_equal(sum.overload, r);
        assert_int_equal(sum.overloaded_elements, cases[c].exceeded);
        /* rope: peak 4 P in element 0 at λ = 1 */
        assert_int_equal(r[0].exceeded, cases[c].exceeded);
        assert_true(r[0].first_time_s == cases[c].first);
        assert_near_rel(r[0].peak_n, 4 * P_N, 1e-9);
        assert_int_equal(r[0].peak_element, 0);
        assert_true(r[0].peak_time_s == 1.0);
        assert_true(r[0].breaking_load_n == cases[c].rope_break_n);
        /* tail: 2 P < 25 kN; plain: P, no breaking load */
        assert_int_equal(r[1].exceeded, 0);
        assert_near_rel(r[1].peak_n, 2 * P_N, 1e-9);
        assert_int_equal(r[1].peak_element, 2);
        assert_int_equal(r[2].exceeded, 0);
        assert_true(r[2].breaking_load_n == 0.0);
        assert_near_rel(r[2].peak_n, P_N, 1e-9);
        assert_int_equal(r[2].peak_element, 3);

        char line[512];
        fem_set_overload_text(&m, 0, &r[0], line, sizeof line);
        if (cases[c].exceeded == 2)
            assert_string_equal(line, "warning: set rope: 2 elements exceeded breaking_load_n 25000 N "
                                      "(first at load factor 0.75); largest 40000 N (1.6x) in element 0 "
                                      "at load factor 1; the model has no rope failure, forces beyond "
                                      "the breaking load are not physical");
        fem_set_overload_text(&m, 1, &r[1], line, sizeof line);
        assert_string_equal(line, "set tail: largest axial force 20000 N, 0.8x breaking_load_n 25000 N, "
                                  "in element 2 at load factor 1");

        /* fem.h5 */
        char path[700];
        snprintf(path, sizeof path, "%s/fem.h5", dir);
        hid_t f = H5Fopen(path, H5F_ACC_RDONLY, H5P_DEFAULT);
        assert_true(f >= 0);
        double peak[3], brk[3], first[3], el_time[4], total = -1;
        int count[3], where[3];
        read_f64(f, "/element_sets/peak_axial_force", peak);
        read_f64(f, "/element_sets/breaking_load", brk);
        read_f64(f, "/element_sets/first_exceedance_time", first);
        read_f64(f, "/element_sets/element_exceedance_time", el_time);
        read_int(f, "/element_sets/exceeded_elements", count);
        read_int(f, "/element_sets/peak_element", where);
        for (int k = 0; k < 3; k++) {
            assert_true(peak[k] == r[k].peak_n && brk[k] == r[k].breaking_load_n);
            assert_true(first[k] == r[k].first_time_s);
            assert_int_equal(count[k], r[k].exceeded);
            assert_int_equal(where[k], r[k].peak_element);
        }
        assert_true(el_time[0] == (cases[c].exceeded ? cases[c].first : -1.0));
        assert_true(el_time[1] == (cases[c].exceeded == 2 ? 1.0 : -1.0));
        assert_true(el_time[2] == -1.0 && el_time[3] == -1.0);
        hid_t a = H5Aopen(f, "overloaded_elements", H5P_DEFAULT);
        assert_true(a >= 0);
        assert_true(H5Aread(a, H5T_NATIVE_DOUBLE, &total) >= 0);
        H5Aclose(a);
        assert_true(total == cases[c].exceeded);
        assert_int_equal(H5Aexists(f, "overload") > 0, cases[c].exceeded > 0);
        H5Fclose(f);
        fem_model_free(&m);
    }
}

/* Dynamic steps k0+1 .. k1 with the monitor (and its peak tracking) of every step. */
static void dynamic_steps(fem_analysis *s, fem_output *o, int k0, int k1)
{
    nc_error err;
    for (int k = k0 + 1; k <= k1; k++) {
        if (fem_analysis_step(s, s->m->settings.dt_s, &err)) fail_msg("step %d: %s", k, err.message);
        s->cur.time_s = k * s->m->settings.dt_s;
        fem_analysis_update_axial(s);
        if (fem_output_monitor(o, s, s->cur.time_s, &err)) fail_msg("%s", err.message);
    }
}

static void test_checkpoint_resume(void **state)
{
    (void)state;
    enum { K_CK = 14, K_END = 200 };
    fem_model m;
    build(&m, 50e3, FEM_DYNAMIC);   /* the overshoot (nearly 80 kN) exceeds it, 40 kN does not */
    char dir[600];
    out_dir("dynamic", dir, sizeof dir);
    nc_error err;
    fem_analysis a, b;
    fem_output oa, ob;
    assert_int_equal(fem_analysis_init(&a, &m, &err), 0);
    assert_int_equal(fem_analysis_initial_acceleration(&a, &err), 0);
    if (fem_output_open(&oa, &m, dir, &err) || fem_output_monitor(&oa, &a, 0.0, &err) ||
        fem_output_step(&oa, &a, 0.0, &err))
        fail_msg("%s", err.message);
    dynamic_steps(&a, &oa, 0, K_CK);
    if (fem_checkpoint_save(dir, "ck", K_CK, a.cur.time_s, &a, &oa, NULL, &err)) fail_msg("%s", err.message);
    fem_set_overload at_ck[3], ra[3], rb[3];
    int n_ck = fem_output_overload(&oa, &m, at_ck);
    dynamic_steps(&a, &oa, K_CK, K_END);
    int na = fem_output_overload(&oa, &m, ra);
    double t_ck = K_CK * m.settings.dt_s;
    /* the overshoot exceeds the breaking loads in elements 0 (rope) and 2 (tail) before the
     * checkpoint (1.3 ms), in element 1 (rope) after it (1.6 ms); the peak comes later still */
    assert_int_equal(n_ck, 2);
    assert_int_equal(at_ck[0].exceeded, 1);
    assert_int_equal(at_ck[1].exceeded, 1);
    assert_int_equal(na, 3);
    assert_int_equal(ra[0].exceeded, 2);
    assert_true(ra[0].first_time_s < t_ck && ra[0].peak_time_s > t_ck);
    assert_true(ra[0].peak_n > 1.5 * 4 * P_N);
    fem_output_close(&oa);

    memset(&ob, 0, sizeof ob);
    ob.max_u_node = -1;
    assert_int_equal(fem_analysis_init(&b, &m, &err), 0);
    if (fem_checkpoint_load(dir, "ck", K_CK, t_ck, &b, &ob, NULL, &err) ||
        fem_output_reopen(&ob, &m, dir, &err))
        fail_msg("%s", err.message);
    fem_set_overload rb_ck[3];
    assert_int_equal(fem_output_overload(&ob, &m, rb_ck), n_ck);
    assert_memory_equal(rb_ck, at_ck, sizeof at_ck);
    dynamic_steps(&b, &ob, K_CK, K_END);
    assert_int_equal(fem_output_overload(&ob, &m, rb), na);
    assert_memory_equal(rb, ra, sizeof ra);
    assert_memory_equal(b.cur.u, a.cur.u, (size_t)a.ndof * sizeof *a.cur.u);
    fem_output_close(&ob);
    fem_analysis_free(&a);
    fem_analysis_free(&b);
    fem_model_free(&m);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_static_closed_form),
        cmocka_unit_test(test_checkpoint_resume),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
