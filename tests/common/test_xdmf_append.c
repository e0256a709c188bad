/* test_xdmf_append — an XDMF file grown in place (nc_xdmf): after each append it is exactly the
 * head, every grid so far and the closing tags; an append that runs out of room (a file-size
 * limit standing in for a full disk: the write stops part way) leaves the file exactly as it
 * was before it, with a message naming the file and the reason; creating it again (a resumed
 * run) replaces it with the grids given. */
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <setjmp.h>
#include <cmocka.h>

#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <unistd.h>

#include "nc_xdmf.h"

static char path[256];
static const char HEAD[] = "<?xml version=\"1.0\" ?>\n<Xdmf Version=\"3.0\">\n <Domain>\n  <Grid>\n";
static const char TAIL[] = "  </Grid>\n </Domain>\n</Xdmf>\n";

static int setup(void **state)
{
    (void)state;
    const char *dir = getenv("NC_TMP") ? getenv("NC_TMP") : "/tmp";
    snprintf(path, sizeof path, "%s/test_xdmf_append_%d.xdmf", dir, (int)getpid());
    return 0;
}

static int teardown(void **state)
{
    (void)state;
    unlink(path);
    return 0;
}

/* The file's whole text (malloc'ed). */
static char *slurp(void)
{
    FILE *f = fopen(path, "rb");
    assert_non_null(f);
    static char buf[1 << 16];
    size_t n = fread(buf, 1, sizeof buf - 1, f);
    fclose(f);
    buf[n] = '\0';
    return strdup(buf);
}

static void assert_file_is(const char *grids)
{
    char expected[1 << 16];
    snprintf(expected, sizeof expected, "%s%s%s", HEAD, grids, TAIL);
    char *text = slurp();
    assert_string_equal(text, expected);
    free(text);
}

/* Appends grid to x, whose file listed the grids `before`, and checks that it lists both. */
static void append_after(nc_xdmf_file *x, const char *before, const char *grid)
{
    nc_error err;
    assert_int_equal(nc_xdmf_append(x, grid, strlen(grid), &err), 0);
    char all[4096];
    snprintf(all, sizeof all, "%s%s", before, grid);
    assert_file_is(all);
}

static void test_grows_in_place(void **state)
{
    (void)state;
    nc_xdmf_file x = {0};
    nc_error err;
    assert_int_equal(nc_xdmf_create(&x, path, HEAD, "", 0, TAIL, &err), 0);
    assert_file_is("");
    char grids[4096] = "";
    for (int k = 0; k < 5; k++) {
        char grid[200];
        int len = snprintf(grid, sizeof grid, "   <Grid Name=\"step%d\"><Time Value=\"%d\"/></Grid>\n", k, k);
        assert_int_equal(nc_xdmf_append(&x, grid, (size_t)len, &err), 0);
        strcat(grids, grid);
        assert_file_is(grids);   /* a complete document after every step */
    }
    /* created again with the first two grids only (a run resumed from a checkpoint) */
    const char *kept = "   <Grid Name=\"step0\"/>\n   <Grid Name=\"step1\"/>\n";
    assert_int_equal(nc_xdmf_create(&x, path, HEAD, kept, strlen(kept), TAIL, &err), 0);
    assert_file_is(kept);
    append_after(&x, kept, "   <Grid Name=\"step2\"/>\n");
    nc_xdmf_close(&x);
    nc_xdmf_close(&x);   /* twice is harmless */
    assert_int_not_equal(nc_xdmf_append(&x, "x", 1, &err), 0);
    assert_non_null(strstr(err.message, path));
}

static void test_failed_append_keeps_the_file(void **state)
{
    (void)state;
    nc_xdmf_file x = {0};
    nc_error err;
    const char *first = "   <Grid Name=\"step0\"/>\n";
    assert_int_equal(nc_xdmf_create(&x, path, HEAD, first, strlen(first), TAIL, &err), 0);
    off_t size = (off_t)(strlen(HEAD) + strlen(first) + strlen(TAIL));
    /* room for 10 more bytes: the next step's grid and tags (60 bytes) stop part way */
    struct rlimit old, lim;
    getrlimit(RLIMIT_FSIZE, &old);
    lim = old;
    lim.rlim_cur = (rlim_t)size + 10;
    void (*was)(int) = signal(SIGXFSZ, SIG_IGN);
    assert_int_equal(setrlimit(RLIMIT_FSIZE, &lim), 0);
    int rc = nc_xdmf_append(&x, "   <Grid Name=\"step1\"><Time Value=\"1\"/></Grid>\n", 48, &err);
    setrlimit(RLIMIT_FSIZE, &old);
    signal(SIGXFSZ, was);
    assert_int_not_equal(rc, 0);
    assert_non_null(strstr(err.message, path));
    assert_non_null(strstr(err.message, "still lists the steps before it"));
    assert_file_is(first);
    /* with room again, the next step is added after the ones before */
    append_after(&x, first, "   <Grid Name=\"step1\"/>\n");
    nc_xdmf_close(&x);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test_setup_teardown(test_grows_in_place, setup, teardown),
        cmocka_unit_test_setup_teardown(test_failed_append_keeps_the_file, setup, teardown),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
