/* proto_codec — the wire format: a JSON header (written directly, parsed with cJSON) and
 * little-endian binary array frames.
 *
 * Decoding trusts nothing: every field is type-checked, every length is checked against the
 * frame that carries it (with overflow-safe arithmetic), sizes are capped, and f64 arrays are
 * scanned for NaN/Inf. See protocol/README.md for the format.
 */
#include "proto.h"

#include <cjson/cJSON.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define PROTO_MAX_HEADER_BYTES (64u * 1024u)

static int host_is_little_endian(void)
{
    const uint16_t probe = 1;
    return *(const uint8_t *)&probe == 1;
}

static void swap_bytes(void *data, size_t count, size_t item_size)
{
    uint8_t *bytes = data;
    for (size_t i = 0; i < count; i++, bytes += item_size)
        for (size_t a = 0, b = item_size - 1; a < b; a++, b--) {
            uint8_t t = bytes[a];
            bytes[a] = bytes[b];
            bytes[b] = t;
        }
}

size_t proto_dtype_size(proto_dtype dtype)
{
    return dtype == PROTO_F64 ? 8 : 4;
}

/* A growing text buffer for the header: written directly, because building a cJSON tree and
 * printing it costs several microseconds per message (its number printing re-parses every
 * value), a noticeable share of a solve round trip. */
typedef struct text_buffer {
    char *data;
    size_t length, capacity;
    int failed;
} text_buffer;

static void put(text_buffer *b, const char *format, ...) __attribute__((format(printf, 2, 3)));
static void put(text_buffer *b, const char *format, ...)
{
    if (b->failed) return;
    for (;;) {
        va_list args;
        va_start(args, format);
        int n = vsnprintf(b->data + b->length, b->capacity - b->length, format, args);
        va_end(args);
        if (n < 0) {
            b->failed = 1;
            return;
        }
        if ((size_t)n < b->capacity - b->length) {
            b->length += (size_t)n;
            return;
        }
        size_t grown = 2 * b->capacity + (size_t)n;
        char *data = realloc(b->data, grown);
        if (!data) {
            b->failed = 1;
            return;
        }
        b->data = data;
        b->capacity = grown;
    }
}

/* A JSON string literal: quotes, backslashes and control characters escaped. */
static void put_string(text_buffer *b, const char *text)
{
    put(b, "\"");
    for (const unsigned char *c = (const unsigned char *)text; *c; c++) {
        if (*c == '"' || *c == '\\') put(b, "\\%c", *c);
        else if (*c == '\n') put(b, "\\n");
        else if (*c == '\t') put(b, "\\t");
        else if (*c < 0x20) put(b, "\\u%04x", *c);
        else put(b, "%c", *c);
    }
    put(b, "\"");
}

