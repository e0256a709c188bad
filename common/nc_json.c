/* nc_json — validated getters over cJSON trees (see nc_json.h). */
#include "nc_json.h"

#include <errno.h>
#include <float.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define NC_JSON_MAX_FILE_BYTES (512L * 1024 * 1024)

/* "fem.json" + "nodes" -> "fem.json: nodes"; "fem.json: supports[0]" + "dofs" ->
 * "fem.json: supports[0].dofs": the file is set off from the path inside it. */
static const char *separator(const char *where, const char *key)
{
    if (!where[0] || !key[0]) return "";
    size_t length = strlen(where);
    return length >= 5 && strcmp(where + length - 5, ".json") == 0 ? ": " : ".";
}

const char *nc_json_path(char *buf, size_t size, const char *where, const char *key)
{
    snprintf(buf, size, "%s%s%s", where, separator(where, key), key);
    return buf;
}

const char *nc_json_path_index(char *buf, size_t size, const char *where, const char *key,
                               int index)
{
    snprintf(buf, size, "%s%s%s[%d]", where, separator(where, key), key, index);
    return buf;
}

/* Short text of a value for messages: the JSON itself, cut to a few dozen characters. */
static void describe(const cJSON *item, char *out, size_t size)
{
    char *text = cJSON_PrintUnformatted(item);
    if (!text) {
        snprintf(out, size, "(unprintable)");
        return;
    }
    if (strlen(text) > 40) strcpy(text + 37, "...");
    snprintf(out, size, "%s", text);
    cJSON_free(text);
}

int nc_json_wrong(nc_error *err, const char *where, const char *key, const char *expected,
                  const cJSON *got)
{
    char shown[64];
    char path[512];
    if (cJSON_IsNumber(got) && !isfinite(got->valuedouble)) /* cJSON would print "null" */
        return nc_error_set(err, 1, "%s: expected %s, got a number out of range",
                            nc_json_path(path, sizeof path, where, key), expected);
    describe(got, shown, sizeof shown);
    return nc_error_set(err, 1, "%s: expected %s, got %s",
                        nc_json_path(path, sizeof path, where, key), expected, shown);
}

static int missing(nc_error *err, const char *where, const char *key, const char *expected)
{
    char path[512];
    return nc_error_set(err, 1, "%s: missing (expected %s)",
                        nc_json_path(path, sizeof path, where, key), expected);
}

/* Path of a value for messages: "nodes[3]", "analysis.dt_s" (appended in place). */
typedef struct tree_path {
    char text[512];
    size_t length;
} tree_path;

static size_t path_push(tree_path *p, const cJSON *parent, const cJSON *item, int index)
{
    size_t saved = p->length;
    size_t room = sizeof p->text - p->length;
    int n = cJSON_IsObject(parent)
                ? snprintf(p->text + p->length, room, "%s%s", p->length ? "." : "",
                           item->string ? item->string : "?")
                : snprintf(p->text + p->length, room, "[%d]", index);
    p->length = n < 0 ? p->length : (size_t)n >= room ? sizeof p->text - 1 : p->length + (size_t)n;
    return saved;
}

static int cmp_key(const void *a, const void *b)
{
    return strcmp(*(const char *const *)a, *(const char *const *)b);
}

/* The first key of `obj` that appears more than once, or NULL; -1 when out of memory.
 * Sorting the keys keeps this O(k log k) for objects with many members. */
static int duplicate_key(const cJSON *obj, const char **dup)
{
    *dup = NULL;
    size_t k = 0;
    for (const cJSON *c = obj->child; c; c = c->next) k++;
    if (k < 2) return 0;
    if (k <= 8) {
        for (const cJSON *a = obj->child; a; a = a->next)
            for (const cJSON *b = a->next; b; b = b->next)
                if (a->string && b->string && strcmp(a->string, b->string) == 0) {
                    *dup = a->string;
                    return 0;
                }
        return 0;
    }
    const char **keys = malloc(k * sizeof *keys);
    if (!keys) return -1;
    size_t n = 0;
    for (const cJSON *c = obj->child; c; c = c->next)
        if (c->string) keys[n++] = c->string;
    qsort(keys, n, sizeof *keys, cmp_key);
    for (size_t i = 1; i < n && !*dup; i++)
        if (strcmp(keys[i], keys[i - 1]) == 0) *dup = keys[i];
    free(keys);
    return 0;
}

