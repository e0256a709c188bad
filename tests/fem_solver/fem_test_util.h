/* fem_test_util — code shared by the fem_solver tests: small models built in code and
 * scratch files. */
#ifndef FEM_TEST_UTIL_H
#define FEM_TEST_UTIL_H

#include <stddef.h>
#include <sys/types.h>

#include "../../fem_solver/fem_model.h"

/* A straight line of n_el equal elements from (0,0,0) to (length,0,0), one element set;
 * with fix_ends the two end nodes are fixed in x, y, z. The model is NOT finalised. */
void fem_test_line(fem_model *m, int n_el, double length, double E, double A, double rho,
                   double S_pre, fem_behaviour behaviour, int fix_ends);

/* A flat square net of n x n nodes over the unit square in the x-y plane
 * (fem_model_generate_net from the origin along x and y), all elements in `set` (the only
 * set), its "boundary" nodes fixed in x, y, z. The model is NOT finalised. Returns the
 * boundary node set, or NULL (err says why) when a step fails. */
const fem_node_set *fem_test_net(fem_model *m, int n, const fem_element_set *set, nc_error *err);

/* Writes text to NC_TMP/name (or /tmp) and returns the path (static buffer per call slot). */
const char *fem_test_write(const char *name, const char *text);

/* Starts $NC_BIN/fem_solver JSON --endpoint tcp://127.0.0.1:* --endpoint-file EPFILE
 * --output OUTDIR --idle-timeout IDLE_S (standard output to /dev/null); returns its pid. */
pid_t fem_test_spawn(const char *json, const char *outdir, const char *epfile, const char *idle_s);
/* Waits up to 30 s for the endpoint file and reads the endpoint; 0, or -1. */
int fem_test_read_endpoint(const char *file, char *ep, size_t size);
/* Exit status of pid within timeout_s (128: killed by a signal); after the timeout the
 * process is killed and -1 returned. */
int fem_test_wait_exit(pid_t pid, double timeout_s);

#endif
