/* test_checkpoint — the checkpoint table of common/nc_checkpoint.h: a round trip keeps every
 * value bit for bit (NaN payloads, ±0, subnormals, infinities, the int64 and size_t extremes,
 * strided rows); a file without an entry, or with another count, is refused naming the file
 * and the entry and changes nothing; a save that fails (a file size limit: the write itself
 * fails; a folder that does not exist) leaves the previous file as it was and no .tmp; the
 * two pruning rules delete exactly the older files of their own prefix.
 */
#include <errno.h>
#include <float.h>
#include <limits.h>
#include <math.h>
#include <setjmp.h>
#include <signal.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <unistd.h>
#include <cmocka.h>

#include "nc_checkpoint.h"
#include "nc_file.h"

static void tmp_dir(const char *leaf, char *out, size_t size)
{
    const char *base = getenv("NC_TMP") ? getenv("NC_TMP") : "/tmp";
    snprintf(out, size, "%s/ckpt_%s", base, leaf);
    nc_error err;
    assert_int_equal(nc_file_make_dirs(out, &err), 0);
}

static int exists(const char *dir, const char *name)
{
    char path[1200];
    snprintf(path, sizeof path, "%s/%s", dir, name);
    struct stat st;
    return stat(path, &st) == 0;
}

static double from_bits(uint64_t b)
{
    double x;
    memcpy(&x, &b, sizeof x);
    return x;
}

/* Every kind of value a checkpoint holds, and a copy to load into. */
typedef struct values {
    double f[10];
    int32_t i32[3];
    int in[3];
    long lg[3];
    int64_t i64[3];
    size_t sz[2];
    uint8_t u8[3];
    struct { double xyz[3]; int tag; } rows[4];   /* strided: xyz of each row */
} values;

static void fill(values *v)
{
    memset(v, 0, sizeof *v);
    double f[10] = {from_bits(0x7ff8000000000123ull),   /* quiet NaN with a payload */
                    from_bits(0xfff4000000000001ull),   /* signalling NaN, sign set */
                    0.0, -0.0, DBL_TRUE_MIN, -DBL_MIN / 3.0, INFINITY, -INFINITY, DBL_MAX,
                    0.1 + 0.2};
    memcpy(v->f, f, sizeof f);
    v->i32[0] = INT32_MIN; v->i32[1] = INT32_MAX; v->i32[2] = -1;
    v->in[0] = INT32_MIN; v->in[1] = 0; v->in[2] = INT32_MAX;
    v->lg[0] = LONG_MIN; v->lg[1] = LONG_MAX; v->lg[2] = 42;
    v->i64[0] = INT64_MIN; v->i64[1] = INT64_MAX; v->i64[2] = (int64_t)1 << 53 | 1;
    v->sz[0] = SIZE_MAX; v->sz[1] = ((size_t)1 << 53) + 1;   /* not exact in a double */
    v->u8[0] = 0; v->u8[1] = 255; v->u8[2] = 128;
    for (int r = 0; r < 4; r++) {
        for (int c = 0; c < 3; c++) v->rows[r].xyz[c] = from_bits(0x3ff0000000000001ull + 7u * (unsigned)(3 * r + c));
        v->rows[r].tag = 1000 + r;
    }
}

static void entries(nc_ckpt_table *t, values *v)
{
    nc_ckpt_f64(t, "floats", "special", v->f, 10);
    nc_ckpt_add(t, "ints", "i32", NC_CKPT_I32, v->i32, 3);
    nc_ckpt_add(t, "ints", "int", NC_CKPT_INT, v->in, 3);
    nc_ckpt_add(t, "ints", "long", NC_CKPT_LONG, v->lg, 3);
    nc_ckpt_add(t, "/ints", "/i64", NC_CKPT_I64, v->i64, 3);
    nc_ckpt_add(t, NULL, "ints/size", NC_CKPT_SIZE, v->sz, 2);
    nc_ckpt_add(t, "deep/er/group", "u8", NC_CKPT_U8, v->u8, 3);
    nc_ckpt_add_rows(t, "rows", "xyz", NC_CKPT_F64, v->rows[0].xyz, 4, 3, sizeof v->rows[0]);
    nc_ckpt_f64(t, "floats", "none", NULL, 0);
}