/* Rejects what cJSON accepts silently: a key given twice in one object (cJSON would use the
 * first) and a number beyond the range of a double (cJSON stores infinity, printed "null"). */
static int check_tree(const cJSON *item, tree_path *p, const char *name, nc_error *err)
{
    if (cJSON_IsNumber(item) && !isfinite(item->valuedouble))
        return nc_error_set(err, 1, "%s: %s: number out of range (the magnitude of a number "
                                    "must be below 1.8e308)", name, p->length ? p->text : "(top level)");
    if (cJSON_IsObject(item)) {
        const char *dup;
        if (duplicate_key(item, &dup))
            return nc_error_set(err, 1, "%s: out of memory checking the keys", name);
        if (dup) {
            if (p->length) return nc_error_set(err, 1, "%s: %s.%s: key given twice", name, p->text, dup);
            return nc_error_set(err, 1, "%s: %s: key given twice", name, dup);
        }
    }
    if (!cJSON_IsObject(item) && !cJSON_IsArray(item)) return 0;
    int index = 0;
    for (const cJSON *c = item->child; c; c = c->next, index++) {
        size_t saved = path_push(p, item, c, index);
        int rc = check_tree(c, p, name, err);
        p->length = saved;
        p->text[saved] = '\0';
        if (rc) return -1;
    }
    return 0;
}

/* cJSON reads a literal too small for a double (1e-400) as 0 without a word: a user who
 * wrote a wrong exponent would run with zero. Its tree keeps no text, so the literals are
 * found in the source: outside strings, a number token with an exponent (or long enough to
 * spell 300 zeros) that strtod reports as underflowing, although it is not zero, is refused
 * with its line and column. Linear in the size of the text. */
static int check_underflow(const char *name, const char *text, size_t size, nc_error *err)
{
    int in_string = 0, line = 1;
    size_t line_start = 0;
    for (size_t i = 0; i < size; i++) {
        char c = text[i];
        if (c == '\n') { line++; line_start = i + 1; }
        if (in_string) {
            if (c == '\\') i++;
            else if (c == '"') in_string = 0;
            continue;
        }
        if (c == '"') { in_string = 1; continue; }
        if (c != '-' && (c < '0' || c > '9')) continue;
        size_t end = i;
        int exponent = 0, nonzero = 0, in_mantissa = 1;
        while (end < size && text[end] && strchr("0123456789+-.eE", text[end])) {
            if (text[end] == 'e' || text[end] == 'E') { exponent = 1; in_mantissa = 0; }
            else if (in_mantissa && text[end] >= '1' && text[end] <= '9') nonzero = 1;
            end++;
        }
        size_t length = end - i;
        if (nonzero && (exponent || length > 300)) {
            char small[64], *buf = length < sizeof small ? small : malloc(length + 1);
            if (!buf) return nc_error_set(err, 1, "%s: out of memory checking the numbers", name);
            memcpy(buf, text + i, length);
            buf[length] = '\0';
            errno = 0;
            double v = strtod(buf, NULL);
            int underflow = errno == ERANGE && fabs(v) < DBL_MIN;
            if (underflow) {
                nc_error_set(err, 1, "%s:%d:%zu: number %.40s%s is too small for a double "
                             "(non-zero magnitudes must be at least 2.2e-308; it would be read as 0)",
                             name, line, i - line_start + 1, buf, length > 40 ? "..." : "");
            }
            if (buf != small) free(buf);
            if (underflow) return -1;
        }
        i = end - 1;
    }
    return 0;
}

