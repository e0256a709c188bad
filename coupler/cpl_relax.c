/* cpl_relax — dispatch of the relaxation methods (none, constant, Aitken, IQN-ILS). */
#include "cpl_relax.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "cpl_relax_aitken.h"
#include "cpl_relax_iqn.h"

struct cpl_relax {
    cpl_relax_settings s;
    size_t n;
    cpl_aitken aitken;
    cpl_iqn iqn;
};

void cpl_relax_settings_default(cpl_relax_settings *s)
{
    memset(s, 0, sizeof *s);
    s->method = CPL_RELAX_NONE;
    s->alpha = 0.5;
    s->first_cap = 0.5;
    s->alpha_min = 1e-6;
    s->alpha_max = 2.0;
    s->restart_growth = 4.0; /* Aitken safeguard on (see cpl_relax_aitken.h) */
    s->iqn_filter = 1e-2;   /* "QR2" filter limit commonly used with IQN-ILS */
    s->iqn_reuse_steps = 4;
    s->iqn_max_columns = 0;
}

const char *cpl_relax_method_name(cpl_relax_method m)
{
    switch (m) {
    case CPL_RELAX_NONE: return "none";
    case CPL_RELAX_CONSTANT: return "constant";
    case CPL_RELAX_AITKEN: return "aitken";
    case CPL_RELAX_IQN_ILS: return "iqn-ils";
    }
    return "unknown";
}

int cpl_relax_create(cpl_relax **out, const cpl_relax_settings *s, size_t n, size_t n_blocks,
                     nc_error *err)
{
    *out = NULL;
    cpl_relax *r = calloc(1, sizeof *r);
    if (!r) return nc_error_set(err, 1, "relaxation: out of memory");
    r->s = *s;
    r->n = n;
    int rc = 0;
    if (s->method == CPL_RELAX_AITKEN) {
        rc = cpl_aitken_init(&r->aitken, n, n_blocks, s->alpha, s->first_cap, s->alpha_min,
                             s->alpha_max, err);
        r->aitken.restart_growth = s->restart_growth;
    }
    else if (s->method == CPL_RELAX_IQN_ILS)
        rc = cpl_iqn_init(&r->iqn, n, s->iqn_max_columns > 0 ? (size_t)s->iqn_max_columns : 0,
                          s->alpha, s->iqn_filter, s->iqn_reuse_steps, err);
    if (rc) {
        free(r);
        return -1;
    }
    *out = r;
    return 0;
}

void cpl_relax_free(cpl_relax *r)
{
    if (!r) return;
    cpl_aitken_free(&r->aitken);
    cpl_iqn_free(&r->iqn);
    free(r);
}

void cpl_relax_begin_step(cpl_relax *r)
{
    if (r->s.method == CPL_RELAX_AITKEN) cpl_aitken_begin_step(&r->aitken);
    else if (r->s.method == CPL_RELAX_IQN_ILS) cpl_iqn_begin_step(&r->iqn);
}

int cpl_relax_update(cpl_relax *r, const double *x_in, const double *x_out, double *x_next,
                     double *alpha, nc_error *err)
{
    double a = 1.0;
    switch (r->s.method) {
    case CPL_RELAX_NONE:
        memmove(x_next, x_out, r->n * sizeof(double));   /* eqs. (37)–(39) */
        break;
    case CPL_RELAX_CONSTANT:
        a = r->s.alpha;
        for (size_t i = 0; i < r->n; i++) x_next[i] = x_in[i] + a * (x_out[i] - x_in[i]);
        break;
    case CPL_RELAX_AITKEN:
        a = cpl_aitken_update(&r->aitken, x_in, x_out, x_next);
        break;
    case CPL_RELAX_IQN_ILS:
        a = cpl_iqn_update(&r->iqn, x_in, x_out, x_next);
        break;
    }
    for (size_t i = 0; i < r->n; i++)
        if (!isfinite(x_next[i]))
            return nc_error_set(err, 1, "%s relaxation produced a non-finite interface value "
                                "(entry %zu); the coupling iteration diverged",
                                cpl_relax_method_name(r->s.method), i);
    if (alpha) *alpha = a;
    return 0;
}

void cpl_relax_forget_pair(cpl_relax *r)
{
    r->aitken.have_prev = 0;
    r->iqn.have_prev = 0;
}

void cpl_relax_forget_history(cpl_relax *r)
{
    r->aitken.have_prev = 0;
    r->aitken.have_alpha = 0;   /* next step starts again from α0 */
    r->iqn.have_prev = 0;
    r->iqn.cols = 0;
}

void cpl_relax_end_step(cpl_relax *r, const double *x_in, const double *x_out)
{
    if (r->s.method == CPL_RELAX_IQN_ILS && x_in && x_out) cpl_iqn_end_step(&r->iqn, x_in, x_out);
}