int proto_encode_header(const proto_message *m, char **json, size_t *length, nc_error *err)
{
    *json = NULL;
    *length = 0;
    if ((int)m->type <= PROTO_MSG_INVALID || m->type >= PROTO_MSG_COUNT)
        return nc_error_set(err, PROTO_ERR_USAGE, "cannot encode a message of invalid type %d", (int)m->type);
    for (size_t i = 0; i < m->n_values; i++) {
        /* JSON has no NaN/Inf: a non-finite value is an encoding error, not a silent null */
        if (!isfinite(m->values[i].value))
            return nc_error_set(err, PROTO_ERR_USAGE, "%s message: value '%s' is not finite",
                                proto_type_name(m->type), m->values[i].name);
    }
    text_buffer b = {malloc(512), 0, 512, 0};
    if (!b.data) return nc_error_set(err, PROTO_ERR_USAGE, "out of memory encoding a header");
    /* %.17g: every double survives the round trip through text exactly */
    put(&b, "{\"type\":\"%s\",\"version\":%d,\"reply\":%s,\"step\":%ld,\"iteration\":%d,"
            "\"time\":%.17g,\"dt\":%.17g,\"status\":\"%s\"",
        proto_type_name(m->type), m->version ? m->version : PROTO_VERSION,
        m->is_reply ? "true" : "false", m->step, m->iteration,
        isfinite(m->time_s) ? m->time_s : 0.0, isfinite(m->dt_s) ? m->dt_s : 0.0,
        m->type == PROTO_MSG_ERROR ? "error" : "ok");
    const char *texts[4][2] = {{"role", m->role}, {"name", m->name}, {"text", m->text},
                               {"session", m->session}};
    for (int t = 0; t < 4; t++) {
        if (!texts[t][1][0]) continue;
        put(&b, ",\"%s\":", texts[t][0]);
        put_string(&b, texts[t][1]);
    }
    if (m->retryable) put(&b, ",\"retryable\":true");
    if (m->offered_version > 0) {
        put(&b, ",\"versions\":[");
        for (int v = PROTO_VERSION_MIN; v <= m->offered_version; v++)
            put(&b, "%s%d", v > PROTO_VERSION_MIN ? "," : "", v);
        put(&b, "]");
    }
    put(&b, ",\"arrays\":[");
    for (size_t i = 0; i < m->n_arrays; i++) {
        const proto_array *a = &m->arrays[i];
        put(&b, "%s{\"name\":", i ? "," : "");
        put_string(&b, a->name);
        if (a->ndim == 2)
            put(&b, ",\"dtype\":\"%s\",\"shape\":[%zu,%zu]}", a->dtype == PROTO_F64 ? "f64" : "i32",
                a->shape[0], a->shape[1]);
        else
            put(&b, ",\"dtype\":\"%s\",\"shape\":[%zu]}", a->dtype == PROTO_F64 ? "f64" : "i32",
                a->shape[0]);
    }
    put(&b, "],\"values\":{");
    for (size_t i = 0; i < m->n_values; i++) {
        put(&b, "%s", i ? "," : "");
        put_string(&b, m->values[i].name);
        put(&b, ":%.17g", m->values[i].value);
    }
    put(&b, "}}");
    if (b.failed) {
        free(b.data);
        return nc_error_set(err, PROTO_ERR_USAGE, "out of memory encoding a header");
    }
    *json = b.data;
    *length = b.length;
    return 0;
}

/* ---- decoding -------------------------------------------------------------------------- */

static int fail(nc_error *err, int code, const char *format, const char *a, const char *b)
{
    return nc_error_set(err, code, format, a, b);
}

/* Optional whole number in [min, max]. */
static int get_whole(const cJSON *root, const char *key, double min, double max, double *out,
                     nc_error *err)
{
    const cJSON *item = cJSON_GetObjectItemCaseSensitive(root, key);
    if (!item) return 0;
    if (!cJSON_IsNumber(item) || !isfinite(item->valuedouble) ||
        item->valuedouble != floor(item->valuedouble) || item->valuedouble < min ||
        item->valuedouble > max)
        return fail(err, PROTO_ERR_DECODE, "header field '%s': expected a whole number%s", key,
                    min >= 0 ? " >= 0" : " >= -1");
    *out = item->valuedouble;
    return 0;
}

static int get_finite(const cJSON *root, const char *key, double *out, nc_error *err)
{
    const cJSON *item = cJSON_GetObjectItemCaseSensitive(root, key);
    if (!item) return 0;
    if (!cJSON_IsNumber(item) || !isfinite(item->valuedouble))
        return fail(err, PROTO_ERR_DECODE, "header field '%s': expected a finite number%s", key, "");
    *out = item->valuedouble;
    return 0;
}

static int get_text(const cJSON *root, const char *key, char *out, size_t size, nc_error *err)
{
    const cJSON *item = cJSON_GetObjectItemCaseSensitive(root, key);
    if (!item) return 0;
    if (!cJSON_IsString(item) || !item->valuestring)
        return fail(err, PROTO_ERR_DECODE, "header field '%s': expected a string%s", key, "");
    if (strlen(item->valuestring) >= size)
        return nc_error_set(err, PROTO_ERR_DECODE, "header field '%s': longer than %zu characters",
                            key, size - 1);
    memcpy(out, item->valuestring, strlen(item->valuestring) + 1);
    return 0;
}

