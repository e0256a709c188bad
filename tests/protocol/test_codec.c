/* Tests of the protocol codec: round trips and every class of malformed input. */
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

#include "proto.h"

#define LIMIT (1u << 20)

/* Decodes a hand-written header with the given frames; returns rc, message in err. */
static int decode_text(proto_message *m, const char *header, const void *const *frames,
                       const size_t *lengths, size_t n, nc_error *err)
{
    return proto_decode(m, header, strlen(header), frames, lengths, n, LIMIT, err);
}

/* Writes the header of a SOLVE carrying one f64 array "u" of n values. */
static void u_header(char *header, size_t size, size_t n)
{
    snprintf(header, size, "{\"type\":\"solve\",\"version\":1,\"arrays\":[{\"name\":\"u\",\"dtype\":\"f64\",\"shape\":[%zu]}]}", n);
}

static void test_round_trip(void **state)
{
    (void)state;
    double force[6] = {1.0, -2.5, 3e-300, 1e300, -0.0, 42.0};
    int32_t elements[4] = {0, 1, 1, 2};
    proto_message out, in;
    memset(&out, 0, sizeof out);
    memset(&in, 0, sizeof in);
    proto_message_init(&out, PROTO_MSG_SOLVE);
    out.step = 12;
    out.iteration = 3;
    out.time_s = 0.0125;
    out.dt_s = 1e-3;
    nc_error err;
    assert_int_equal(proto_message_add_f64(&out, "force", force, 2, 3, &err), 0);
    assert_int_equal(proto_message_add_i32(&out, "elements", elements, 2, 2, &err), 0);
    assert_int_equal(proto_message_set_value(&out, "near_interface", 1.0, &err), 0);
    assert_int_equal(proto_message_set_value(&out, "min_gap_m", -1.5e-3, &err), 0);

    char *header;
    size_t length;
    assert_int_equal(proto_encode_header(&out, &header, &length, &err), 0);
    const void *frames[2] = {force, elements};
    size_t lengths[2] = {sizeof force, sizeof elements};
    assert_int_equal(proto_decode(&in, header, length, frames, lengths, 2, LIMIT, &err), 0);
    free(header);

    assert_int_equal(in.type, PROTO_MSG_SOLVE);
    assert_int_equal(in.step, 12);
    assert_int_equal(in.iteration, 3);
    assert_near(in.time_s, 0.0125, 0.0); /* exact: cJSON prints 17 significant digits */
    assert_near(in.dt_s, 1e-3, 0.0);
    const double *f;
    size_t rows;
    assert_int_equal(proto_message_get_f64(&in, "force", 2, 3, &f, &rows, &err), 0);
    assert_int_equal(rows, 2);
    assert_memory_equal(f, force, sizeof force); /* bit-exact, including -0.0 */
    assert_ptr_not_equal(f, force);              /* decoded into owned storage */
    const int32_t *e;
    assert_int_equal(proto_message_get_i32(&in, "elements", 2, 2, &e, NULL, &err), 0);
    assert_memory_equal(e, elements, sizeof elements);
    assert_near(proto_message_value(&in, "near_interface", 0.0), 1.0, 0.0);
    assert_near(proto_message_value(&in, "min_gap_m", 0.0), -1.5e-3, 0.0);
    assert_near(proto_message_value(&in, "absent", 7.0), 7.0, 0.0);

    /* wrong expectations are reported with the array's name */
    assert_int_equal(proto_message_get_f64(&in, "force", 3, 3, &f, NULL, &err), -1);
    assert_non_null(strstr(err.message, "'force'"));
    assert_int_equal(proto_message_get_f64(&in, "elements", 0, 0, &f, NULL, &err), -1);
    assert_non_null(strstr(err.message, "i32"));
    assert_int_equal(proto_message_get_f64(&in, "velocity", 0, 0, &f, NULL, &err), -1);
    assert_non_null(strstr(err.message, "missing"));
    proto_message_free(&in);
}

