/* cpl_config — reading coupler.json (documented key by key in coupler/README.md).
 *
 * Every key is validated with a message naming file and field; unknown keys are rejected.
 * Relative endpoint-file paths are relative to the folder of coupler.json.
 */
#ifndef CPL_CONFIG_H
#define CPL_CONFIG_H

#include <cjson/cJSON.h>
#include "cpl_loop.h"
#include "nc_error.h"

#define CPL_PATH_MAX 1024

typedef struct cpl_endpoint_config {
    char endpoint[CPL_PATH_MAX];        /* "" when given by a file */
    char endpoint_file[CPL_PATH_MAX];   /* "" when given directly */
} cpl_endpoint_config;

typedef struct cpl_config {
    cpl_loop_settings loop;
    cpl_endpoint_config fem, dem;
    double connect_timeout_s;   /* wait for endpoint files and the HELLO answer */
    double reply_timeout_s;     /* longest wait for one reply */
    double shutdown_timeout_s;  /* wait for the SHUTDOWN acknowledgement */
    int write_iterations;       /* the /iterations group of coupling.h5 */
    double progress_interval_s; /* plain progress lines when not on a terminal */
    int accept_unconverged;     /* accepted unconverged steps do not make the exit status
                                   non-zero (they are still reported as not reliable) */
    int accept_energy_growth;   /* likewise for energy created beyond energy_tolerance */
    int accept_impulse_loss;    /* likewise for interface impulse the structure missed beyond
                                   impulse_tolerance (cpl_impulse.h) */
} cpl_config;

void cpl_config_default(cpl_config *c);
/* Parses an already loaded document; `where` is the file name for messages, `base_dir` the
 * folder relative paths refer to. */
int cpl_config_parse(cpl_config *c, const cJSON *root, const char *where, const char *base_dir,
                     nc_error *err);
int cpl_config_load(cpl_config *c, const char *path, nc_error *err);

#endif