int nc_json_parse_text(const char *name, const char *text, size_t size, cJSON **root,
                       nc_error *err)
{
    *root = NULL;
    if (size == 0) return nc_error_set(err, 1, "%s: file is empty (expected JSON)", name);
    const char *end = NULL;
    cJSON *parsed = cJSON_ParseWithLengthOpts(text, size, &end, 0);
    if (!parsed) {
        int line = 1, column = 1;
        const char *stop = end ? end : text;
        if (stop < text || stop > text + size) stop = text;
        for (const char *c = text; c < stop; c++) {
            if (*c == '\n') { line++; column = 1; } else column++;
        }
        return nc_error_set(err, 1, "%s:%d:%d: malformed JSON near this position", name, line,
                            column);
    }
    if (!cJSON_IsObject(parsed)) {
        cJSON_Delete(parsed);
        return nc_error_set(err, 1, "%s: expected a JSON object at top level", name);
    }
    tree_path path = {{0}, 0};
    if (check_tree(parsed, &path, name, err) || check_underflow(name, text, size, err)) {
        cJSON_Delete(parsed);
        return -1;
    }
    *root = parsed;
    return 0;
}

int nc_json_load_file(const char *path, cJSON **root, nc_error *err)
{
    *root = NULL;
    FILE *file = fopen(path, "rb");
    if (!file) return nc_error_set(err, 1, "%s: cannot open: %s", path, strerror(errno));
    if (fseek(file, 0, SEEK_END) != 0) {
        fclose(file);
        return nc_error_set(err, 1, "%s: cannot read (not a regular file?)", path);
    }
    long size = ftell(file);
    if (size < 0 || size > NC_JSON_MAX_FILE_BYTES) {
        fclose(file);
        return nc_error_set(err, 1, "%s: cannot read or larger than %ld bytes", path,
                            NC_JSON_MAX_FILE_BYTES);
    }
    rewind(file);
    char *text = malloc((size_t)size + 1);
    if (!text) {
        fclose(file);
        return nc_error_set(err, 1, "%s: out of memory reading %ld bytes", path, size);
    }
    size_t got = fread(text, 1, (size_t)size, file);
    fclose(file);
    if (got != (size_t)size) {
        free(text);
        return nc_error_set(err, 1, "%s: short read", path);
    }
    text[size] = '\0';
    int rc = nc_json_parse_text(path, text, (size_t)size, root, err);
    free(text);
    return rc;
}

int nc_json_check_keys(const cJSON *obj, const char *where, const char *const *allowed,
                       nc_error *err)
{
    const cJSON *item;
    cJSON_ArrayForEach(item, obj) {
        int known = 0;
        for (const char *const *a = allowed; *a; a++) {
            if (item->string && strcmp(item->string, *a) == 0) { known = 1; break; }
        }
        if (!known) {
            char list[600] = "";
            for (const char *const *a = allowed; *a; a++) {
                size_t used = strlen(list);
                snprintf(list + used, sizeof list - used, "%s%s", used ? ", " : "", *a);
            }
            char path[512];
            return nc_error_set(err, 1, "%s: unknown key (allowed: %s)",
                                nc_json_path(path, sizeof path, where,
                                             item->string ? item->string : "?"), list);
        }
    }
    return 0;
}

static int get_number(const cJSON *obj, const char *where, const char *key, int required,
                      double fallback, double min, double max, double *out, nc_error *err)
{
    const cJSON *item = cJSON_GetObjectItemCaseSensitive(obj, key);
    char expected[128];
    if (isfinite(min) && isfinite(max)) snprintf(expected, sizeof expected, "a number in [%g, %g]", min, max);
    else if (isfinite(min)) snprintf(expected, sizeof expected, "a number >= %g", min);
    else if (isfinite(max)) snprintf(expected, sizeof expected, "a number <= %g", max);
    else snprintf(expected, sizeof expected, "a number");
    if (!item || cJSON_IsNull(item)) {
        if (required) return missing(err, where, key, expected);
        *out = fallback;
        return 0;
    }
    if (!cJSON_IsNumber(item) || !isfinite(item->valuedouble)) return nc_json_wrong(err, where, key, expected, item);
    double value = item->valuedouble;
    if (value < min || value > max) return nc_json_wrong(err, where, key, expected, item);
    *out = value;
    return 0;
}