static void test_round_trip_text_fields(void **state)
{
    (void)state;
    proto_message out, in;
    memset(&out, 0, sizeof out);
    memset(&in, 0, sizeof in);
    proto_message_init(&out, PROTO_MSG_ERROR);
    out.is_reply = 1;
    snprintf(out.text, sizeof out.text,
             "Newton did not converge: \"residual\" = 3e-2\n\tpath C:\\x \x01 \xc2\xb5m (UTF-8 kept)");
    snprintf(out.role, sizeof out.role, "fem");
    char *header;
    size_t length;
    nc_error err;
    assert_int_equal(proto_encode_header(&out, &header, &length, &err), 0);
    assert_int_equal(proto_decode(&in, header, length, NULL, NULL, 0, LIMIT, &err), 0);
    free(header);
    assert_int_equal(in.type, PROTO_MSG_ERROR);
    assert_int_equal(in.is_reply, 1);
    assert_string_equal(in.text, out.text);
    assert_string_equal(in.role, "fem");
    assert_int_equal(in.n_arrays, 0);
}

static void test_empty_array(void **state)
{
    (void)state;
    proto_message in;
    memset(&in, 0, sizeof in);
    nc_error err;
    const void *frames[1] = {""};
    size_t lengths[1] = {0};
    assert_int_equal(decode_text(&in, "{\"type\":\"solve\",\"version\":1,\"arrays\":[{\"name\":\"force\",\"dtype\":\"f64\",\"shape\":[0,3]}]}",
                                 frames, lengths, 1, &err), 0);
    assert_int_equal(in.arrays[0].count, 0);
    proto_message_free(&in);
}

/* Each malformed header must be rejected with a message containing `expect`. */
static void expect_reject(const char *header, const void *const *frames, const size_t *lengths,
                          size_t n, const char *expect, int code)
{
    proto_message in;
    memset(&in, 0, sizeof in);
    nc_error err;
    nc_error_clear(&err);
    int rc = decode_text(&in, header, frames, lengths, n, &err);
    if (rc != -1 || !strstr(err.message, expect) || err.code != code)
        fail_msg("header %s: rc %d, code %d, message '%s' (expected '%s')", header, rc, err.code,
                 err.message, expect);
    assert_int_equal(in.n_arrays, 0);
    proto_message_free(&in);
}

static void test_malformed_headers(void **state)
{
    (void)state;
    expect_reject("{\"type\":\"solve\"", NULL, NULL, 0, "not valid JSON", PROTO_ERR_DECODE);
    expect_reject("[1,2]", NULL, NULL, 0, "not a JSON object", PROTO_ERR_DECODE);
    expect_reject("{\"version\":1}", NULL, NULL, 0, "no 'type'", PROTO_ERR_DECODE);
    expect_reject("{\"type\":\"explode\",\"version\":1}", NULL, NULL, 0, "unknown message type 'explode'", PROTO_ERR_DECODE);
    expect_reject("{\"type\":7,\"version\":1}", NULL, NULL, 0, "'type'", PROTO_ERR_DECODE);
    expect_reject("{\"type\":\"solve\"}", NULL, NULL, 0, "no 'version'", PROTO_ERR_DECODE);
    expect_reject("{\"type\":\"solve\",\"version\":3}", NULL, NULL, 0, "version mismatch", PROTO_ERR_VERSION);
    expect_reject("{\"type\":\"solve\",\"version\":1,\"step\":1.5}", NULL, NULL, 0, "'step'", PROTO_ERR_DECODE);
    expect_reject("{\"type\":\"solve\",\"version\":1,\"step\":\"3\"}", NULL, NULL, 0, "'step'", PROTO_ERR_DECODE);
    expect_reject("{\"type\":\"solve\",\"version\":1,\"iteration\":-2}", NULL, NULL, 0, "'iteration'", PROTO_ERR_DECODE);
    expect_reject("{\"type\":\"solve\",\"version\":1,\"time\":\"now\"}", NULL, NULL, 0, "'time'", PROTO_ERR_DECODE);
    expect_reject("{\"type\":\"solve\",\"version\":1,\"dt\":1e999}", NULL, NULL, 0, "'dt'", PROTO_ERR_DECODE);
    expect_reject("{\"type\":\"solve\",\"version\":1,\"status\":\"maybe\"}", NULL, NULL, 0, "'status'", PROTO_ERR_DECODE);
    expect_reject("{\"type\":\"solve\",\"version\":1,\"reply\":1}", NULL, NULL, 0, "'reply'", PROTO_ERR_DECODE);
    expect_reject("{\"type\":\"solve\",\"version\":1,\"values\":{\"a\":\"x\"}}", NULL, NULL, 0, "value 'a'", PROTO_ERR_DECODE);
    expect_reject("{\"type\":\"solve\",\"version\":1,\"values\":[1]}", NULL, NULL, 0, "'values'", PROTO_ERR_DECODE);
    expect_reject("{\"type\":\"solve\",\"version\":1,\"arrays\":{}}", NULL, NULL, 0, "'arrays'", PROTO_ERR_DECODE);

    char long_text[PROTO_TEXT_MAX + 64];
    snprintf(long_text, sizeof long_text, "{\"type\":\"error\",\"version\":1,\"text\":\"%0*d\"}", PROTO_TEXT_MAX + 5, 0);
    expect_reject(long_text, NULL, NULL, 0, "longer than", PROTO_ERR_DECODE);
}