static void test_round_trip_bit_for_bit(void **state)
{
    (void)state;
    char dir[900], path[1000];
    tmp_dir("round_trip", dir, sizeof dir);
    snprintf(path, sizeof path, "%s/x_rt.h5", dir);
    values a, b;
    fill(&a);
    memset(&b, 0x5a, sizeof b);
    for (int r = 0; r < 4; r++) b.rows[r].tag = -r;   /* between the strided values: kept */
    nc_ckpt_table ta = {0}, tb = {0};
    entries(&ta, &a);
    entries(&tb, &b);
    nc_error err;
    if (nc_ckpt_save(&ta, path, &err)) fail_msg("%s", err.message);
    assert_false(exists(dir, "x_rt.h5.tmp"));
    if (nc_ckpt_load(&tb, path, &err)) fail_msg("%s", err.message);
    assert_memory_equal(a.f, b.f, sizeof a.f);
    assert_memory_equal(a.i32, b.i32, sizeof a.i32);
    assert_memory_equal(a.in, b.in, sizeof a.in);
    assert_memory_equal(a.lg, b.lg, sizeof a.lg);
    assert_memory_equal(a.i64, b.i64, sizeof a.i64);
    assert_memory_equal(a.sz, b.sz, sizeof a.sz);
    assert_memory_equal(a.u8, b.u8, sizeof a.u8);
    for (int r = 0; r < 4; r++) {
        assert_memory_equal(a.rows[r].xyz, b.rows[r].xyz, sizeof a.rows[r].xyz);
        assert_int_equal(b.rows[r].tag, -r);
    }
    /* one value before the table is built */
    int64_t top = 0;
    assert_int_equal(nc_ckpt_read_scalar(path, "/ints/i64", NC_CKPT_I64, &top, &err), -1);
    assert_non_null(strstr(err.message, "/ints/i64"));   /* 3 values, not one */
    long l = 0;
    nc_ckpt_table one = {0};
    nc_ckpt_long(&one, "ints", "long", &l);
    assert_int_equal(nc_ckpt_load(&one, path, &err), -1);
    nc_ckpt_table_free(&one);
    /* the rows are stored as [rows, width] */
    nc_ckpt_table flat = {0};
    double xyz[12];
    nc_ckpt_f64(&flat, "rows", "xyz", xyz, 12);
    assert_int_equal(nc_ckpt_load(&flat, path, &err), -1);
    assert_non_null(strstr(err.message, "/rows/xyz"));
    nc_ckpt_table_free(&flat);
    nc_ckpt_table_free(&ta);
    nc_ckpt_table_free(&tb);
}

static void test_missing_entry_and_wrong_count(void **state)
{
    (void)state;
    char dir[900], path[1000];
    tmp_dir("refused", dir, sizeof dir);
    snprintf(path, sizeof path, "%s/x_ref.h5", dir);
    values a, b;
    fill(&a);
    nc_ckpt_table t = {0};
    entries(&t, &a);
    nc_error err;
    assert_int_equal(nc_ckpt_save(&t, path, &err), 0);
    nc_ckpt_table_free(&t);

    /* an entry the file does not have: refused, and nothing loaded */
    memset(&b, 0, sizeof b);
    double extra = 7.0;
    entries(&t, &b);
    nc_ckpt_f64(&t, "floats", "added_later", &extra, 1);
    assert_int_equal(nc_ckpt_load(&t, path, &err), -1);
    assert_non_null(strstr(err.message, path));
    assert_non_null(strstr(err.message, "/floats/added_later"));
    values zero;
    memset(&zero, 0, sizeof zero);
    assert_memory_equal(&b, &zero, sizeof b);
    assert_true(extra == 7.0);
    nc_ckpt_table_free(&t);

    /* another count (a model with another size) */
    double u[11];
    nc_ckpt_f64(&t, "floats", "special", u, 11);
    assert_int_equal(nc_ckpt_load(&t, path, &err), -1);
    assert_non_null(strstr(err.message, path));
    assert_non_null(strstr(err.message, "/floats/special"));
    assert_non_null(strstr(err.message, "10"));
    assert_non_null(strstr(err.message, "11"));
    nc_ckpt_table_free(&t);

    /* another kind: an integer entry read as doubles */
    double as_f[3];
    nc_ckpt_f64(&t, "ints", "long", as_f, 3);
    assert_int_equal(nc_ckpt_load(&t, path, &err), -1);
    assert_non_null(strstr(err.message, "/ints/long"));
    nc_ckpt_table_free(&t);

    /* no file; a file that is not HDF5 */
    char none[1100];
    snprintf(none, sizeof none, "%s/missing.h5", dir);
    nc_ckpt_f64(&t, "floats", "special", u, 10);
    assert_int_equal(nc_ckpt_load(&t, none, &err), -1);
    assert_non_null(strstr(err.message, none));
    assert_non_null(strstr(err.message, "No such file"));
    assert_int_equal(nc_file_write_line(none, "not a checkpoint", &err), 0);
    assert_int_equal(nc_ckpt_load(&t, none, &err), -1);
    assert_non_null(strstr(err.message, none));
    nc_ckpt_table_free(&t);

    /* a name too long: the add is kept as a failure, save and load refuse naming the file */
    char long_name[200];
    memset(long_name, 'n', sizeof long_name - 1);
    long_name[sizeof long_name - 1] = '\0';
    nc_ckpt_f64(&t, "floats", long_name, u, 1);
    nc_ckpt_f64(&t, "floats", "special", u, 10);
    assert_true(t.failed);
    assert_int_equal(nc_ckpt_save(&t, path, &err), -1);
    assert_non_null(strstr(err.message, path));
    assert_int_equal(nc_ckpt_load(&t, path, &err), -1);
    nc_ckpt_table_free(&t);
}

