/* cpl_relax — the relaxation interface: settings of the `relaxation` object and one
 * relaxation object, both calling through the chosen method's table of operations
 * (cpl_relax_ops.h). The only thing done here for every method is the finiteness check of
 * the next input. */
#include "cpl_relax.h"

#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cpl_relax_ops.h"
#include "nc_json.h"

enum { MAX_METHODS = 16, MAX_KEYS = 64 };

struct cpl_relax {
    const cpl_relax_ops *ops;
    void *state;
    size_t n;
};

void cpl_relax_settings_default(cpl_relax_settings *s)
{
    memset(s, 0, sizeof *s);
    s->method = cpl_relax_method_find("none");
    s->alpha = 0.5;
}

static void use_method(cpl_relax_settings *s, const cpl_relax_ops *m)
{
    s->method = m;
    memset(s->params, 0, sizeof s->params);
    if (m->defaults) m->defaults(s);
}

/* "one of \"none\", \"constant\", ..." for messages */
static const char *method_names(char *buf, size_t size)
{
    snprintf(buf, size, "one of");
    for (const cpl_relax_ops *const *m = cpl_relax_methods(); *m; m++) {
        size_t used = strlen(buf);
        snprintf(buf + used, size - used, "%s \"%s\"", m == cpl_relax_methods() ? "" : ",",
                 (*m)->name);
    }
    return buf;
}

int cpl_relax_settings_select(cpl_relax_settings *s, const char *method, nc_error *err)
{
    const cpl_relax_ops *m = cpl_relax_method_find(method);
    if (!m) {
        char names[400];
        return nc_error_set(err, 1, "relaxation method \"%s\" unknown: expected %s", method,
                            method_names(names, sizeof names));
    }
    use_method(s, m);
    return 0;
}

const char *cpl_relax_settings_method(const cpl_relax_settings *s)
{
    return s->method->name;
}

double cpl_relax_method_id(const char *name)
{
    uint32_t h = 2166136261u;
    for (const unsigned char *c = (const unsigned char *)name; *c; c++) {
        h ^= *c;
        h *= 16777619u;
    }
    return (double)h;
}

const char *cpl_relax_method_name(double id)
{
    for (const cpl_relax_ops *const *m = cpl_relax_methods(); *m; m++)
        if (cpl_relax_method_id((*m)->name) == id) return (*m)->name;
    return NULL;
}

/* alpha and the keys of every method (unknown keys rejected); the chosen method's values
 * are kept, the others only checked. */
static int parse_keys(cpl_relax_settings *s, const cJSON *obj, const char *where, int check,
                      nc_error *err)
{
    const char *keys[MAX_KEYS] = {"method", "alpha"};
    size_t n_keys = 2;
    for (const cpl_relax_ops *const *m = cpl_relax_methods(); *m; m++)
        for (const char *const *k = (*m)->keys; k && *k && n_keys + 1 < MAX_KEYS; k++)
            keys[n_keys++] = *k;
    keys[n_keys] = NULL;
    if (nc_json_check_keys(obj, where, keys, err) ||
        nc_json_number_range_opt(obj, where, "alpha", s->alpha, 1e-12, 2.0, &s->alpha, err))
        return -1;
    if (cJSON_GetObjectItemCaseSensitive(obj, "alpha")) s->alpha_given = 1;
    /* all methods read their keys first, then all check them: the first error is the same
     * whichever method is chosen */
    cpl_relax_settings each[MAX_METHODS];
    size_t n_methods = 0;
    for (const cpl_relax_ops *const *m = cpl_relax_methods(); *m && n_methods < MAX_METHODS;
         m++) {
        cpl_relax_settings *t = &each[n_methods++];
        *t = *s;
        if (*m != s->method) use_method(t, *m);
        if ((*m)->parse && (*m)->parse(t, obj, where, err)) return -1;
    }
    for (size_t i = 0; check && i < n_methods; i++)
        if (each[i].method->check && each[i].method->check(&each[i], where, err)) return -1;
    for (size_t i = 0; i < n_methods; i++)
        if (each[i].method == s->method) *s = each[i];
    return 0;
}