int nc_json_number(const cJSON *obj, const char *where, const char *key, double *out,
                   nc_error *err)
{
    return get_number(obj, where, key, 1, 0.0, -INFINITY, INFINITY, out, err);
}

int nc_json_number_opt(const cJSON *obj, const char *where, const char *key, double fallback,
                       double *out, nc_error *err)
{
    return get_number(obj, where, key, 0, fallback, -INFINITY, INFINITY, out, err);
}

int nc_json_number_range(const cJSON *obj, const char *where, const char *key, double min,
                         double max, double *out, nc_error *err)
{
    return get_number(obj, where, key, 1, 0.0, min, max, out, err);
}

int nc_json_number_range_opt(const cJSON *obj, const char *where, const char *key,
                             double fallback, double min, double max, double *out,
                             nc_error *err)
{
    return get_number(obj, where, key, 0, fallback, min, max, out, err);
}

int nc_json_positive(const cJSON *obj, const char *where, const char *key, double *out,
                     nc_error *err)
{
    const cJSON *item = cJSON_GetObjectItemCaseSensitive(obj, key);
    if (!item) return missing(err, where, key, "a number > 0");
    if (!cJSON_IsNumber(item) || !isfinite(item->valuedouble) || !(item->valuedouble > 0.0))
        return nc_json_wrong(err, where, key, "a number > 0", item);
    *out = item->valuedouble;
    return 0;
}

static int get_int(const cJSON *obj, const char *where, const char *key, int required,
                   long fallback, long min, long max, long *out, nc_error *err)
{
    const cJSON *item = cJSON_GetObjectItemCaseSensitive(obj, key);
    char expected[128];
    snprintf(expected, sizeof expected, "a whole number in [%ld, %ld]", min, max);
    if (!item || cJSON_IsNull(item)) {
        if (required) return missing(err, where, key, expected);
        *out = fallback;
        return 0;
    }
    if (!cJSON_IsNumber(item)) return nc_json_wrong(err, where, key, expected, item);
    double value = item->valuedouble;
    if (!isfinite(value) || value != floor(value) || value < (double)min || value > (double)max)
        return nc_json_wrong(err, where, key, expected, item);
    *out = (long)value;
    return 0;
}

int nc_json_int(const cJSON *obj, const char *where, const char *key, long min, long max,
                long *out, nc_error *err)
{
    return get_int(obj, where, key, 1, 0, min, max, out, err);
}

int nc_json_int_opt(const cJSON *obj, const char *where, const char *key, long fallback,
                    long min, long max, long *out, nc_error *err)
{
    return get_int(obj, where, key, 0, fallback, min, max, out, err);
}

int nc_json_bool_opt(const cJSON *obj, const char *where, const char *key, int fallback,
                     int *out, nc_error *err)
{
    const cJSON *item = cJSON_GetObjectItemCaseSensitive(obj, key);
    if (!item || cJSON_IsNull(item)) {
        *out = fallback;
        return 0;
    }
    if (!cJSON_IsBool(item)) return nc_json_wrong(err, where, key, "true or false", item);
    *out = cJSON_IsTrue(item);
    return 0;
}

int nc_json_string(const cJSON *obj, const char *where, const char *key, const char **out,
                   nc_error *err)
{
    const cJSON *item = cJSON_GetObjectItemCaseSensitive(obj, key);
    if (!item) return missing(err, where, key, "a string");
    if (!cJSON_IsString(item) || !item->valuestring) return nc_json_wrong(err, where, key, "a string", item);
    *out = item->valuestring;
    return 0;
}

int nc_json_string_opt(const cJSON *obj, const char *where, const char *key,
                       const char *fallback, const char **out, nc_error *err)
{
    const cJSON *item = cJSON_GetObjectItemCaseSensitive(obj, key);
    if (!item || cJSON_IsNull(item)) {
        *out = fallback;
        return 0;
    }
    return nc_json_string(obj, where, key, out, err);
}

