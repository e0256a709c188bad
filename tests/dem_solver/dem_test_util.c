/* dem_test_util — code shared by the dem_solver tests. */
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <setjmp.h>
#include <cmocka.h>

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/types.h>
#include <unistd.h>

#include "dem_test_util.h"

int dem_test_try_build(dem_sim *s, const char *json, nc_error *err)
{
    dem_sim_init(s);
    nc_error_clear(err);
    if (dem_config_parse_string(s, json, "test.json", ".", err)) return -1;
    return dem_sim_prepare(s, err);
}

void dem_test_build(dem_sim *s, const char *json)
{
    nc_error err;
    if (dem_test_try_build(s, json, &err)) {
        print_error("build failed: %s\n", err.message);
        fail();
    }
}

const char *dem_test_write_file(char *buf, size_t size, const char *name, const void *text,
                                size_t length)
{
    const char *dir = getenv("NC_TMP");
    if (!dir || !dir[0]) dir = "/tmp";
    snprintf(buf, size, "%s/%s.%ld", dir, name, (long)getpid());
    FILE *f = fopen(buf, "wb");
    assert_non_null(f);
    assert_int_equal(fwrite(text, 1, length, f), length);
    fclose(f);
    return buf;
}

int dem_test_start_participant(const char *input, const char *outdir, char *endpoint,
                               size_t size)
{
    const char *bin = getenv("NC_BIN");
    assert_non_null(bin);
    char exe[600], epfile[700], log[700];
    snprintf(exe, sizeof exe, "%s/dem_solver", bin);
    snprintf(epfile, sizeof epfile, "%s.endpoint", outdir);
    snprintf(log, sizeof log, "%s.log", outdir);
    remove(epfile);
    pid_t pid = fork();
    assert_true(pid >= 0);
    if (pid == 0) {
        if (!freopen(log, "w", stdout)) _exit(126);
        execl(exe, exe, input, "--endpoint", "tcp://127.0.0.1:*", "--endpoint-file", epfile,
              "--output", outdir, "--idle-timeout", "60", (char *)NULL);
        _exit(127);
    }
    endpoint[0] = '\0';
    for (int k = 0; k < 300 && !endpoint[0]; k++) { /* sanitizer builds start slowly */
        FILE *e = fopen(epfile, "r");
        if (e) {
            if (!fgets(endpoint, (int)size, e)) endpoint[0] = '\0';
            fclose(e);
            endpoint[strcspn(endpoint, "\n")] = '\0';
        }
        if (!endpoint[0]) usleep(100000);
    }
    assert_true(endpoint[0] != '\0');
    return (int)pid;
}