static int decode_header(proto_message *m, cJSON *root, nc_error *err)
{
    const cJSON *type = cJSON_GetObjectItemCaseSensitive(root, "type");
    if (!type) return nc_error_set(err, PROTO_ERR_DECODE, "header has no 'type'");
    if (!cJSON_IsString(type) || !type->valuestring)
        return nc_error_set(err, PROTO_ERR_DECODE, "header field 'type': expected a string");
    proto_msg_type t = proto_type_from_name(type->valuestring);
    if (t == PROTO_MSG_INVALID) {
        char shown[48];
        snprintf(shown, sizeof shown, "%s", type->valuestring);
        return nc_error_set(err, PROTO_ERR_DECODE, "unknown message type '%s'", shown);
    }
    proto_message_init(m, t);

    const cJSON *version = cJSON_GetObjectItemCaseSensitive(root, "version");
    if (!version) return nc_error_set(err, PROTO_ERR_DECODE, "header has no 'version'");
    if (!cJSON_IsNumber(version) || version->valuedouble != floor(version->valuedouble))
        return nc_error_set(err, PROTO_ERR_DECODE, "header field 'version': expected a whole number");
    if (version->valuedouble < PROTO_VERSION_MIN || version->valuedouble > PROTO_VERSION)
        return nc_error_set(err, PROTO_ERR_VERSION,
                            "protocol version mismatch: message has version %.0f, this side speaks "
                            "%d to %d", version->valuedouble, PROTO_VERSION_MIN, PROTO_VERSION);
    m->version = (int)version->valuedouble;

    const cJSON *reply = cJSON_GetObjectItemCaseSensitive(root, "reply");
    if (reply && !cJSON_IsBool(reply))
        return nc_error_set(err, PROTO_ERR_DECODE, "header field 'reply': expected true or false");
    m->is_reply = reply ? cJSON_IsTrue(reply) : 0;

    double step = -1, iteration = 0;
    if (get_whole(root, "step", -1, 9.0e15, &step, err)) return -1;
    if (get_whole(root, "iteration", 0, 2147483647.0, &iteration, err)) return -1;
    m->step = (long)step;
    m->iteration = (int)iteration;
    if (get_finite(root, "time", &m->time_s, err)) return -1;
    if (get_finite(root, "dt", &m->dt_s, err)) return -1;

    const cJSON *status = cJSON_GetObjectItemCaseSensitive(root, "status");
    if (status && (!cJSON_IsString(status) || (strcmp(status->valuestring, "ok") != 0 &&
                                                strcmp(status->valuestring, "error") != 0)))
        return nc_error_set(err, PROTO_ERR_DECODE, "header field 'status': expected \"ok\" or \"error\"");
    if (status && strcmp(status->valuestring, "error") == 0) m->type = PROTO_MSG_ERROR;

    if (get_text(root, "role", m->role, sizeof m->role, err)) return -1;
    if (get_text(root, "name", m->name, sizeof m->name, err)) return -1;
    if (get_text(root, "text", m->text, sizeof m->text, err)) return -1;
    if (get_text(root, "session", m->session, sizeof m->session, err)) return -1;
    const cJSON *retryable = cJSON_GetObjectItemCaseSensitive(root, "retryable");
    if (retryable && !cJSON_IsBool(retryable))
        return nc_error_set(err, PROTO_ERR_DECODE, "header field 'retryable': expected true or false");
    m->retryable = retryable ? cJSON_IsTrue(retryable) : 0;
    /* hello: the versions the coupler speaks; the newest is what a participant may choose */
    const cJSON *versions = cJSON_GetObjectItemCaseSensitive(root, "versions");
    if (versions) {
        if (!cJSON_IsArray(versions))
            return nc_error_set(err, PROTO_ERR_DECODE, "header field 'versions': expected a list");
        const cJSON *v;
        cJSON_ArrayForEach(v, versions) {
            if (!cJSON_IsNumber(v) || v->valuedouble != floor(v->valuedouble) ||
                v->valuedouble < 1 || v->valuedouble > 1e6)
                return nc_error_set(err, PROTO_ERR_DECODE,
                                    "header field 'versions': expected whole numbers >= 1");
            if (v->valuedouble > m->offered_version) m->offered_version = (int)v->valuedouble;
        }
    }

    const cJSON *values = cJSON_GetObjectItemCaseSensitive(root, "values");
    if (values) {
        if (!cJSON_IsObject(values))
            return nc_error_set(err, PROTO_ERR_DECODE, "header field 'values': expected an object");
        const cJSON *v;
        cJSON_ArrayForEach(v, values) {
            if (m->n_values >= PROTO_MAX_VALUES)
                return nc_error_set(err, PROTO_ERR_DECODE, "header field 'values': more than %d values",
                                    PROTO_MAX_VALUES);
            if (!v->string || !v->string[0] || strlen(v->string) >= PROTO_NAME_MAX)
                return nc_error_set(err, PROTO_ERR_DECODE,
                                    "header field 'values': names must have 1..%d characters",
                                    PROTO_NAME_MAX - 1);
            if (!cJSON_IsNumber(v) || !isfinite(v->valuedouble))
                return nc_error_set(err, PROTO_ERR_DECODE, "value '%s': expected a finite number",
                                    v->string);
            if (proto_message_has_value(m, v->string))
                return nc_error_set(err, PROTO_ERR_DECODE, "value '%s' appears twice", v->string);
            proto_message_set_value(m, v->string, v->valuedouble, NULL);
        }
    }
    return 0;
}

