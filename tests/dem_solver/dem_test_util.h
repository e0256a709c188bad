/* dem_test_util — code shared by the dem_solver tests: building a prepared simulation from
 * JSON text, a file in the test folder, and bin/dem_solver started as a participant. */
#ifndef DEM_TEST_UTIL_H
#define DEM_TEST_UTIL_H

#include "dem_config.h"
#include "dem_sim.h"

/* dem_sim_init + parse + prepare; fails the test (cmocka) on error. */
void dem_test_build(dem_sim *s, const char *json);
/* Same, returning -1 and the message instead of failing. */
int dem_test_try_build(dem_sim *s, const char *json, nc_error *err);
/* Writes `text` to NC_TMP (or /tmp)/name and returns the path in buf. */
const char *dem_test_write_file(char *buf, size_t size, const char *name, const void *text,
                                size_t length);

/* Starts bin/dem_solver (NC_BIN) as a coupling participant on input with --output outdir,
 * waits for its endpoint file (up to 30 s) and returns its pid with the endpoint in
 * `endpoint`; stdout goes to outdir.log. Fails the test when it does not start. */
int dem_test_start_participant(const char *input, const char *outdir, char *endpoint,
                               size_t size);

#endif
