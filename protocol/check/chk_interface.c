/* chk_interface — interface mesh of netcouple-check (chk_interface.h). */
#include "chk_interface.h"

#include <cjson/cJSON.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

void chk_interface_free(chk_interface *f)
{
    free(f->node_ids);
    free(f->coords);
    free(f->elements);
    memset(f, 0, sizeof *f);
}

static int allocate(chk_interface *f, size_t n, size_t m, nc_error *err)
{
    chk_interface_free(f);
    f->n = n;
    f->m = m;
    f->node_ids = malloc((n ? n : 1) * sizeof *f->node_ids);
    f->coords = malloc((n ? n : 1) * 3 * sizeof *f->coords);
    f->elements = malloc((m ? m : 1) * 2 * sizeof *f->elements);
    if (!f->node_ids || !f->coords || !f->elements) {
        chk_interface_free(f);
        return nc_error_set(err, 1, "out of memory for an interface of %zu nodes", n);
    }
    return 0;
}

/* Element indices in range, node ids >= 0 and distinct, at least one node. */
static int check(const chk_interface *f, nc_error *err)
{
    if (f->n == 0) return nc_error_set(err, 1, "no interface nodes");
    for (size_t e = 0; e < 2 * f->m; e++)
        if (f->elements[e] < 0 || (size_t)f->elements[e] >= f->n)
            return nc_error_set(err, 1, "elements[%zu] = %d is not an index into the %zu nodes",
                                e / 2, f->elements[e], f->n);
    for (size_t e = 0; e < f->m; e++)
        if (f->elements[2 * e] == f->elements[2 * e + 1])
            return nc_error_set(err, 1, "element %zu joins node %d to itself", e, f->elements[2 * e]);
    for (size_t i = 0; i < f->n; i++) {
        if (f->node_ids[i] < 0) return nc_error_set(err, 1, "node_ids[%zu] = %d is negative", i, f->node_ids[i]);
        if (!isfinite(f->coords[3 * i]) || !isfinite(f->coords[3 * i + 1]) || !isfinite(f->coords[3 * i + 2]))
            return nc_error_set(err, 1, "coordinates[%zu] is not finite", i);
    }
    /* distinct ids: sort a copy */
    int32_t *ids = malloc(f->n * sizeof *ids);
    if (!ids) return nc_error_set(err, 1, "out of memory");
    memcpy(ids, f->node_ids, f->n * sizeof *ids);
    for (size_t i = 1; i < f->n; i++) { /* insertion sort: interfaces are small */
        int32_t x = ids[i];
        size_t j = i;
        while (j > 0 && ids[j - 1] > x) { ids[j] = ids[j - 1]; j--; }
        ids[j] = x;
    }
    int dup = -1;
    for (size_t i = 1; i < f->n && dup < 0; i++)
        if (ids[i] == ids[i - 1]) dup = ids[i];
    free(ids);
    if (dup >= 0) return nc_error_set(err, 1, "node id %d appears twice in node_ids", dup);
    return 0;
}

int chk_interface_synthetic(chk_interface *f, nc_error *err)
{
    if (allocate(f, 9, 12, err)) return -1;
    size_t e = 0;
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++) {
            int k = 3 * i + j;
            f->node_ids[k] = k;
            f->coords[3 * k] = -0.5 + 0.5 * i;
            f->coords[3 * k + 1] = -0.5 + 0.5 * j;
            f->coords[3 * k + 2] = 0.0;
            if (i < 2) { f->elements[2 * e] = k; f->elements[2 * e + 1] = k + 3; e++; }
            if (j < 2) { f->elements[2 * e] = k; f->elements[2 * e + 1] = k + 1; e++; }
        }
    return 0;
}

int chk_interface_from_reply(chk_interface *f, const proto_message *reply, nc_error *err)
{
    const int32_t *ids, *elements;
    const double *coords;
    size_t n = 0, m = 0, rows = 0;
    if (proto_message_get_i32(reply, "node_ids", 0, 0, &ids, &n, err)) return -1;
    const proto_array *a = proto_message_find(reply, "node_ids");
    if (a->ndim != 1 && a->shape[1] != 1)
        return nc_error_set(err, 1, "node_ids has shape [%zu, %zu], expected [n]", a->shape[0], a->shape[1]);
    if (proto_message_get_f64(reply, "coordinates", n, 3, &coords, &rows, err)) return -1;
    if (proto_message_get_i32(reply, "elements", 0, 2, &elements, &m, err)) return -1;
    if (allocate(f, n, m, err)) return -1;
    memcpy(f->node_ids, ids, n * sizeof *ids);
    memcpy(f->coords, coords, 3 * n * sizeof *coords);
    memcpy(f->elements, elements, 2 * m * sizeof *elements);
    if (check(f, err)) {
        chk_interface_free(f);
        return -1;
    }
    return 0;
}

static int number_list(const cJSON *item, double *out, size_t count)
{
    if (!cJSON_IsArray(item) || (size_t)cJSON_GetArraySize(item) != count) return -1;
    size_t k = 0;
    const cJSON *x;
    cJSON_ArrayForEach(x, item) {
        if (!cJSON_IsNumber(x)) return -1;
        out[k++] = x->valuedouble;
    }
    return 0;
}

static int whole(double x, int32_t *out)
{
    if (x != floor(x) || x < -2147483648.0 || x > 2147483647.0) return -1;
    *out = (int32_t)x;
    return 0;
}