static void test_malformed_arrays(void **state)
{
    (void)state;
    double data[6] = {0};
    const void *one[1] = {data};
    size_t len48[1] = {48};
    size_t len40[1] = {40};
    /* frame count differs from descriptors */
    expect_reject("{\"type\":\"solve\",\"version\":1,\"arrays\":[]}", one, len48, 1, "describes 0 arrays but the message has 1", PROTO_ERR_DECODE);
    expect_reject("{\"type\":\"solve\",\"version\":1,\"arrays\":[{\"name\":\"f\",\"dtype\":\"f64\",\"shape\":[2,3]}]}", NULL, NULL, 0, "describes 1 arrays but the message has 0", PROTO_ERR_DECODE);
    /* length inconsistent with the shape */
    expect_reject("{\"type\":\"solve\",\"version\":1,\"arrays\":[{\"name\":\"f\",\"dtype\":\"f64\",\"shape\":[2,3]}]}", one, len40, 1, "needs 48 bytes, frame 1 has 40", PROTO_ERR_DECODE);
    expect_reject("{\"type\":\"solve\",\"version\":1,\"arrays\":[{\"name\":\"f\",\"dtype\":\"i32\",\"shape\":[2,3]}]}", one, len48, 1, "needs 24 bytes", PROTO_ERR_DECODE);
    /* bad descriptors */
    expect_reject("{\"type\":\"solve\",\"version\":1,\"arrays\":[{\"name\":\"f\",\"dtype\":\"f32\",\"shape\":[6]}]}", one, len48, 1, "dtype", PROTO_ERR_DECODE);
    expect_reject("{\"type\":\"solve\",\"version\":1,\"arrays\":[{\"name\":\"\",\"dtype\":\"f64\",\"shape\":[6]}]}", one, len48, 1, "name", PROTO_ERR_DECODE);
    expect_reject("{\"type\":\"solve\",\"version\":1,\"arrays\":[{\"name\":\"f\",\"dtype\":\"f64\",\"shape\":[6,1,1]}]}", one, len48, 1, "shape must be", PROTO_ERR_DECODE);
    expect_reject("{\"type\":\"solve\",\"version\":1,\"arrays\":[{\"name\":\"f\",\"dtype\":\"f64\",\"shape\":[-6]}]}", one, len48, 1, "whole numbers", PROTO_ERR_DECODE);
    expect_reject("{\"type\":\"solve\",\"version\":1,\"arrays\":[{\"name\":\"f\",\"dtype\":\"f64\",\"shape\":[1e12,1e12]}]}", one, len48, 1, "too large", PROTO_ERR_DECODE);
    expect_reject("{\"type\":\"solve\",\"version\":1,\"arrays\":[{\"name\":\"f\",\"dtype\":\"f64\",\"shape\":[4294967296,4294967296]}]}", one, len48, 1, "", PROTO_ERR_DECODE);
    expect_reject("{\"type\":\"solve\",\"version\":1,\"arrays\":[7]}", one, len48, 1, "arrays[0]", PROTO_ERR_DECODE);
    /* duplicate names */
    const void *two[2] = {data, data};
    size_t len2[2] = {24, 24};
    expect_reject("{\"type\":\"solve\",\"version\":1,\"arrays\":[{\"name\":\"f\",\"dtype\":\"f64\",\"shape\":[3]},{\"name\":\"f\",\"dtype\":\"f64\",\"shape\":[3]}]}", two, len2, 2, "appears twice", PROTO_ERR_DECODE);
}

