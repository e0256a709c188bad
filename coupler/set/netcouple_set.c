/* netcouple-set — the --set overrides of scripts/run_case.sh, applied to a run folder's copies
 * of the input files:
 *
 *   netcouple-set DIR FILE.KEY=VALUE ...
 *
 * FILE is fem, dem or coupler (DIR/FILE.json); KEY a dotted path in it, numbers indexing
 * lists (dem.materials.0.restitution, or dem.materials[0].restitution). VALUE is JSON when
 * it parses as JSON (0.2, true, [1, 2], {"a": 1}), else a string. A missing key of an object
 * is added, missing objects on the way are created; an index must exist (brackets hold
 * nothing else). Each file touched is written once, after every override was applied,
 * through a temporary file and a rename (indented by two spaces). On
 * any error nothing is written, a message names the override (or the file) and the exit
 * status is 2, as run_case.sh's own argument errors.
 *
 * A C program rather than the interpreter the launcher used before: Python starts in about
 * 50 ms, a noticeable part of a short run.
 */
#include <ctype.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cjson/cJSON.h>

#include "nc_error.h"
#include "nc_file.h"
#include "nc_json.h"

static const char *const FILES[] = {"fem", "dem", "coupler"};
#define N_FILES 3

static const char *kind_of(const cJSON *node)
{
    if (cJSON_IsNumber(node)) return "number";
    if (cJSON_IsString(node)) return "string";
    if (cJSON_IsBool(node)) return "boolean";
    if (cJSON_IsNull(node)) return "null";
    return "value";
}

static int is_index(const char *key)
{
    if (!*key) return 0;
    for (const char *c = key; *c; c++)
        if (!isdigit((unsigned char)*c)) return 0;
    return 1;
}

/* KEY written with list indices in brackets, as in JSONPath or Python (particles[0].radius),
 * becomes the dotted form in place (particles.0.radius: never longer). -1 when a bracket
 * holds anything but digits or is not followed by '.', '[' or the end. */
static int brackets_to_dots(char *key)
{
    char *out = key;
    for (const char *c = key; *c;) {
        if (*c == ']') return -1;
        if (*c != '[') {
            *out++ = *c++;
            continue;
        }
        c++;
        if (!isdigit((unsigned char)*c)) return -1;
        *out++ = '.';
        while (isdigit((unsigned char)*c)) *out++ = *c++;
        if (*c++ != ']' || (*c && *c != '.' && *c != '[')) return -1;
    }
    *out = '\0';
    return 0;
}

