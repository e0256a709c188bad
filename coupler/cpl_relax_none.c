/* cpl_relax_none — no relaxation: the next input is the produced value, x^{k+1} = x̃^k
 * (plain Gauss–Seidel; the weak scheme's exchange, eqs. (37)–(39)). No keys of its own. */
#include "cpl_relax_ops.h"

#include <stdlib.h>
#include <string.h>

typedef struct none_state {
    size_t n;
} none_state;

static int none_create(void **state, const cpl_relax_settings *s, size_t n, size_t n_blocks,
                       nc_error *err)
{
    (void)s;
    (void)n_blocks;
    none_state *st = malloc(sizeof *st);
    if (!st) return nc_error_set(err, 1, "none: out of memory");
    st->n = n;
    *state = st;
    return 0;
}

static double none_update(void *state, const double *x_in, const double *x_out,
                          double *x_next)
{
    (void)x_in;
    const none_state *st = state;
    memmove(x_next, x_out, st->n * sizeof(double));
    return 1.0;
}

static void none_free(void *state)
{
    free(state);
}

const cpl_relax_ops cpl_relax_none = {
    .name = "none",
    .create = none_create,
    .update = none_update,
    .free = none_free,
};
