/* test_config_limits — coupler.json: a dt below 1e6 float spacings of the run's times is
 * refused (start_time 1e17 with dt 1e-3 used to run forever at t = 1e17), so is a run of more
 * than 1e9 steps; a duplicate key and 1e400 are named through the file reader. */
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <setjmp.h>
#include <cmocka.h>

#include <stdio.h>
#include <string.h>

#include "../../coupler/cpl_config.h"
#include "nc_json.h"

static int parse(const char *text, nc_error *err)
{
    cJSON *root;
    if (nc_json_parse_text("coupler.json", text, strlen(text), &root, err)) return -1;
    cpl_config c;
    cpl_config_default(&c);
    int rc = cpl_config_parse(&c, root, "coupler.json", "/case", err);
    cJSON_Delete(root);
    return rc;
}

static void expect(const char *text, const char *const *pieces)
{
    nc_error err;
    if (parse(text, &err) == 0) fail_msg("accepted: %s", text);
    for (const char *const *p = pieces; *p; p++)
        if (!strstr(err.message, *p)) fail_msg("message lacks \"%s\": %s", *p, err.message);
}

static void test_time_limits(void **state)
{
    (void)state;
    static const char *const late[] = {"coupler.json: dt", "too small for times up to 1e+17", NULL};
    expect("{\"scheme\": \"weak\", \"dt\": 0.001, \"start_time\": 1e17, \"end_time\": 1.00000001e17}", late);
    static const char *const many[] = {"coupler.json: dt", "2e+09 steps", NULL};
    expect("{\"scheme\": \"weak\", \"dt\": 1e-5, \"end_time\": 2e4}", many);
    static const char *const dup[] = {"coupler.json: dt: key given twice", NULL};
    expect("{\"scheme\": \"weak\", \"dt\": 1e-3, \"end_time\": 1, \"dt\": 1e-4}", dup);
    static const char *const big[] = {"coupler.json: end_time: number out of range", NULL};
    expect("{\"scheme\": \"weak\", \"dt\": 1e-3, \"end_time\": 1e400}", big);
    nc_error err;
    if (parse("{\"scheme\": \"strong\", \"dt\": 1e-3, \"start_time\": 100, \"end_time\": 101}", &err))
        fail_msg("%s", err.message);
}

int main(void)
{
    const struct CMUnitTest tests[] = {cmocka_unit_test(test_time_limits)};
    return cmocka_run_group_tests(tests, NULL, NULL);
}
