/* dem_config — reading dem.json into a dem_sim (materials, particles, generators, clusters,
 * planes, STL meshes, parameters, net wall material). Every key is documented in
 * dem_solver/README.md; unknown keys, wrong types and out-of-range values are errors naming
 * the file, the field and what was expected.
 *
 * Contract: call dem_sim_init() first; on success the sim is filled but not prepared (call
 * dem_sim_prepare()). On failure the sim may be partly filled; dem_sim_free() it.
 */
#ifndef DEM_CONFIG_H
#define DEM_CONFIG_H

#include "dem_sim.h"

int dem_config_load(dem_sim *s, const char *path, nc_error *err);
/* Same from JSON text; `where` names the source in messages, `base_dir` resolves STL paths. */
int dem_config_parse_string(dem_sim *s, const char *json, const char *where,
                            const char *base_dir, nc_error *err);

#endif