static void test_nan_and_inf_rejected(void **state)
{
    (void)state;
    const char *header = "{\"type\":\"solve\",\"version\":1,\"arrays\":[{\"name\":\"force\",\"dtype\":\"f64\",\"shape\":[2,3]}]}";
    double data[6] = {1, 2, 3, 4, 5, 6};
    const void *frames[1] = {data};
    size_t lengths[1] = {sizeof data};
    data[4] = NAN;
    expect_reject(header, frames, lengths, 1, "array 'force': value 4 (row 1, column 1) is NaN", PROTO_ERR_DECODE);
    data[4] = 5;
    data[0] = -INFINITY;
    expect_reject(header, frames, lengths, 1, "value 0 (row 0, column 0) is infinite", PROTO_ERR_DECODE);
    /* a NaN value cannot even be encoded */
    proto_message out;
    memset(&out, 0, sizeof out);
    proto_message_init(&out, PROTO_MSG_SOLVE);
    proto_message_set_value(&out, "gap", NAN, NULL);
    char *text;
    size_t length;
    nc_error err;
    assert_int_equal(proto_encode_header(&out, &text, &length, &err), -1);
    assert_non_null(strstr(err.message, "'gap'"));
}

static void test_non_finite_found_anywhere_in_large_arrays(void **state)
{
    (void)state;
    /* the vectorised check works in blocks of 16 with a scalar tail: try every region */
    size_t n = 1000 * 3 + 1;
    double *data = calloc(n, sizeof *data);
    for (size_t k = 0; k < n; k++) data[k] = 1e300 * ((k % 7) - 3.0); /* large but finite */
    char header[256];
    u_header(header, sizeof header, n);
    const void *frames[1] = {data};
    size_t lengths[1] = {n * sizeof *data};
    proto_message in;
    memset(&in, 0, sizeof in);
    nc_error err;
    assert_int_equal(proto_decode(&in, header, strlen(header), frames, lengths, 1, LIMIT, &err), 0);
    size_t positions[6] = {0, 15, 16, 1777, n - 2, n - 1};
    double bad[3] = {NAN, INFINITY, -INFINITY};
    for (int p = 0; p < 6; p++) {
        for (int b = 0; b < 3; b++) {
            double keep = data[positions[p]];
            data[positions[p]] = bad[b];
            assert_int_equal(proto_decode(&in, header, strlen(header), frames, lengths, 1, LIMIT, &err), -1);
            char expect[64];
            snprintf(expect, sizeof expect, "value %zu (row %zu,", positions[p], positions[p]);
            if (!strstr(err.message, expect)) fail_msg("%s (expected '%s')", err.message, expect);
            data[positions[p]] = keep;
        }
    }
    proto_message_free(&in);
    free(data);
}

static void test_oversize_rejected(void **state)
{
    (void)state;
    size_t n = 1000;
    double *data = calloc(n, sizeof *data);
    char header[256];
    u_header(header, sizeof header, n);
    const void *frames[1] = {data};
    size_t lengths[1] = {n * sizeof *data};
    proto_message in;
    memset(&in, 0, sizeof in);
    nc_error err;
    assert_int_equal(proto_decode(&in, header, strlen(header), frames, lengths, 1, 4096, &err), -1);
    assert_non_null(strstr(err.message, "larger than the limit of 4096 bytes"));
    assert_int_equal(proto_decode(&in, header, strlen(header), frames, lengths, 1, 1u << 20, &err), 0);
    /* an absurd frame length must not overflow the size sum */
    size_t huge[1] = {SIZE_MAX};
    assert_int_equal(proto_decode(&in, header, strlen(header), frames, huge, 1, 1u << 20, &err), -1);
    proto_message_free(&in);
    free(data);
}