/* Reads one array descriptor into a (without data). */
static int decode_descriptor(const cJSON *item, size_t index, proto_array *a, nc_error *err)
{
    if (!cJSON_IsObject(item))
        return nc_error_set(err, PROTO_ERR_DECODE, "arrays[%zu]: expected an object", index);
    const cJSON *name = cJSON_GetObjectItemCaseSensitive(item, "name");
    if (!cJSON_IsString(name) || !name->valuestring[0] || strlen(name->valuestring) >= PROTO_NAME_MAX)
        return nc_error_set(err, PROTO_ERR_DECODE,
                            "arrays[%zu].name: expected a string of 1..%d characters", index,
                            PROTO_NAME_MAX - 1);
    snprintf(a->name, sizeof a->name, "%s", name->valuestring);
    const cJSON *dtype = cJSON_GetObjectItemCaseSensitive(item, "dtype");
    if (cJSON_IsString(dtype) && strcmp(dtype->valuestring, "f64") == 0) a->dtype = PROTO_F64;
    else if (cJSON_IsString(dtype) && strcmp(dtype->valuestring, "i32") == 0) a->dtype = PROTO_I32;
    else
        return nc_error_set(err, PROTO_ERR_DECODE, "array '%s': dtype must be \"f64\" or \"i32\"",
                            a->name);
    const cJSON *shape = cJSON_GetObjectItemCaseSensitive(item, "shape");
    int ndim = cJSON_IsArray(shape) ? cJSON_GetArraySize(shape) : 0;
    if (ndim < 1 || ndim > 2)
        return nc_error_set(err, PROTO_ERR_DECODE,
                            "array '%s': shape must be [rows] or [rows, columns]", a->name);
    a->ndim = ndim;
    a->shape[1] = 1;
    for (int d = 0; d < ndim; d++) {
        const cJSON *extent = cJSON_GetArrayItem(shape, d);
        /* 2^40 values is far beyond any message limit; it also keeps products exact */
        if (!cJSON_IsNumber(extent) || extent->valuedouble < 0 || extent->valuedouble > 1099511627776.0 ||
            extent->valuedouble != floor(extent->valuedouble))
            return nc_error_set(err, PROTO_ERR_DECODE,
                                "array '%s': shape entries must be whole numbers >= 0", a->name);
        a->shape[d] = (size_t)extent->valuedouble;
    }
    if (a->shape[1] != 0 && a->shape[0] > SIZE_MAX / 16 / a->shape[1])
        return nc_error_set(err, PROTO_ERR_DECODE, "array '%s': shape too large", a->name);
    a->count = a->shape[0] * a->shape[1];
    return 0;
}