int chk_interface_read(chk_interface *f, const char *path, nc_error *err)
{
    FILE *file = fopen(path, "rb");
    if (!file) return nc_error_set(err, 1, "%s: cannot open", path);
    fseek(file, 0, SEEK_END);
    long size = ftell(file);
    fseek(file, 0, SEEK_SET);
    char *text = size >= 0 ? malloc((size_t)size + 1) : NULL;
    size_t got = text ? fread(text, 1, (size_t)size, file) : 0;
    fclose(file);
    if (!text || got != (size_t)size) {
        free(text);
        return nc_error_set(err, 1, "%s: cannot read", path);
    }
    text[got] = '\0';
    cJSON *root = cJSON_Parse(text);
    free(text);
    if (!cJSON_IsObject(root)) {
        cJSON_Delete(root);
        return nc_error_set(err, 1, "%s: not a JSON object", path);
    }
    const cJSON *ids = cJSON_GetObjectItemCaseSensitive(root, "node_ids");
    const cJSON *coords = cJSON_GetObjectItemCaseSensitive(root, "coordinates");
    const cJSON *elements = cJSON_GetObjectItemCaseSensitive(root, "elements");
    int rc = 0;
    const char *field = NULL;
    if (!cJSON_IsArray(ids)) field = "node_ids";
    else if (!cJSON_IsArray(coords) || cJSON_GetArraySize(coords) != cJSON_GetArraySize(ids)) field = "coordinates";
    else if (!cJSON_IsArray(elements)) field = "elements";
    if (field) {
        cJSON_Delete(root);
        return nc_error_set(err, 1, "%s: field '%s': expected a list (node_ids [n], coordinates "
                            "[n][3], elements [m][2])", path, field);
    }
    size_t n = (size_t)cJSON_GetArraySize(ids), m = (size_t)cJSON_GetArraySize(elements);
    if (allocate(f, n, m, err)) {
        cJSON_Delete(root);
        return -1;
    }
    size_t k = 0;
    const cJSON *x;
    cJSON_ArrayForEach(x, ids) {
        if (!cJSON_IsNumber(x) || whole(x->valuedouble, &f->node_ids[k])) {
            rc = nc_error_set(err, 1, "%s: node_ids[%zu]: expected a whole number", path, k);
            break;
        }
        k++;
    }
    k = 0;
    cJSON_ArrayForEach(x, coords) {
        if (rc) break;
        if (number_list(x, &f->coords[3 * k], 3))
            rc = nc_error_set(err, 1, "%s: coordinates[%zu]: expected 3 numbers", path, k);
        k++;
    }
    k = 0;
    cJSON_ArrayForEach(x, elements) {
        if (rc) break;
        double pair[2];
        if (number_list(x, pair, 2) || whole(pair[0], &f->elements[2 * k]) ||
            whole(pair[1], &f->elements[2 * k + 1]))
            rc = nc_error_set(err, 1, "%s: elements[%zu]: expected 2 node indices", path, k);
        k++;
    }
    cJSON_Delete(root);
    if (!rc && check(f, err)) rc = nc_error_prefix(err, "%s", path);
    if (rc) chk_interface_free(f);
    return rc;
}

int chk_interface_write(const chk_interface *f, const char *path, nc_error *err)
{
    FILE *file = fopen(path, "w");
    if (!file) return nc_error_set(err, 1, "%s: cannot create", path);
    fprintf(file, "{\n  \"node_ids\": [");
    for (size_t i = 0; i < f->n; i++) fprintf(file, "%s%d", i ? ", " : "", f->node_ids[i]);
    fprintf(file, "],\n  \"coordinates\": [");
    for (size_t i = 0; i < f->n; i++)
        fprintf(file, "%s\n    [%.17g, %.17g, %.17g]", i ? "," : "", f->coords[3 * i],
                f->coords[3 * i + 1], f->coords[3 * i + 2]);
    fprintf(file, "],\n  \"elements\": [");
    for (size_t e = 0; e < f->m; e++)
        fprintf(file, "%s[%d, %d]", e ? ", " : "", f->elements[2 * e], f->elements[2 * e + 1]);
    fprintf(file, "]\n}\n");
    if (fclose(file) != 0) return nc_error_set(err, 1, "%s: cannot write", path);
    return 0;
}

int chk_interface_add(const chk_interface *f, proto_message *m, nc_error *err)
{
    if (proto_message_add_i32(m, "node_ids", f->node_ids, f->n, 0, err) ||
        proto_message_add_f64(m, "coordinates", f->coords, f->n, 3, err) ||
        proto_message_add_i32(m, "elements", f->elements, f->m, 2, err))
        return -1;
    return 0;
}

size_t chk_interface_central_node(const chk_interface *f)
{
    double c[3] = {0, 0, 0};
    for (size_t i = 0; i < f->n; i++)
        for (int d = 0; d < 3; d++) c[d] += f->coords[3 * i + d] / (double)f->n;
    size_t best = 0;
    double best_d2 = INFINITY;
    for (size_t i = 0; i < f->n; i++) {
        double d2 = 0;
        for (int d = 0; d < 3; d++) d2 += (f->coords[3 * i + d] - c[d]) * (f->coords[3 * i + d] - c[d]);
        if (d2 < best_d2) { best_d2 = d2; best = i; }
    }
    return best;
}