static void test_storage_reused(void **state)
{
    (void)state;
    /* A steady exchange must not reallocate: the second decode of the same size keeps the buffer. */
    double data[30] = {0};
    const char *header = "{\"type\":\"solve\",\"version\":1,\"arrays\":[{\"name\":\"u\",\"dtype\":\"f64\",\"shape\":[10,3]}]}";
    const void *frames[1] = {data};
    size_t lengths[1] = {sizeof data};
    proto_message in;
    memset(&in, 0, sizeof in);
    nc_error err;
    assert_int_equal(proto_decode(&in, header, strlen(header), frames, lengths, 1, LIMIT, &err), 0);
    const void *first = in.arrays[0].data;
    data[7] = 3.5;
    assert_int_equal(proto_decode(&in, header, strlen(header), frames, lengths, 1, LIMIT, &err), 0);
    assert_ptr_equal(in.arrays[0].data, first);
    assert_near(((const double *)in.arrays[0].data)[7], 3.5, 0.0);
    proto_message_free(&in);
}

static void test_add_array_usage_errors(void **state)
{
    (void)state;
    proto_message m;
    memset(&m, 0, sizeof m);
    proto_message_init(&m, PROTO_MSG_SOLVE);
    double x[3] = {0};
    nc_error err;
    assert_int_equal(proto_message_add_f64(&m, "x", x, 1, 3, &err), 0);
    assert_int_equal(proto_message_add_f64(&m, "x", x, 1, 3, &err), -1);
    assert_non_null(strstr(err.message, "added twice"));
    assert_int_equal(proto_message_add_f64(&m, "", x, 1, 3, &err), -1);
    for (int i = 1; i < PROTO_MAX_ARRAYS; i++) {
        char name[16];
        snprintf(name, sizeof name, "a%d", i);
        assert_int_equal(proto_message_add_f64(&m, name, x, 3, 0, &err), 0);
    }
    assert_int_equal(proto_message_add_f64(&m, "one_too_many", x, 3, 0, &err), -1);
    assert_int_equal(proto_type_from_name("accept_step"), PROTO_MSG_ACCEPT_STEP);
    assert_string_equal(proto_type_name(PROTO_MSG_BEGIN_STEP), "begin_step");
}

/* Version 2 header fields: session, retryable and versions survive the round trip, are absent
 * from the header when unset, and default to "", 0 and 0 when absent. */
static void test_round_trip_version2_fields(void **state)
{
    (void)state;
    proto_message out, in;
    memset(&out, 0, sizeof out);
    memset(&in, 0, sizeof in);
    nc_error err;
    char *header;
    size_t length;

    proto_message_init(&out, PROTO_MSG_HELLO);
    out.version = 1;
    out.offered_version = 2;
    snprintf(out.session, sizeof out.session, "0f1e2d3c4b5a6978");
    assert_int_equal(proto_encode_header(&out, &header, &length, &err), 0);
    assert_non_null(strstr(header, "\"versions\":[1,2]"));
    assert_non_null(strstr(header, "\"session\":\"0f1e2d3c4b5a6978\""));
    assert_null(strstr(header, "retryable"));
    assert_int_equal(proto_decode(&in, header, length, NULL, NULL, 0, LIMIT, &err), 0);
    free(header);
    assert_int_equal(in.type, PROTO_MSG_HELLO);
    assert_int_equal(in.version, 1);
    assert_int_equal(in.offered_version, 2);
    assert_string_equal(in.session, "0f1e2d3c4b5a6978");
    assert_int_equal(in.retryable, 0);

    proto_message_init(&out, PROTO_MSG_ERROR);
    out.version = 2;
    out.is_reply = 1;
    out.step = 41;
    out.iteration = 3;
    out.retryable = 1;
    snprintf(out.session, sizeof out.session, "0f1e2d3c4b5a6978");
    snprintf(out.text, sizeof out.text, "solve (step 41, iteration 3): Newton did not converge");
    assert_int_equal(proto_encode_header(&out, &header, &length, &err), 0);
    assert_non_null(strstr(header, "\"retryable\":true"));
    assert_null(strstr(header, "versions"));
    assert_int_equal(proto_decode(&in, header, length, NULL, NULL, 0, LIMIT, &err), 0);
    free(header);
    assert_int_equal(in.type, PROTO_MSG_ERROR);
    assert_int_equal(in.version, 2);
    assert_int_equal(in.retryable, 1);
    assert_int_equal(in.offered_version, 0);
    assert_int_equal(in.step, 41);
    assert_int_equal(in.iteration, 3);
    assert_string_equal(in.session, "0f1e2d3c4b5a6978");

    /* a plain version-1 message: none of them in the header, the defaults after decoding */
    proto_message_init(&out, PROTO_MSG_BEGIN_STEP);
    out.version = 1;
    assert_int_equal(proto_encode_header(&out, &header, &length, &err), 0);
    assert_null(strstr(header, "session"));
    assert_null(strstr(header, "versions"));
    assert_null(strstr(header, "retryable"));
    free(header);
    assert_int_equal(decode_text(&in, "{\"type\":\"begin_step\",\"version\":1,\"retryable\":false}",
                                 NULL, NULL, 0, &err), 0);
    assert_string_equal(in.session, "");
    assert_int_equal(in.retryable, 0);
    assert_int_equal(in.offered_version, 0);

    /* the newest offered version counts, in any order; versions newer than this side speaks
     * may be offered (hello is read as version 1) */
    assert_int_equal(decode_text(&in, "{\"type\":\"hello\",\"version\":1,\"versions\":[3,1,2]}",
                                 NULL, NULL, 0, &err), 0);
    assert_int_equal(in.offered_version, 3);
    assert_int_equal(decode_text(&in, "{\"type\":\"hello\",\"version\":1,\"versions\":[]}",
                                 NULL, NULL, 0, &err), 0);
    assert_int_equal(in.offered_version, 0);
    proto_message_free(&in);
}

