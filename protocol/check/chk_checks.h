/* chk_checks — the conformance checks of netcouple-check: the harness plays the coupler
 * against one participant and records one row per property of protocol/README.md.
 *
 * With a PROGRAM it runs the participant up to five times, each started as a launcher starts it
 * (PROGRAM ARGS... --endpoint tcp://127.0.0.1:* --endpoint-file FILE --output DIR
 * --idle-timeout S):
 *   1. the clean run — endpoint file, hello, a second coupler's hello, interface, two steps
 *      with the restore checks, a command of a foreign session, shutdown, exit status 0;
 *   2. the error run — commands out of order and malformed ones, each answered with an error
 *      while the participant keeps serving, shutdown, exit status 1 (§6);
 *   3. the checkpoint runs (capability `checkpoint`, §3.3) — step 0, CHECKPOINT, step 1;
 *      then started again in the same folder, RESUME, step 1: the same answer bit for bit;
 *   4. the idle run — no command at all: exit status 1 within the idle time plus a margin.
 * With an endpoint (a participant started by the user) runs 1 and 2 share one connection and
 * the process checks are skipped.
 * Every wait is bounded (reply timeout, start timeout); a participant that stops answering
 * ends its run with a FAIL row naming the command and, when it exited, its status.
 */
#ifndef CHK_CHECKS_H
#define CHK_CHECKS_H

#include "chk_report.h"

typedef struct chk_config {
    const char *role;           /* "fem" or "dem"; NULL: the role the hello reply names */
    char **program;             /* PROGRAM ARGS..., NULL-terminated; NULL with endpoint */
    const char *endpoint;       /* a running participant instead of a program */
    const char *work_dir;       /* where the run folders go (kept); NULL: a temporary folder */
    const char *interface_file; /* dem role: interface JSON to send (NULL: a 3 x 3 net) */
    const char *save_interface; /* fem role: write the interface received here (JSON) */
    double timeout_s;           /* reply timeout */
    double start_timeout_s;     /* how long a start may take until the endpoint file */
    double idle_timeout_s;      /* --idle-timeout of runs 1 and 2 */
    double dt_s;                /* step size of the steps sent */
    double force_n;             /* fem role: the load on one interface node [N] */
    int idle_check;             /* run 3 */
} chk_config;

/* Runs every check into `report`; returns 0, or -1 when the checks could not be run at all
 * (no run folder, bad interface file): err says why. */
int chk_run(const chk_config *cfg, chk_report *report, nc_error *err);

#endif
