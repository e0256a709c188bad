/* fem_input — reads fem.json into a fem_model (every key is documented in README.md).
 *
 * Unknown keys are rejected; every error names the file, the field and what was expected,
 * e.g. "net.json: element_sets[0].youngs_modulus_pa: expected a number > 0, got -3".
 * On success the model is finalised (fem_model_finalize) and ready for fem_analysis_init.
 * Implausible values (modulus, area, density, prestress, breaking load outside wide
 * engineering ranges, README "Plausibility warnings") are warnings, not errors: one line each,
 * "warning: <file>: <field>: ...", to the options' sink; the input is still read.
 */
#ifndef FEM_INPUT_H
#define FEM_INPUT_H

#include <stdio.h>

#include "fem_model.h"

typedef struct fem_input_options {
    FILE *warnings;   /* sink of the plausibility warnings (NULL: not reported) */
} fem_input_options;

/* opt may be NULL (no warnings reported). */
int fem_input_load_opt(const char *path, fem_model *m, const fem_input_options *opt,
                       nc_error *err);
int fem_input_load(const char *path, fem_model *m, nc_error *err);

#endif
