/* fem_input — reads fem.json into a fem_model (every key is documented in README.md).
 *
 * Unknown keys are rejected; every error names the file, the field and what was expected,
 * e.g. "net.json: element_sets[0].youngs_modulus_pa: expected a number > 0, got -3".
 * On success the model is finalised (fem_model_finalize) and ready for fem_analysis_init.
 */
#ifndef FEM_INPUT_H
#define FEM_INPUT_H

#include "fem_model.h"

int fem_input_load(const char *path, fem_model *m, nc_error *err);

#endif