/* Whether all values are finite: x * 0 is 0 for finite x and NaN for NaN or ±Inf, so the
 * sum of those products is 0 exactly when all are finite. Sixteen independent sums let the
 * compiler vectorise without reassociating; AVX-512 and AVX2 builds of the same loop are used
 * where the processor has them (2-3x faster; validation is most of the protocol's cost on big
 * arrays). */
#define ALL_FINITE_BODY                                                        \
    double s[16] = {0};                                                        \
    size_t k = 0;                                                              \
    for (; k + 16 <= count; k += 16)                                           \
        for (int j = 0; j < 16; j++) s[j] += values[k + j] * 0.0;              \
    for (; k < count; k++) s[0] += values[k] * 0.0;                            \
    double total = 0;                                                          \
    for (int j = 0; j < 16; j++) total += s[j];                                \
    return total == 0.0;

static int all_finite_generic(const double *values, size_t count) { ALL_FINITE_BODY }

#if defined(__x86_64__) && defined(__GNUC__)
__attribute__((target("avx2"))) static int all_finite_avx2(const double *values, size_t count)
{
    ALL_FINITE_BODY
}
__attribute__((target("avx512f"))) static int all_finite_avx512(const double *values, size_t count)
{
    ALL_FINITE_BODY
}
#endif

/* Index of the first non-finite value, or count if all are finite. */
static size_t first_non_finite(const double *values, size_t count)
{
#if defined(__x86_64__) && defined(__GNUC__)
    int finite = __builtin_cpu_supports("avx512f") ? all_finite_avx512(values, count)
                 : __builtin_cpu_supports("avx2")  ? all_finite_avx2(values, count)
                                                   : all_finite_generic(values, count);
#else
    int finite = all_finite_generic(values, count);
#endif
    if (finite) return count;
    for (size_t k = 0; k < count; k++)
        if (!isfinite(values[k])) return k;
    return count;
}

