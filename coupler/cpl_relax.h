/* cpl_relax — relaxation of the exchanged interface data, eqs. (31)–(34), and interface
 * quasi-Newton (IQN-ILS, Degroote et al. 2009), behind one interface.
 *
 * The relaxed vector x is either [u; s·u̇] (algorithm 2; s = the nominal Δt so both halves
 * are lengths) or the forces F (algorithm 3). In each coupling iteration the loop hands
 * over the input it used (x^k, the previous relaxed value) and the value the solvers
 * produced from it (x̃^k); cpl_relax_update() returns the input of the next iteration.
 * The methods (one file each, see cpl_relax_ops.h; the list is cpl_relax_methods.c):
 *   none      x^{k+1} = x̃^k                                        (cpl_relax_none.c)
 *   constant  x^{k+1} = x^k + α r^k,  r^k = x̃^k − x^k, eqs. (31)–(33) (cpl_relax_constant.c)
 *   aitken    as constant with α^k of eq. (34), one α per block; α = 1 while the residual
 *             contracts when the FEM solves with the interface Jacobian (cpl_relax_aitken.c)
 *   iqn-ils   x^{k+1} = x̃^k + W c,  c = argmin ‖V c + r^k‖           (cpl_relax_iqn.c)
 * Lifecycle per step: begin_step, update for each non-final iteration, end_step.
 *
 * Settings are what the `relaxation` object of coupler.json says: the method, the common
 * `alpha`, and the method's own keys, kept opaque here (only the method's file knows their
 * layout). Set them from JSON (cpl_relax_settings_parse) or key by key with the same names
 * (cpl_relax_settings_set).
 */
#ifndef CPL_RELAX_H
#define CPL_RELAX_H

#include <stddef.h>
#include <cjson/cJSON.h>
#include "nc_error.h"

typedef struct cpl_relax_ops cpl_relax_ops;   /* one method's operations (cpl_relax_ops.h) */

enum { CPL_RELAX_PARAMS_SIZE = 64 };   /* room for a method's own settings */

typedef struct cpl_relax_settings {
    const cpl_relax_ops *method;
    double alpha;   /* common key: constant α; Aitken α of the very first iteration; IQN α
                       of a plain relaxation step (no columns yet); unused by none */
    int alpha_given;   /* alpha came from the file (IQN-ILS: 1 with the Jacobian if not);
                          code that sets alpha itself sets this too */
    unsigned char params[CPL_RELAX_PARAMS_SIZE];   /* the method's own keys, private */
} cpl_relax_settings;

/* Method none, α = 0.5. */
void cpl_relax_settings_default(cpl_relax_settings *s);
/* Switches to the named method with its defaults (α is kept); an unknown name fails
 * listing the known ones. */
int cpl_relax_settings_select(cpl_relax_settings *s, const char *method, nc_error *err);
const char *cpl_relax_settings_method(const cpl_relax_settings *s);
/* A number naming a method in a checkpoint: FNV-1a (32 bit) of its name, so it stays when
 * methods are added or reordered; and the method's name back from it (NULL: none). */
double cpl_relax_method_id(const char *name);
const char *cpl_relax_method_name(double id);
/* Reads the `relaxation` object (`where` names it in messages, e.g.
 * "coupler.json.relaxation"): method, alpha, and the keys of every method, each checked
 * (keys of another method than the chosen one are accepted and checked too, so switching
 * the method alone keeps a file valid); unknown keys are rejected. */
int cpl_relax_settings_parse(cpl_relax_settings *s, const cJSON *obj, const char *where,
                             nc_error *err);
/* One key as coupler.json spells it ("alpha", "filter", ...), range-checked like the file;
 * for programs and tests. A key of another method is checked and ignored. */
int cpl_relax_settings_set(cpl_relax_settings *s, const char *key, double value,
                           nc_error *err);
/* The value of one key of the chosen method (or "alpha"); -1 when it has no such key. A key
 * whose default depends on the regime reads 0 while not given (Aitken's
 * first_iteration_cap: 1 with the interface Jacobian's Newton rule, else 0.5). */
int cpl_relax_settings_get(const cpl_relax_settings *s, const char *key, double *value);
/* Consistency of the chosen method's settings (ranges, α_min < α_max, ...). */
int cpl_relax_settings_check(const cpl_relax_settings *s, const char *where, nc_error *err);

typedef struct cpl_relax cpl_relax;

/* n unknowns split into n_blocks equal contiguous blocks (Aitken computes one α per block). */
int cpl_relax_create(cpl_relax **out, const cpl_relax_settings *s, size_t n, size_t n_blocks,
                     nc_error *err);
void cpl_relax_free(cpl_relax *r);

void cpl_relax_begin_step(cpl_relax *r);
/* nc_error code of cpl_relax_update when its result is not finite: the coupling iteration
 * diverged (the loop may retry the step with a smaller Δt). */
enum { CPL_RELAX_ERR_NOT_FINITE = 44 };

/* x_in: input of this iteration, x_out: produced value; writes the next input into x_next
 * (may alias x_in, not x_out). *alpha gets the α used (block 0), NAN for a quasi-Newton
 * update. Fails with CPL_RELAX_ERR_NOT_FINITE when the result is not finite (diverged
 * iteration). */
int cpl_relax_update(cpl_relax *r, const double *x_in, const double *x_out, double *x_next,
                     double *alpha, nc_error *err);

typedef enum {
    /* the last pair was not an evaluation of the fixed-point map (algorithm 3's first
     * iteration starts from the DEM at the predicted position, not from the relaxed force),
     * the map changed (contact backtracking moved the iterate; the DEM's search ended every
     * contact and the try goes on without the structure's compliance): no secant
     * information from it (Aitken's r^{k-1}, IQN's next column) */
    CPL_RELAX_FORGET_PAIR = 0,
    /* also everything learnt in earlier steps (IQN columns, Aitken's last α): after a step
     * that did not converge, whose information would mislead the next steps */
    CPL_RELAX_FORGET_HISTORY
} cpl_relax_forget_level;
void cpl_relax_forget(cpl_relax *r, cpl_relax_forget_level level);

/* Whether the FEM solves with the DEM's contact linearisation (the interface Jacobian), so
 * that the produced value is Newton's step from the input (Aitken's newton_contraction acts
 * only then). Off until set. */
void cpl_relax_set_linearised(cpl_relax *r, int on);

/* The step is accepted. x_in/x_out: the last pair when it was not passed to update (IQN
 * keeps its columns for the next steps), or NULL. Aitken keeps its last α regardless. */
void cpl_relax_end_step(cpl_relax *r, const double *x_in, const double *x_out);

/* Adds the method's state to a checkpoint table under `prefix` (cpl_checkpoint.h); the
 * same entries serve to save and to load it. */
struct nc_ckpt_table;
void cpl_relax_checkpoint_entries(cpl_relax *r, struct nc_ckpt_table *t, const char *prefix);

/* A method's diagnostic counter by name ("restarts" and "full_steps" of Aitken;
 * "columns", "dropped_columns" of IQN-ILS); -1 when the method has no such counter. */
int cpl_relax_counter(const cpl_relax *r, const char *name, double *value);

#endif