static void test_malformed_version2_fields(void **state)
{
    (void)state;
    expect_reject("{\"type\":\"solve\",\"version\":2,\"session\":12}", NULL, NULL, 0, "'session': expected a string", PROTO_ERR_DECODE);
    expect_reject("{\"type\":\"solve\",\"version\":2,\"session\":null}", NULL, NULL, 0, "'session'", PROTO_ERR_DECODE);
    expect_reject("{\"type\":\"error\",\"version\":2,\"retryable\":1}", NULL, NULL, 0, "'retryable': expected true or false", PROTO_ERR_DECODE);
    expect_reject("{\"type\":\"error\",\"version\":2,\"retryable\":\"true\"}", NULL, NULL, 0, "'retryable'", PROTO_ERR_DECODE);
    expect_reject("{\"type\":\"hello\",\"version\":1,\"versions\":2}", NULL, NULL, 0, "'versions': expected a list", PROTO_ERR_DECODE);
    expect_reject("{\"type\":\"hello\",\"version\":1,\"versions\":{\"a\":2}}", NULL, NULL, 0, "'versions': expected a list", PROTO_ERR_DECODE);
    expect_reject("{\"type\":\"hello\",\"version\":1,\"versions\":[1,\"2\"]}", NULL, NULL, 0, "'versions': expected whole numbers", PROTO_ERR_DECODE);
    expect_reject("{\"type\":\"hello\",\"version\":1,\"versions\":[1,2.5]}", NULL, NULL, 0, "'versions': expected whole numbers", PROTO_ERR_DECODE);
    expect_reject("{\"type\":\"hello\",\"version\":1,\"versions\":[0,1]}", NULL, NULL, 0, "'versions': expected whole numbers", PROTO_ERR_DECODE);
    expect_reject("{\"type\":\"hello\",\"version\":1,\"versions\":[1,1e9]}", NULL, NULL, 0, "'versions': expected whole numbers", PROTO_ERR_DECODE);
    char long_session[PROTO_NAME_MAX + 64];
    snprintf(long_session, sizeof long_session, "{\"type\":\"solve\",\"version\":2,\"session\":\"%0*d\"}",
             PROTO_NAME_MAX, 0);
    expect_reject(long_session, NULL, NULL, 0, "'session': longer than", PROTO_ERR_DECODE);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_round_trip),
        cmocka_unit_test(test_round_trip_text_fields),
        cmocka_unit_test(test_round_trip_version2_fields),
        cmocka_unit_test(test_malformed_version2_fields),
        cmocka_unit_test(test_empty_array),
        cmocka_unit_test(test_malformed_headers),
        cmocka_unit_test(test_malformed_arrays),
        cmocka_unit_test(test_nan_and_inf_rejected),
        cmocka_unit_test(test_non_finite_found_anywhere_in_large_arrays),
        cmocka_unit_test(test_oversize_rejected),
        cmocka_unit_test(test_storage_reused),
        cmocka_unit_test(test_add_array_usage_errors),
    };
    return cmocka_run_group_tests_name("protocol codec", tests, NULL, NULL);
}
