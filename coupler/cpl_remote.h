/* cpl_remote — participants reached over the protocol (proto_peer), plugged into the loop.
 *
 * Start-up: cpl_remote_open (HELLO within the connect timeout), then the interface mesh goes
 * from the FEM to the DEM (INTERFACE to the FEM, its arrays to the DEM). The loop then drives
 * BEGIN_STEP / SOLVE / ACCEPT_STEP through cpl_remote_participant(). SHUTDOWN at the end, or
 * after a failure, through a fresh short-timeout connection so a hung peer cannot block exit.
 * Errors: a participant's error reply marked retryable becomes CPL_ERR_STEP_FAILED (the loop
 * retries the step with a smaller dt); a malformed reply leaves the participant marked alive
 * (it answered, wrongly) so that it still gets SHUTDOWN.
 * Interface-Jacobian coupling (version 2, capability "jacobian" on both sides): a DEM SOLVE
 * asks for the linearisation with the value "jacobian" 1, and the FEM's SOLVE carries it with
 * the point it was taken at (protocol/README.md §3.1).
 * The structure's compliance (capability "compliance" on both sides, §3.4): a FEM SOLVE with
 * call->compliance_out asks for it with the value "compliance" 1 and stores the reply's
 * arrays there; a DEM SOLVE with call->compliance_in sends them (when of the same dt) with
 * the force the structure balanced, and stores where the DEM's wall ended in
 * call->compliance_out.
 * Replies may carry the value "solve_time_s" (the participant's own compute time for the
 * request); the coupler then splits waiting time into solver and exchange time.
 */
#ifndef CPL_REMOTE_H
#define CPL_REMOTE_H

#include "cpl_interface.h"
#include "cpl_loop.h"
#include "proto.h"

typedef enum { CPL_REMOTE_FEM, CPL_REMOTE_DEM } cpl_remote_kind;

typedef struct cpl_remote {
    cpl_remote_kind kind;
    char name[PROTO_NAME_MAX];        /* "fem" / "dem" */
    char endpoint[1024];
    char peer_role[PROTO_NAME_MAX];   /* what the participant said in HELLO */
    char peer_program[PROTO_NAME_MAX];
    char capabilities[PROTO_TEXT_MAX];/* its capability words */
    int version;                      /* protocol version agreed in HELLO */
    char session[PROTO_NAME_MAX];     /* this coupler's token with it (version 2) */
    double idle_timeout_s;            /* what it said in HELLO (0: none or not said) */
    proto_peer *peer;
    proto_message request, reply;
    size_t n_nodes;
    int alive;                        /* 0 once it is known to be gone */
} cpl_remote;

/* Connects and shakes hands: HELLO must be answered within connect_timeout_s; later
 * requests wait up to reply_timeout_s. */
int cpl_remote_open(cpl_remote *r, cpl_remote_kind kind, const char *endpoint,
                    double connect_timeout_s, double reply_timeout_s, nc_error *err);
/* INTERFACE to the FEM: fills the mesh; *u0 / *v0 get the initial interface state when the
 * FEM sends "displacement"/"velocity" with it (malloc'ed, else NULL). */
int cpl_remote_interface_fem(cpl_remote *fem, cpl_mesh *mesh, double **u0, double **v0,
                             nc_error *err);
/* INTERFACE to the DEM with the FEM's mesh. */
int cpl_remote_interface_dem(cpl_remote *dem, const cpl_mesh *mesh, nc_error *err);
/* With checkpoint/resume when it announced the capability "checkpoint" (version 2,
 * protocol/README.md §3.3); the reply's text, when set, is the name of its checkpoint file. */
cpl_participant cpl_remote_participant(cpl_remote *r);
int cpl_remote_can_checkpoint(const cpl_remote *r);
/* SHUTDOWN over a fresh connection with the given timeout; -1 if not acknowledged. */
int cpl_remote_shutdown(cpl_remote *r, double timeout_s, nc_error *err);
void cpl_remote_close(cpl_remote *r);

/* Reads an endpoint file written by a participant, waiting up to timeout_s for it. */
int cpl_read_endpoint_file(const char *path, double timeout_s, char *endpoint, size_t size,
                           volatile const sig_atomic_t *stop, nc_error *err);

#endif
