/* proto_message — building and reading proto_message structs (no I/O, no JSON). */
#include "proto.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static const char *const type_names[PROTO_MSG_COUNT] = {
    [PROTO_MSG_INVALID] = "invalid",       [PROTO_MSG_HELLO] = "hello",
    [PROTO_MSG_INTERFACE] = "interface",   [PROTO_MSG_BEGIN_STEP] = "begin_step",
    [PROTO_MSG_SOLVE] = "solve",           [PROTO_MSG_ACCEPT_STEP] = "accept_step",
    [PROTO_MSG_SHUTDOWN] = "shutdown",     [PROTO_MSG_ERROR] = "error",
    [PROTO_MSG_CHECKPOINT] = "checkpoint", [PROTO_MSG_RESUME] = "resume",
};

const char *proto_type_name(proto_msg_type type)
{
    if ((int)type <= PROTO_MSG_INVALID || type >= PROTO_MSG_COUNT) return "invalid";
    return type_names[type];
}

proto_msg_type proto_type_from_name(const char *name)
{
    for (int t = PROTO_MSG_INVALID + 1; t < PROTO_MSG_COUNT; t++)
        if (strcmp(name, type_names[t]) == 0) return (proto_msg_type)t;
    return PROTO_MSG_INVALID;
}

void proto_message_init(proto_message *m, proto_msg_type type)
{
    void *storage[PROTO_MAX_ARRAYS];
    size_t capacity[PROTO_MAX_ARRAYS];
    memcpy(storage, m->storage, sizeof storage);
    memcpy(capacity, m->storage_capacity, sizeof capacity);
    memset(m, 0, sizeof *m);
    memcpy(m->storage, storage, sizeof storage);
    memcpy(m->storage_capacity, capacity, sizeof capacity);
    m->type = type;
    m->version = PROTO_VERSION;
    m->step = -1;
}

void proto_message_free(proto_message *m)
{
    for (int i = 0; i < PROTO_MAX_ARRAYS; i++) {
        free(m->storage[i]);
        m->storage[i] = NULL;
        m->storage_capacity[i] = 0;
    }
    m->n_arrays = 0;
}

static int valid_name(const char *name)
{
    size_t length = strlen(name);
    return length > 0 && length < PROTO_NAME_MAX;
}

static int add_array(proto_message *m, const char *name, proto_dtype dtype, const void *data,
                     size_t rows, size_t cols, nc_error *err)
{
    if (!valid_name(name))
        return nc_error_set(err, PROTO_ERR_USAGE, "array name must have 1..%d characters",
                            PROTO_NAME_MAX - 1);
    if (m->n_arrays >= PROTO_MAX_ARRAYS)
        return nc_error_set(err, PROTO_ERR_USAGE, "array '%s': a message holds at most %d arrays",
                            name, PROTO_MAX_ARRAYS);
    for (size_t i = 0; i < m->n_arrays; i++)
        if (strcmp(m->arrays[i].name, name) == 0)
            return nc_error_set(err, PROTO_ERR_USAGE, "array '%s' added twice", name);
    if (rows > 0 && !data)
        return nc_error_set(err, PROTO_ERR_USAGE, "array '%s': no data", name);
    proto_array *a = &m->arrays[m->n_arrays++];
    snprintf(a->name, sizeof a->name, "%s", name);
    a->dtype = dtype;
    a->ndim = cols ? 2 : 1;
    a->shape[0] = rows;
    a->shape[1] = cols ? cols : 1;
    a->count = rows * a->shape[1];
    a->data = data;
    return 0;
}

int proto_message_add_f64(proto_message *m, const char *name, const double *data, size_t rows,
                          size_t cols, nc_error *err)
{
    return add_array(m, name, PROTO_F64, data, rows, cols, err);
}

int proto_message_add_i32(proto_message *m, const char *name, const int32_t *data, size_t rows,
                          size_t cols, nc_error *err)
{
    return add_array(m, name, PROTO_I32, data, rows, cols, err);
}

