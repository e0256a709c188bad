/* cpl_heartbeat — the coupler's sign of life for the program that launched it.
 *
 * A small text file (coupler --progress-file PATH; scripts/run_case.sh uses
 * DIR/coupler.progress), replaced atomically, so a reader never sees half of it:
 *   state connecting|running|finishing|stopping
 *   status <the progress status line of the last step>
 *   waiting <fem|dem> <seconds>      only while a request to that participant is pending
 * The main thread rewrites it with every step (at most every CPL_HEARTBEAT_MIN_INTERVAL_S);
 * while the main thread waits for a participant, a background thread rewrites it every
 * `every_s`, but only as long as the wait is within its own timeout plus
 * CPL_HEARTBEAT_MARGIN_S. So the file stays fresh as long as the coupler works or waits as it
 * should, and goes stale when it does not (stopped, stuck in a loop, a wait that outlived its
 * timeout): the launcher stops a coupler whose file is older than its limit.
 */
#ifndef CPL_HEARTBEAT_H
#define CPL_HEARTBEAT_H

#include "nc_error.h"

#define CPL_HEARTBEAT_MIN_INTERVAL_S 0.2
#define CPL_HEARTBEAT_MARGIN_S 5.0

typedef struct cpl_heartbeat cpl_heartbeat;

/* Writes the file once (state "connecting") and starts the background thread. */
int cpl_heartbeat_start(cpl_heartbeat **out, const char *path, double every_s, nc_error *err);
/* New state and status line (either may be NULL: unchanged); written now unless the last
 * write is younger than CPL_HEARTBEAT_MIN_INTERVAL_S and the state is unchanged. */
int cpl_heartbeat_update(cpl_heartbeat *hb, const char *state, const char *status,
                         nc_error *err);
/* A request to `peer` that may take up to timeout_s begins / has ended. */
void cpl_heartbeat_wait_begin(cpl_heartbeat *hb, const char *peer, double timeout_s);
void cpl_heartbeat_wait_end(cpl_heartbeat *hb);
/* Stops the thread (the file stays, with its last content); NULL is fine. */
void cpl_heartbeat_stop(cpl_heartbeat *hb);

#endif
