/* dem_test_util — code shared by the dem_solver tests. */
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <setjmp.h>
#include <cmocka.h>

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
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