int proto_message_set_value(proto_message *m, const char *name, double value, nc_error *err)
{
    if (!valid_name(name))
        return nc_error_set(err, PROTO_ERR_USAGE, "value name must have 1..%d characters",
                            PROTO_NAME_MAX - 1);
    for (size_t i = 0; i < m->n_values; i++) {
        if (strcmp(m->values[i].name, name) == 0) {
            m->values[i].value = value;
            return 0;
        }
    }
    if (m->n_values >= PROTO_MAX_VALUES)
        return nc_error_set(err, PROTO_ERR_USAGE, "value '%s': a message holds at most %d values",
                            name, PROTO_MAX_VALUES);
    proto_value *v = &m->values[m->n_values++];
    snprintf(v->name, sizeof v->name, "%s", name);
    v->value = value;
    return 0;
}

static int get_array(const proto_message *m, const char *name, proto_dtype dtype,
                     size_t expected_rows, size_t expected_cols, const void **data,
                     size_t *rows, nc_error *err)
{
    const char *type = proto_type_name(m->type);
    for (size_t i = 0; i < m->n_arrays; i++) {
        const proto_array *a = &m->arrays[i];
        if (strcmp(a->name, name) != 0) continue;
        if (a->dtype != dtype)
            return nc_error_set(err, PROTO_ERR_USAGE, "%s message: array '%s' is %s, expected %s",
                                type, name, a->dtype == PROTO_F64 ? "f64" : "i32",
                                dtype == PROTO_F64 ? "f64" : "i32");
        if ((expected_rows && a->shape[0] != expected_rows) ||
            (expected_cols && (a->ndim != 2 || a->shape[1] != expected_cols)))
            return nc_error_set(err, PROTO_ERR_USAGE,
                                "%s message: array '%s' has shape [%zu, %zu], expected [%zu, %zu]",
                                type, name, a->shape[0], a->ndim == 2 ? a->shape[1] : (size_t)0,
                                expected_rows ? expected_rows : a->shape[0], expected_cols);
        *data = a->data;
        if (rows) *rows = a->shape[0];
        return 0;
    }
    return nc_error_set(err, PROTO_ERR_USAGE, "%s message: array '%s' is missing", type, name);
}

int proto_message_get_f64(const proto_message *m, const char *name, size_t expected_rows,
                          size_t expected_cols, const double **data, size_t *rows,
                          nc_error *err)
{
    return get_array(m, name, PROTO_F64, expected_rows, expected_cols, (const void **)data, rows,
                     err);
}

int proto_message_get_i32(const proto_message *m, const char *name, size_t expected_rows,
                          size_t expected_cols, const int32_t **data, size_t *rows,
                          nc_error *err)
{
    return get_array(m, name, PROTO_I32, expected_rows, expected_cols, (const void **)data, rows,
                     err);
}

double proto_message_value(const proto_message *m, const char *name, double fallback)
{
    for (size_t i = 0; i < m->n_values; i++)
        if (strcmp(m->values[i].name, name) == 0) return m->values[i].value;
    return fallback;
}

int proto_message_has_value(const proto_message *m, const char *name)
{
    for (size_t i = 0; i < m->n_values; i++)
        if (strcmp(m->values[i].name, name) == 0) return 1;
    return 0;
}

int proto_has_capability(const char *capabilities, const char *word)
{
    size_t length = strlen(word);
    if (!capabilities || length == 0) return 0;
    for (const char *c = capabilities; (c = strstr(c, word)) != NULL; c += length) {
        int starts = c == capabilities || c[-1] == ' ';
        int ends = c[length] == '\0' || c[length] == ' ';
        if (starts && ends) return 1;
    }
    return 0;
}

const proto_array *proto_message_find(const proto_message *m, const char *name)
{
    for (size_t i = 0; i < m->n_arrays; i++)
        if (strcmp(m->arrays[i].name, name) == 0) return &m->arrays[i];
    return NULL;
}