static int decode(proto_message *m, const void *header, size_t header_length,
                  const void *const *frames, const size_t *frame_lengths, size_t n_frames,
                  size_t max_bytes, int borrow, nc_error *err)
{
    proto_message_init(m, PROTO_MSG_INVALID);
    if (!header || header_length == 0)
        return nc_error_set(err, PROTO_ERR_DECODE, "empty header frame");
    if (header_length > PROTO_MAX_HEADER_BYTES)
        return nc_error_set(err, PROTO_ERR_DECODE, "header of %zu bytes exceeds the %u-byte limit",
                            header_length, PROTO_MAX_HEADER_BYTES);
    size_t total = header_length;
    for (size_t i = 0; i < n_frames; i++) {
        if (frame_lengths[i] > max_bytes || total > max_bytes - frame_lengths[i])
            return nc_error_set(err, PROTO_ERR_DECODE,
                                "message larger than the limit of %zu bytes", max_bytes);
        total += frame_lengths[i];
    }
    if (total > max_bytes)
        return nc_error_set(err, PROTO_ERR_DECODE, "message larger than the limit of %zu bytes",
                            max_bytes);

    cJSON *root = cJSON_ParseWithLength(header, header_length);
    if (!root) return nc_error_set(err, PROTO_ERR_DECODE, "header is not valid JSON");
    int rc = -1;
    if (!cJSON_IsObject(root)) {
        nc_error_set(err, PROTO_ERR_DECODE, "header is not a JSON object");
        goto done;
    }
    if (decode_header(m, root, err)) goto done;

    const cJSON *arrays = cJSON_GetObjectItemCaseSensitive(root, "arrays");
    size_t n_arrays = 0;
    if (arrays) {
        if (!cJSON_IsArray(arrays)) {
            nc_error_set(err, PROTO_ERR_DECODE, "header field 'arrays': expected a list");
            goto done;
        }
        n_arrays = (size_t)cJSON_GetArraySize(arrays);
    }
    if (n_arrays > PROTO_MAX_ARRAYS) {
        nc_error_set(err, PROTO_ERR_DECODE, "%zu arrays: a message holds at most %d", n_arrays,
                     PROTO_MAX_ARRAYS);
        goto done;
    }
    if (n_arrays != n_frames) {
        nc_error_set(err, PROTO_ERR_DECODE,
                     "header describes %zu arrays but the message has %zu data frames", n_arrays,
                     n_frames);
        goto done;
    }
    for (size_t i = 0; i < n_arrays; i++) {
        proto_array *a = &m->arrays[i];
        if (decode_descriptor(cJSON_GetArrayItem(arrays, (int)i), i, a, err)) goto done;
        for (size_t j = 0; j < i; j++) {
            if (strcmp(m->arrays[j].name, a->name) == 0) {
                nc_error_set(err, PROTO_ERR_DECODE, "array '%s' appears twice", a->name);
                goto done;
            }
        }
        size_t item_size = proto_dtype_size(a->dtype);
        size_t bytes = a->count * item_size;
        if (frame_lengths[i] != bytes) {
            nc_error_set(err, PROTO_ERR_DECODE,
                         "array '%s': shape [%zu, %zu] of %s needs %zu bytes, frame %zu has %zu",
                         a->name, a->shape[0], a->shape[1], a->dtype == PROTO_F64 ? "f64" : "i32",
                         bytes, i + 1, frame_lengths[i]);
            goto done;
        }
        int aligned = ((uintptr_t)frames[i] % item_size) == 0;
        if (borrow && aligned && host_is_little_endian()) {
            a->data = frames[i];
        } else {
        if (bytes > m->storage_capacity[i]) {
            void *grown = realloc(m->storage[i], bytes);
            if (!grown) {
                nc_error_set(err, PROTO_ERR_DECODE, "array '%s': out of memory for %zu bytes",
                             a->name, bytes);
                goto done;
            }
            m->storage[i] = grown;
            m->storage_capacity[i] = bytes;
        }
        if (bytes) memcpy(m->storage[i], frames[i], bytes);
        if (!host_is_little_endian()) swap_bytes(m->storage[i], a->count, item_size);
        a->data = m->storage[i];
        }
        if (a->dtype == PROTO_F64) {
            const double *values = a->data;
            size_t k = first_non_finite(values, a->count);
            if (k < a->count) {
                nc_error_set(err, PROTO_ERR_DECODE,
                             "array '%s': value %zu (row %zu, column %zu) is %s", a->name, k,
                             k / a->shape[1], k % a->shape[1], isnan(values[k]) ? "NaN" : "infinite");
                goto done;
            }
        }
        m->n_arrays = i + 1;
    }
    rc = 0;
done:
    cJSON_Delete(root);
    if (rc) m->n_arrays = 0;
    return rc;
}

int proto_decode(proto_message *m, const void *header, size_t header_length,
                 const void *const *frames, const size_t *frame_lengths, size_t n_frames,
                 size_t max_bytes, nc_error *err)
{
    return decode(m, header, header_length, frames, frame_lengths, n_frames, max_bytes, 0, err);
}

int proto_decode_borrowed(proto_message *m, const void *header, size_t header_length,
                          const void *const *frames, const size_t *frame_lengths,
                          size_t n_frames, size_t max_bytes, nc_error *err)
{
    return decode(m, header, header_length, frames, frame_lengths, n_frames, max_bytes, 1, err);
}