/* Applies one override (`set`, the argument as given) to docs[]; loads the file on first use. */
static int apply(const char *dir, const char *set, cJSON **docs, nc_error *err)
{
    const char *equals = strchr(set, '=');
    const char *dot = strchr(set, '.');
    if (!equals || !dot || dot > equals)
        return nc_error_set(err, 2, "--set '%s': expected FILE.KEY=VALUE, e.g. coupler.dt=0.001", set);
    int f = -1;
    for (int i = 0; i < N_FILES; i++)
        if ((size_t)(dot - set) == strlen(FILES[i]) && strncmp(set, FILES[i], strlen(FILES[i])) == 0) f = i;
    if (f < 0) return nc_error_set(err, 2, "--set '%s': FILE must be fem, dem or coupler", set);
    if (!docs[f]) {
        char path[4200];
        snprintf(path, sizeof path, "%s/%s.json", dir, FILES[f]);
        if (nc_json_load_file(path, &docs[f], err)) return -1;
    }
    const char *raw = equals + 1;
    cJSON *value = cJSON_ParseWithOpts(raw, NULL, 1);
    if (!value) value = cJSON_CreateString(raw);
    if (!value) return nc_error_set(err, 2, "--set '%s': out of memory", set);

    char path[1024];
    size_t len = (size_t)(equals - dot - 1);
    if (len >= sizeof path) {
        cJSON_Delete(value);
        return nc_error_set(err, 2, "--set '%s': KEY too long", set);
    }
    memcpy(path, dot + 1, len);
    path[len] = '\0';
    if (brackets_to_dots(path)) {
        cJSON_Delete(value);
        return nc_error_set(err, 2, "--set '%s': brackets in KEY hold a list index only "
                            "(dem.particles[0].radius, or dem.particles.0.radius)", set);
    }
    cJSON *node = docs[f];
    char *key = path;
    for (;;) {
        char *next = strchr(key, '.');
        if (next) *next = '\0';
        if (!*key) {
            cJSON_Delete(value);
            return nc_error_set(err, 2, "--set '%s': an empty name in KEY", set);
        }
        cJSON *child = NULL;
        if (cJSON_IsArray(node)) {
            int n = cJSON_GetArraySize(node);
            long at = is_index(key) && strlen(key) < 10 ? atol(key) : -1;
            if (at < 0 || at >= n) {
                cJSON_Delete(value);
                return nc_error_set(err, 2, "--set '%s': '%s' is not an index of a list of %d item%s",
                                    set, key, n, n == 1 ? "" : "s");
            }
            if (!next) {
                cJSON_ReplaceItemInArray(node, (int)at, value);
                return 0;
            }
            child = cJSON_GetArrayItem(node, (int)at);
        } else if (cJSON_IsObject(node)) {
            child = cJSON_GetObjectItemCaseSensitive(node, key);
            if (!next) {
                if (child) cJSON_ReplaceItemInObjectCaseSensitive(node, key, value);
                else cJSON_AddItemToObject(node, key, value);
                return 0;
            }
            if (!child) {
                child = cJSON_CreateObject();
                if (!child) {
                    cJSON_Delete(value);
                    return nc_error_set(err, 2, "--set '%s': out of memory", set);
                }
                cJSON_AddItemToObject(node, key, child);
            }
        } else {
            cJSON_Delete(value);
            return nc_error_set(err, 2, "--set '%s': '%s' is inside a %s, not an object or list",
                                set, key, kind_of(node));
        }
        node = child;
        key = next + 1;
    }
}

/* cJSON's formatted text with two spaces instead of its tabs (JSON strings hold no raw tab:
 * every tab of the text is layout). */
static int write_doc(const char *dir, const char *name, const cJSON *doc, nc_error *err)
{
    char path[4200], tmp[4220];
    snprintf(path, sizeof path, "%s/%s.json", dir, name);
    char *text = cJSON_Print(doc);
    if (!text) return nc_error_set(err, 1, "%s: out of memory", path);
    FILE *f = nc_file_replace_open(path, tmp, sizeof tmp, err);
    if (!f) {
        free(text);
        return -1;
    }
    int line_start = 1;
    for (const char *c = text; *c; c++) {
        if (*c == '\t') fputs(line_start ? "  " : " ", f);
        else {
            fputc(*c, f);
            line_start = *c == '\n';
        }
    }
    fputc('\n', f);
    free(text);
    return nc_file_replace_commit(f, tmp, path, err);
}

int main(int argc, char **argv)
{
    if (argc < 3 || argv[1][0] == '-') {
        fprintf(stderr, "usage: netcouple-set DIR FILE.KEY=VALUE ...\n"
                        "Applies run_case.sh's --set overrides to DIR/fem.json, dem.json, coupler.json.\n");
        return 2;
    }
    cJSON *docs[N_FILES] = {NULL, NULL, NULL};
    nc_error err;
    nc_error_clear(&err);
    int rc = 0;
    for (int i = 2; i < argc && rc == 0; i++) rc = apply(argv[1], argv[i], docs, &err);
    for (int f = 0; f < N_FILES && rc == 0; f++)
        if (docs[f]) rc = write_doc(argv[1], FILES[f], docs[f], &err);
    for (int f = 0; f < N_FILES; f++) cJSON_Delete(docs[f]);
    if (rc) {
        fprintf(stderr, "run_case: %s\n", err.message);
        return 2;
    }
    return 0;
}