static void test_failed_save_keeps_previous(void **state)
{
    (void)state;
    char dir[900], path[1000];
    tmp_dir("failed_save", dir, sizeof dir);
    snprintf(path, sizeof path, "%s/x_prev.h5", dir);
    values a;
    fill(&a);
    nc_ckpt_table t = {0};
    entries(&t, &a);
    nc_error err;
    assert_int_equal(nc_ckpt_save(&t, path, &err), 0);
    struct stat before;
    assert_int_equal(stat(path, &before), 0);

    /* a larger checkpoint whose write fails (file size limit: EFBIG, also for root) */
    size_t n_big = 1u << 17;
    double *big = malloc(n_big * sizeof *big);
    assert_non_null(big);
    for (size_t i = 0; i < n_big; i++) big[i] = (double)i;
    nc_ckpt_f64(&t, "big", "values", big, n_big);
    struct rlimit old, small;
    assert_int_equal(getrlimit(RLIMIT_FSIZE, &old), 0);
    small = old;
    small.rlim_cur = (rlim_t)before.st_size + 4096;
    void (*prev)(int) = signal(SIGXFSZ, SIG_IGN);
    assert_int_equal(setrlimit(RLIMIT_FSIZE, &small), 0);
    int rc = nc_ckpt_save(&t, path, &err);
    assert_int_equal(setrlimit(RLIMIT_FSIZE, &old), 0);
    signal(SIGXFSZ, prev);
    assert_int_equal(rc, -1);
    print_message("expected error: %s\n", err.message);
    assert_non_null(strstr(err.message, "x_prev.h5"));
    assert_non_null(strstr(err.message, strerror(EFBIG)));
    assert_false(exists(dir, "x_prev.h5.tmp"));
    /* the previous checkpoint is there, whole */
    struct stat after;
    assert_int_equal(stat(path, &after), 0);
    assert_int_equal(after.st_size, before.st_size);
    nc_ckpt_table_free(&t);
    values b;
    memset(&b, 0, sizeof b);
    entries(&t, &b);
    if (nc_ckpt_load(&t, path, &err)) fail_msg("%s", err.message);
    assert_memory_equal(a.f, b.f, sizeof a.f);
    nc_ckpt_table_free(&t);
    free(big);

    /* a folder that does not exist */
    char missing[1100];
    snprintf(missing, sizeof missing, "%s/no_such_folder/x.h5", dir);
    entries(&t, &a);
    assert_int_equal(nc_ckpt_save(&t, missing, &err), -1);
    assert_non_null(strstr(err.message, "no_such_folder/x.h5"));
    assert_non_null(strstr(err.message, strerror(ENOENT)));
    /* a folder that cannot be written (only without root's rights) */
    if (geteuid() != 0) {
        char ro[1000], in_ro[1100];
        tmp_dir("read_only", ro, sizeof ro);
        snprintf(in_ro, sizeof in_ro, "%s/x.h5", ro);
        assert_int_equal(chmod(ro, 0555), 0);
        assert_int_equal(nc_ckpt_save(&t, in_ro, &err), -1);
        assert_non_null(strstr(err.message, in_ro));
        assert_non_null(strstr(err.message, strerror(EACCES)));
        assert_int_equal(chmod(ro, 0755), 0);
        assert_false(exists(ro, "x.h5.tmp"));
        assert_false(exists(ro, "x.h5"));
    }
    nc_ckpt_table_free(&t);
}