int cpl_relax_settings_parse(cpl_relax_settings *s, const cJSON *obj, const char *where,
                             nc_error *err)
{
    const cpl_relax_ops *const *methods = cpl_relax_methods();
    const char *names[MAX_METHODS + 1];
    int n = 0, index = 0;
    for (; methods[n] && n < MAX_METHODS; n++) {
        if (methods[n] == s->method) index = n;
        names[n] = methods[n]->name;
    }
    names[n] = NULL;
    if (nc_json_choice_opt(obj, where, "method", names, index, &index, err)) return -1;
    if (methods[index] != s->method) use_method(s, methods[index]);
    return parse_keys(s, obj, where, 1, err);
}

int cpl_relax_settings_set(cpl_relax_settings *s, const char *key, double value,
                           nc_error *err)
{
    if (strcmp(key, "method") == 0)
        return nc_error_set(err, 1, "relaxation: method is a name (cpl_relax_settings_select)");
    cJSON *obj = cJSON_CreateObject();
    if (!obj || !cJSON_AddNumberToObject(obj, key, value)) {
        cJSON_Delete(obj);
        return nc_error_set(err, 1, "relaxation: out of memory");
    }
    int rc = parse_keys(s, obj, "relaxation", 0, err);
    cJSON_Delete(obj);
    return rc;
}

int cpl_relax_settings_get(const cpl_relax_settings *s, const char *key, double *value)
{
    if (strcmp(key, "alpha") == 0) {
        *value = s->alpha;
        return 0;
    }
    return s->method->get ? s->method->get(s, key, value) : -1;
}

int cpl_relax_settings_check(const cpl_relax_settings *s, const char *where, nc_error *err)
{
    return s->method->check ? s->method->check(s, where, err) : 0;
}

int cpl_relax_check_alpha(const cpl_relax_settings *s, const char *where, nc_error *err)
{
    if (!(s->alpha > 0.0 && s->alpha <= 2.0))
        return nc_error_set(err, 1, "%s: alpha must be in (0, 2], got %g", where, s->alpha);
    return 0;
}

int cpl_relax_create(cpl_relax **out, const cpl_relax_settings *s, size_t n, size_t n_blocks,
                     nc_error *err)
{
    *out = NULL;
    cpl_relax *r = calloc(1, sizeof *r);
    if (!r) return nc_error_set(err, 1, "relaxation: out of memory");
    r->ops = s->method;
    r->n = n;
    if (r->ops->create(&r->state, s, n, n_blocks, err)) {
        free(r);
        return -1;
    }
    *out = r;
    return 0;
}

void cpl_relax_free(cpl_relax *r)
{
    if (!r) return;
    r->ops->free(r->state);
    free(r);
}

void cpl_relax_begin_step(cpl_relax *r)
{
    if (r->ops->begin_step) r->ops->begin_step(r->state);
}

void cpl_relax_set_linearised(cpl_relax *r, int on)
{
    if (r->ops->linearised) r->ops->linearised(r->state, on);
}

int cpl_relax_update(cpl_relax *r, const double *x_in, const double *x_out, double *x_next,
                     double *alpha, nc_error *err)
{
    double a = r->ops->update(r->state, x_in, x_out, x_next);
    for (size_t i = 0; i < r->n; i++)
        if (!isfinite(x_next[i]))
            return nc_error_set(err, CPL_RELAX_ERR_NOT_FINITE,
                                "%s relaxation produced a non-finite interface value "
                                "(entry %zu); the coupling iteration diverged",
                                r->ops->name, i);
    if (alpha) *alpha = a;
    return 0;
}

void cpl_relax_forget(cpl_relax *r, cpl_relax_forget_level level)
{
    if (r->ops->forget) r->ops->forget(r->state, level);
}

void cpl_relax_end_step(cpl_relax *r, const double *x_in, const double *x_out)
{
    if (r->ops->end_step) r->ops->end_step(r->state, x_in, x_out);
}

int cpl_relax_counter(const cpl_relax *r, const char *name, double *value)
{
    return r->ops->counter ? r->ops->counter(r->state, name, value) : -1;
}

void cpl_relax_checkpoint_entries(cpl_relax *r, cpl_ckpt_table *t, const char *prefix)
{
    if (r->ops->checkpoint) r->ops->checkpoint(r->state, t, prefix);
}