int nc_json_choice_opt(const cJSON *obj, const char *where, const char *key,
                       const char *const *choices, int fallback_index, int *index,
                       nc_error *err)
{
    char expected[400] = "one of";
    for (const char *const *c = choices; *c; c++) {
        size_t used = strlen(expected);
        snprintf(expected + used, sizeof expected - used, "%s \"%s\"", c == choices ? "" : ",", *c);
    }
    const cJSON *item = cJSON_GetObjectItemCaseSensitive(obj, key);
    if (!item || cJSON_IsNull(item)) {
        if (fallback_index < 0) return missing(err, where, key, expected);
        *index = fallback_index;
        return 0;
    }
    if (!cJSON_IsString(item)) return nc_json_wrong(err, where, key, expected, item);
    for (int i = 0; choices[i]; i++) {
        if (strcmp(item->valuestring, choices[i]) == 0) {
            *index = i;
            return 0;
        }
    }
    return nc_json_wrong(err, where, key, expected, item);
}

int nc_json_vec3(const cJSON *obj, const char *where, const char *key, double out[3],
                 nc_error *err)
{
    const cJSON *item = cJSON_GetObjectItemCaseSensitive(obj, key);
    if (!item) return missing(err, where, key, "[x, y, z]");
    if (!cJSON_IsArray(item) || cJSON_GetArraySize(item) != 3)
        return nc_json_wrong(err, where, key, "[x, y, z] (3 numbers)", item);
    int i = 0;
    for (const cJSON *c = item->child; c; c = c->next, i++) {
        if (!cJSON_IsNumber(c) || !isfinite(c->valuedouble))
            return nc_json_wrong(err, where, key, "[x, y, z] (3 finite numbers)", item);
        out[i] = c->valuedouble;
    }
    return 0;
}

int nc_json_vec3_opt(const cJSON *obj, const char *where, const char *key,
                     const double fallback[3], double out[3], nc_error *err)
{
    const cJSON *item = cJSON_GetObjectItemCaseSensitive(obj, key);
    if (!item || cJSON_IsNull(item)) {
        for (int i = 0; i < 3; i++) out[i] = fallback[i];
        return 0;
    }
    return nc_json_vec3(obj, where, key, out, err);
}

int nc_json_array(const cJSON *obj, const char *where, const char *key, const cJSON **arr,
                  int *count, nc_error *err)
{
    const cJSON *item = cJSON_GetObjectItemCaseSensitive(obj, key);
    if (!item) return missing(err, where, key, "an array");
    if (!cJSON_IsArray(item)) return nc_json_wrong(err, where, key, "an array", item);
    *arr = item;
    *count = cJSON_GetArraySize(item);
    return 0;
}

int nc_json_array_opt(const cJSON *obj, const char *where, const char *key, const cJSON **arr,
                      int *count, nc_error *err)
{
    const cJSON *item = cJSON_GetObjectItemCaseSensitive(obj, key);
    if (!item || cJSON_IsNull(item)) {
        *arr = NULL;
        *count = 0;
        return 0;
    }
    return nc_json_array(obj, where, key, arr, count, err);
}

int nc_json_object(const cJSON *obj, const char *where, const char *key, const cJSON **out,
                   nc_error *err)
{
    const cJSON *item = cJSON_GetObjectItemCaseSensitive(obj, key);
    if (!item) return missing(err, where, key, "an object {...}");
    if (!cJSON_IsObject(item)) return nc_json_wrong(err, where, key, "an object {...}", item);
    *out = item;
    return 0;
}

int nc_json_object_opt(const cJSON *obj, const char *where, const char *key,
                       const cJSON **out, nc_error *err)
{
    const cJSON *item = cJSON_GetObjectItemCaseSensitive(obj, key);
    if (!item || cJSON_IsNull(item)) {
        *out = NULL;
        return 0;
    }
    return nc_json_object(obj, where, key, out, err);
}
