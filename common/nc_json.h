/* nc_json — reading input files with cJSON, with errors that name file, field and expectation.
 *
 * `where` is the location of `obj` in the input, e.g. "cases/x/fem.json: element_sets[1]";
 * messages read "<where>.<key>: expected a number > 0, got \"abc\"". Required getters fail when
 * the key is missing; *_opt getters leave `*out = fallback` when it is missing but still fail
 * on a wrong type or range. All return 0 / -1 (see nc_error.h).
 */
#ifndef NC_JSON_H
#define NC_JSON_H

#include <stddef.h>
#include <cjson/cJSON.h>
#include "nc_error.h"

/* Reads and parses a whole file; parse errors give line and column. Free with cJSON_Delete.
 * The top level must be an object; a key given twice in one object and a number beyond the
 * range of a double (1e400) are errors naming the path of the value. */
int nc_json_load_file(const char *path, cJSON **root, nc_error *err);
/* The same for `size` bytes of text in memory; `name` stands for the file in messages. */
int nc_json_parse_text(const char *name, const char *text, size_t size, cJSON **root,
                       nc_error *err);

/* The error of a value that is not what `key` takes: "<where>.<key>: expected <expected>,
 * got <the value>" (for checks the getters below do not make). Returns -1. */
int nc_json_wrong(nc_error *err, const char *where, const char *key, const char *expected,
                  const cJSON *got);

/* Fails naming any key of `obj` not in the NULL-terminated `allowed` list (catches typos). */
int nc_json_check_keys(const cJSON *obj, const char *where, const char *const *allowed,
                       nc_error *err);

int nc_json_number(const cJSON *obj, const char *where, const char *key, double *out,
                   nc_error *err);
int nc_json_number_opt(const cJSON *obj, const char *where, const char *key, double fallback,
                       double *out, nc_error *err);
/* Like nc_json_number(_opt) but also requires min <= value <= max (use ±INFINITY to skip). */
int nc_json_number_range(const cJSON *obj, const char *where, const char *key, double min,
                         double max, double *out, nc_error *err);
int nc_json_number_range_opt(const cJSON *obj, const char *where, const char *key,
                             double fallback, double min, double max, double *out,
                             nc_error *err);
/* A positive number (> 0), the most common physical-property check. */
int nc_json_positive(const cJSON *obj, const char *where, const char *key, double *out,
                     nc_error *err);

/* Integers must be whole numbers within [min, max]. */
int nc_json_int(const cJSON *obj, const char *where, const char *key, long min, long max,
                long *out, nc_error *err);
int nc_json_int_opt(const cJSON *obj, const char *where, const char *key, long fallback,
                    long min, long max, long *out, nc_error *err);

int nc_json_bool_opt(const cJSON *obj, const char *where, const char *key, int fallback,
                     int *out, nc_error *err);

/* *out points into the cJSON tree (valid while root lives). */
int nc_json_string(const cJSON *obj, const char *where, const char *key, const char **out,
                   nc_error *err);
int nc_json_string_opt(const cJSON *obj, const char *where, const char *key,
                       const char *fallback, const char **out, nc_error *err);
/* A string that must be one of the NULL-terminated `choices`; *index gets its position. */
int nc_json_choice_opt(const cJSON *obj, const char *where, const char *key,
                       const char *const *choices, int fallback_index, int *index,
                       nc_error *err);

/* A 3-vector [x, y, z] of finite numbers. */
int nc_json_vec3(const cJSON *obj, const char *where, const char *key, double out[3],
                 nc_error *err);
int nc_json_vec3_opt(const cJSON *obj, const char *where, const char *key,
                     const double fallback[3], double out[3], nc_error *err);

/* An array; *count gets its length. Missing key is an error for the required form and gives
 * *arr = NULL, *count = 0 for the optional one. */
int nc_json_array(const cJSON *obj, const char *where, const char *key, const cJSON **arr,
                  int *count, nc_error *err);
int nc_json_array_opt(const cJSON *obj, const char *where, const char *key, const cJSON **arr,
                      int *count, nc_error *err);
/* An object member (required / optional: NULL when missing). */
int nc_json_object(const cJSON *obj, const char *where, const char *key, const cJSON **out,
                   nc_error *err);
int nc_json_object_opt(const cJSON *obj, const char *where, const char *key,
                       const cJSON **out, nc_error *err);

/* Builds "<where>.<key>" or "<where>[index]" into buf (for nested messages). */
const char *nc_json_path(char *buf, size_t size, const char *where, const char *key);
const char *nc_json_path_index(char *buf, size_t size, const char *where, const char *key,
                               int index);

#endif
