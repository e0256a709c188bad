/* cpl_relax_ops — the table of operations of one relaxation method, for the method files
 * (cpl_relax_<name>.c) and the list of methods (cpl_relax_methods.c); the rest of the
 * coupler uses cpl_relax.h only.
 *
 * A method is one file exporting `const cpl_relax_ops cpl_relax_<name>`; its settings and
 * state are structs private to that file. Its settings live in cpl_relax_settings.params
 * (copy them in and out with memcpy; at most CPL_RELAX_PARAMS_SIZE bytes); the common α is
 * cpl_relax_settings.alpha. Optional operations may be NULL (nothing to do / no such thing).
 */
#ifndef CPL_RELAX_OPS_H
#define CPL_RELAX_OPS_H

#include <stddef.h>
#include <cjson/cJSON.h>
#include "cpl_checkpoint.h"
#include "cpl_relax.h"
#include "nc_error.h"

struct cpl_relax_ops {
    const char *name;          /* relaxation.method in coupler.json */
    /* its own keys of the relaxation object, NULL-terminated (optional) */
    const char *const *keys;
    /* settings: defaults into s->params (optional: all zero); read the own keys of `obj`
     * (nc_json getters, falling back to the current values; `where` names obj in
     * messages), each key's range checked (optional); consistency, including the common α
     * (cpl_relax_check_alpha) (optional); the value of an own key, -1 if not one (optional) */
    void (*defaults)(cpl_relax_settings *s);
    int (*parse)(cpl_relax_settings *s, const cJSON *obj, const char *where, nc_error *err);
    int (*check)(const cpl_relax_settings *s, const char *where, nc_error *err);
    int (*get)(const cpl_relax_settings *s, const char *key, double *value);
    /* state for n unknowns in n_blocks equal blocks (settings already checked) */
    int (*create)(void **state, const cpl_relax_settings *s, size_t n, size_t n_blocks,
                  nc_error *err);
    void (*begin_step)(void *state);   /* optional */
    /* x_next from the input x_in and the produced x_out (x_next may alias x_in, not
     * x_out); returns the α applied (block 0) or NAN. The caller checks finiteness. */
    double (*update)(void *state, const double *x_in, const double *x_out, double *x_next);
    void (*forget)(void *state, cpl_relax_forget_level level);   /* optional */
    /* on: the FEM solves with the DEM's linearisation, so an iteration is Newton's step on
     * the interface (set before the first step; optional) */
    void (*linearised)(void *state, int on);
    /* step accepted; x_in/x_out the last pair not passed to update, or both NULL (optional) */
    void (*end_step)(void *state, const double *x_in, const double *x_out);
    int (*counter)(const void *state, const char *name, double *value);   /* optional */
    /* checkpoint/resume: adds every part of the state the next steps depend on (history
     * carried across steps, the counters a run reports) to the table under `prefix`; the
     * same entries are saved and loaded, so a resumed run continues bit for bit (optional:
     * no state kept between steps) */
    void (*checkpoint)(void *state, cpl_ckpt_table *t, const char *prefix);
    void (*free)(void *state);
};

/* The list of methods (cpl_relax_methods.c): NULL-terminated, in documentation order. */
const cpl_relax_ops *const *cpl_relax_methods(void);
/* NULL when no method has that name. */
const cpl_relax_ops *cpl_relax_method_find(const char *name);

/* The common α: in (0, 2] (for the methods that use it). */
int cpl_relax_check_alpha(const cpl_relax_settings *s, const char *where, nc_error *err);

#endif
