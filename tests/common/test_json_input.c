/* test_json_input — what every JSON input refuses beyond cJSON's own syntax check: a key given
 * twice in one object (cJSON silently keeps the first) and a number beyond the range of a
 * double (cJSON keeps infinity and prints it as "null"), or too small for one (cJSON reads 1e-400
 * as 0; named with line and column); named with the file and the
 * path of the value, at any depth. Large arrays are checked once per object in O(k log k). */
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <setjmp.h>
#include <cmocka.h>

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "nc_json.h"

static void expect_refused(const char *text, const char *const *pieces)
{
    cJSON *root;
    nc_error err;
    if (nc_json_parse_text("in.json", text, strlen(text), &root, &err) == 0) {
        cJSON_Delete(root);
        fail_msg("accepted: %s", text);
    }
    for (const char *const *p = pieces; *p; p++)
        if (!strstr(err.message, *p)) fail_msg("message lacks \"%s\": %s", *p, err.message);
}

static void test_duplicate_keys(void **state)
{
    (void)state;
    static const char *const top[] = {"in.json: dt_s: key given twice", NULL};
    expect_refused("{\"dt_s\": 1e-5, \"end_time_s\": 1, \"dt_s\": 1e-3}", top);
    static const char *const deep[] = {"in.json: particles[1].radius: key given twice", NULL};
    expect_refused("{\"particles\": [{\"radius\": 1}, {\"radius\": 0.1, \"position\": [0,0,0], \"radius\": 2}]}", deep);
    /* more than 8 keys: the sorted check */
    static const char *const many[] = {"analysis.k3: key given twice", NULL};
    expect_refused("{\"analysis\": {\"k1\":1,\"k2\":2,\"k3\":3,\"k4\":4,\"k5\":5,\"k6\":6,\"k7\":7,\"k8\":8,\"k9\":9,\"k3\":0}}", many);
    /* the same key in different objects is fine */
    const char *ok = "{\"a\": {\"x\": 1}, \"b\": {\"x\": 2}, \"c\": [{\"x\": 3}, {\"x\": 4}]}";
    cJSON *root;
    nc_error err;
    if (nc_json_parse_text("ok.json", ok, strlen(ok), &root, &err)) fail_msg("%s", err.message);
    cJSON_Delete(root);
}

static void test_underflowing_numbers(void **state)
{
    (void)state;
    /* 1e-400 would be read as 0 without a word: refused with its line and column */
    static const char *const tiny[] = {"in.json:2:11: number 1e-400 is too small", "read as 0", NULL};
    expect_refused("{\"a\": 1,\n  \"dt_s\": 1e-400}", tiny);
    static const char *const neg[] = {"in.json:1:11: number -2.5E-330", NULL};
    expect_refused("{\"x\": [1, -2.5E-330]}", neg);
    /* zero spelled with an exponent, the smallest normal double, numbers inside strings and a
     * string holding an escaped quote before a number stay accepted */
    const char *ok = "{\"a\": 0e-400, \"b\": 2.3e-308, \"c\": \"1e-400\", \"d\": \"q\\\"1e-999\", "
                     "\"e\": -0.0e-5000, \"f\": [true, false, null, 1e-307]}";
    cJSON *root;
    nc_error err;
    if (nc_json_parse_text("ok.json", ok, strlen(ok), &root, &err)) fail_msg("%s", err.message);
    cJSON_Delete(root);
}

static void test_out_of_range_numbers(void **state)
{
    (void)state;
    static const char *const big[] = {"in.json: analysis.dt_s: number out of range", NULL};
    expect_refused("{\"analysis\": {\"dt_s\": 1e400}}", big);
    static const char *const neg[] = {"in.json: nodes[2][1]: number out of range", NULL};
    expect_refused("{\"nodes\": [[0,0,0], [1,0,0], [2,-1e999,0]]}", neg);
    /* the largest doubles are still numbers */
    const char *ok = "{\"a\": 1.7e308, \"b\": -1.7e308, \"c\": 1e-300}";
    cJSON *root;
    nc_error err;
    if (nc_json_parse_text("ok.json", ok, strlen(ok), &root, &err)) fail_msg("%s", err.message);
    double a;
    assert_int_equal(nc_json_number(root, "ok.json", "a", &a, &err), 0);
    cJSON_Delete(root);
    /* a tree built in code (not parsed) holding infinity: the getter says "out of range" */
    cJSON *built = cJSON_CreateObject();
    cJSON_AddNumberToObject(built, "dt_s", 1e308 * 10.0);
    assert_int_equal(nc_json_number(built, "x.json", "dt_s", &a, &err), -1);
    if (!strstr(err.message, "x.json: dt_s: expected a number, got a number out of range"))
        fail_msg("%s", err.message);
    cJSON_Delete(built);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_duplicate_keys),
        cmocka_unit_test(test_out_of_range_numbers),
        cmocka_unit_test(test_underflowing_numbers),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
