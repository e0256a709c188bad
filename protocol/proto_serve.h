/* proto_serve — the participant's serve loop: one command at a time until SHUTDOWN, the idle
 * timeout or a stop request, dispatched to a solver's handlers.
 *
 * The loop owns the step state machine and the one restore rule (protocol/README.md §3):
 *   BEGIN_STEP   save_state (when the open step was already solved, restore_state first:
 *                a step begun again without ACCEPT_STEP starts from the last accepted state);
 *   SOLVE        refused outside a begun step; the first SOLVE of a step runs from the saved
 *                state, every further SOLVE of the same step calls restore_state first;
 *   ACCEPT_STEP  refused outside a begun step or when its last SOLVE failed; closes the step;
 *   CHECKPOINT   refused inside a begun step (the state saved is an accepted one);
 *   RESUME       refused after the first BEGIN_STEP or a RESUME (a run resumes once, before
 *                it steps).
 * A handler that fails, and a command refused by the loop, get an error reply naming the
 * command, step and iteration with the reason (marked retryable when the handler's error
 * code is PROTO_ERR_STEP_FAILED); serving continues. HELLO and malformed
 * commands are answered inside proto_participant_receive() (counted in `rejected`).
 * The loop never prints: every error reply it sends is passed to handlers->report.
 */
#ifndef PROTO_SERVE_H
#define PROTO_SERVE_H

#include <signal.h>
#include "proto.h"

/* The solver side. Every handler returns 0, or -1 with a reason in err; NULL handlers:
 * interface -> INTERFACE is refused; save_state / restore_state / accept_step / shutdown ->
 * nothing to do. `reply` has been initialised with the command's type; a handler adds its
 * arrays (which must stay valid until the reply is sent) and values. */
typedef struct proto_serve_handlers {
    int (*interface)(void *ctx, const proto_message *cmd, proto_message *reply, nc_error *err);
    int (*save_state)(void *ctx, const proto_message *cmd, nc_error *err);   /* BEGIN_STEP */
    int (*restore_state)(void *ctx, const proto_message *cmd, nc_error *err);
    int (*solve)(void *ctx, const proto_message *cmd, proto_message *reply, nc_error *err);
    int (*accept_step)(void *ctx, const proto_message *cmd, proto_message *reply, nc_error *err);
    int (*shutdown)(void *ctx, const proto_message *cmd, nc_error *err);
    /* version 2, capability `checkpoint` (protocol/README.md §3.3): save the complete state
     * under the name in cmd->text, durably, before returning; load it again and reopen the
     * result files as they were at that checkpoint. NULL: the command is refused. */
    int (*checkpoint)(void *ctx, const proto_message *cmd, proto_message *reply, nc_error *err);
    int (*resume)(void *ctx, const proto_message *cmd, proto_message *reply, nc_error *err);
    /* Each error reply sent, e.g. "solve (step 12, iteration 2): Newton did not converge ...";
     * for the program's log. */
    void (*report)(void *ctx, const char *message);
} proto_serve_handlers;

typedef struct proto_serve_summary {
    long commands;          /* commands dispatched (HELLO and malformed ones not counted) */
    long steps_accepted;
    long solves;            /* SOLVE handler calls */
    long restores;          /* restore_state calls */
    long checkpoints;       /* CHECKPOINT commands carried out */
    int resumed;            /* a RESUME was carried out */
    long failed;            /* error replies: handler failures and refused commands */
    long retryable;         /* error replies marked retryable (PROTO_ERR_STEP_FAILED): the
                               coupler retries the step; not counted in failed */
    long rejected;          /* malformed commands (answered with an error by the receive) */
    long refused;           /* commands of another coupler's session, or before hello
                               (version 2): refused, and not an error of this run */
    int step_open;          /* the loop ended inside a begun, not accepted step ... */
    int step_solved;        /* ... which was solved (the state is not the saved one) */
} proto_serve_summary;

/* Serves until SHUTDOWN (returns 0, also after failed commands: see summary.failed and
 * summary.rejected), until *stop becomes non-zero (returns 1; stop may be NULL) or until
 * the idle timeout or a transport failure (returns -1 with PROTO_ERR_IDLE / the transport
 * error in err). out may be NULL. */
int proto_serve(proto_participant *p, const proto_serve_handlers *handlers, void *ctx,
                const volatile sig_atomic_t *stop, proto_serve_summary *out, nc_error *err);

#endif
