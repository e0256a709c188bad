/* dem_config — reading dem.json into a dem_sim (materials, particles, generators, clusters,
 * planes, STL meshes, parameters, net wall material). Every key is documented in
 * dem_solver/README.md; unknown keys, wrong types and out-of-range values are errors naming
 * the file, the field and what was expected.
 *
 * Implausible values (a radius, density, modulus or speed outside wide engineering ranges,
 * README "Plausibility warnings") are warnings, not errors: one line each, "warning: <file>:
 * <field>: <value> is outside ...", written to the options' sink; the input is still read.
 *
 * Contract: call dem_sim_init() first; on success the sim is filled but not prepared (call
 * dem_sim_prepare()). On failure the sim may be partly filled; dem_sim_free() it.
 */
#ifndef DEM_CONFIG_H
#define DEM_CONFIG_H

#include <stdio.h>

#include "dem_sim.h"

typedef struct dem_config_options {
    FILE *warnings;   /* sink of the plausibility warnings (NULL: not reported) */
} dem_config_options;

/* opt may be NULL (no warnings reported). */
int dem_config_load_opt(dem_sim *s, const char *path, const dem_config_options *opt,
                        nc_error *err);
int dem_config_load(dem_sim *s, const char *path, nc_error *err);
/* Same from JSON text; `where` names the source in messages, `base_dir` resolves STL paths. */
int dem_config_parse_string_opt(dem_sim *s, const char *json, const char *where,
                                const char *base_dir, const dem_config_options *opt,
                                nc_error *err);
int dem_config_parse_string(dem_sim *s, const char *json, const char *where,
                            const char *base_dir, nc_error *err);

#endif
