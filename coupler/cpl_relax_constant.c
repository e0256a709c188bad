/* cpl_relax_constant — constant under-relaxation, eqs. (31)–(33):
 *   x^{k+1} = x^k + α r^k,  r^k = x̃^k − x^k,  α = relaxation.alpha (common key).
 * No keys of its own. */
#include "cpl_relax_ops.h"

#include <stdlib.h>

typedef struct constant_state {
    size_t n;
    double alpha;
} constant_state;

static int constant_create(void **state, const cpl_relax_settings *s, size_t n,
                           size_t n_blocks, nc_error *err)
{
    (void)n_blocks;
    constant_state *st = malloc(sizeof *st);
    if (!st) return nc_error_set(err, 1, "constant: out of memory");
    st->n = n;
    st->alpha = s->alpha;
    *state = st;
    return 0;
}

static double constant_update(void *state, const double *x_in, const double *x_out,
                              double *x_next)
{
    const constant_state *st = state;
    const double a = st->alpha;
    for (size_t i = 0; i < st->n; i++) x_next[i] = x_in[i] + a * (x_out[i] - x_in[i]);
    return a;
}

static void constant_free(void *state)
{
    free(state);
}

/* its whole state: α (the settings' value, the same in a resumed run) */
static void constant_checkpoint(void *state, cpl_ckpt_table *t, const char *prefix)
{
    constant_state *st = state;
    cpl_ckpt_f64(t, prefix, "alpha", &st->alpha, 1);
}

const cpl_relax_ops cpl_relax_constant = {
    .name = "constant",
    .check = cpl_relax_check_alpha,
    .create = constant_create,
    .update = constant_update,
    .checkpoint = constant_checkpoint,
    .free = constant_free,
};