/* A checkpoint of `step` named prefix_<name>.h5 in dir. */
static void save_step(const char *dir, const char *file, long step)
{
    char path[1200];
    snprintf(path, sizeof path, "%s/%s", dir, file);
    nc_ckpt_table t = {0};
    nc_ckpt_long(&t, "header", "step", &step);
    nc_error err;
    if (nc_ckpt_save(&t, path, &err)) fail_msg("%s", err.message);
    nc_ckpt_table_free(&t);
}

static void test_pruning(void **state)
{
    (void)state;
    char dir[900];
    tmp_dir("prune", dir, sizeof dir);
    nc_error err;
    char path[1200];
    /* by step: keep the one just written and the newest one before it */
    for (long s = 1; s <= 6; s++) {
        char f[64];
        snprintf(f, sizeof f, "p_step_%ld.h5", s);
        save_step(dir, f, s);
    }
    save_step(dir, "p_later.h5", 40);                    /* a later step: left alone */
    snprintf(path, sizeof path, "%s/p_broken.h5", dir);  /* unreadable: left alone */
    assert_int_equal(nc_file_write_line(path, "not hdf5", &err), 0);
    save_step(dir, "q_step_1.h5", 1);                    /* another program's */
    nc_ckpt_prune_by_step(dir, "p_", "p_step_5.h5", "/header/step", 5, 1);
    assert_false(exists(dir, "p_step_1.h5"));
    assert_false(exists(dir, "p_step_2.h5"));
    assert_false(exists(dir, "p_step_3.h5"));
    assert_true(exists(dir, "p_step_4.h5"));
    assert_true(exists(dir, "p_step_5.h5"));
    assert_true(exists(dir, "p_step_6.h5"));             /* step 6 > 5 */
    assert_true(exists(dir, "p_later.h5"));
    assert_true(exists(dir, "p_broken.h5"));
    assert_true(exists(dir, "q_step_1.h5"));
    nc_ckpt_prune_by_step(dir, "p_", "p_step_6.h5", "/header/step", 6, 2);
    assert_true(exists(dir, "p_step_4.h5"));
    assert_true(exists(dir, "p_step_5.h5"));
    nc_ckpt_prune_by_step(dir, "p_", "p_step_6.h5", "/header/step", 6, 0);
    assert_false(exists(dir, "p_step_4.h5"));
    assert_false(exists(dir, "p_step_5.h5"));
    assert_true(exists(dir, "p_step_6.h5"));

    /* by name: exactly the files named stay, leftovers of a crash go */
    save_step(dir, "r_a.h5", 1);
    save_step(dir, "r_b.h5", 2);
    save_step(dir, "r_c.h5", 3);
    snprintf(path, sizeof path, "%s/r_d.h5.tmp", dir);
    assert_int_equal(nc_file_write_line(path, "half", &err), 0);
    snprintf(path, sizeof path, "%s/r_notes.txt", dir);
    assert_int_equal(nc_file_write_line(path, "not a checkpoint", &err), 0);
    const char *keep[3] = {"r_c.h5", NULL, "r_b.h5"};
    nc_ckpt_prune_except(dir, "r_", keep, 3);
    assert_false(exists(dir, "r_a.h5"));
    assert_true(exists(dir, "r_b.h5"));
    assert_true(exists(dir, "r_c.h5"));
    assert_false(exists(dir, "r_d.h5.tmp"));
    assert_true(exists(dir, "r_notes.txt"));
    assert_true(exists(dir, "q_step_1.h5"));
    assert_true(exists(dir, "p_step_6.h5"));
}

static void test_durable_text(void **state)
{
    (void)state;
    char dir[900], path[1000];
    tmp_dir("text", dir, sizeof dir);
    snprintf(path, sizeof path, "%s/latest.json", dir);
    nc_error err;
    const char *a = "{\"checkpoint\": \"step_000001\"}\n", *b = "{\"checkpoint\": \"step_000002\"}\n";
    assert_int_equal(nc_file_write_durably(path, a, strlen(a), &err), 0);
    assert_int_equal(nc_file_write_durably(path, b, strlen(b), &err), 0);
    FILE *f = fopen(path, "r");
    assert_non_null(f);
    char buf[100] = {0};
    assert_int_equal(fread(buf, 1, sizeof buf - 1, f), strlen(b));
    fclose(f);
    assert_string_equal(buf, b);
    assert_false(exists(dir, "latest.json.tmp"));
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_round_trip_bit_for_bit),
        cmocka_unit_test(test_missing_entry_and_wrong_count),
        cmocka_unit_test(test_failed_save_keeps_previous),
        cmocka_unit_test(test_pruning),
        cmocka_unit_test(test_durable_text),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
