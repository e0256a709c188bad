/* proto_serve — the participant's serve loop and step state machine (proto_serve.h). */
#include "proto_serve.h"

#include <stdio.h>
#include <string.h>

typedef struct step_state {
    int open;         /* BEGIN_STEP done, no ACCEPT_STEP yet */
    int solved;       /* a SOLVE handler ran in the open step: the state is not the saved one */
    int last_ok;      /* the last SOLVE of the open step succeeded */
    int stepped;      /* a BEGIN_STEP or a RESUME was carried out: too late to resume */
} step_state;

/* "solve (step 12, iteration 2)", "begin_step (step 3)", "interface". */
static void describe(const proto_message *cmd, char *out, size_t size)
{
    const char *type = proto_type_name(cmd->type);
    if (cmd->step >= 0 && cmd->iteration > 0)
        snprintf(out, size, "%s (step %ld, iteration %d)", type, cmd->step, cmd->iteration);
    else if (cmd->step >= 0)
        snprintf(out, size, "%s (step %ld)", type, cmd->step);
    else
        snprintf(out, size, "%s", type);
}

/* Answers the current command with an error naming it and `reason`; -1 only when the reply
 * cannot be sent. */
static int reply_failure(proto_participant *p, const proto_serve_handlers *h, void *ctx,
                         const proto_message *cmd, const nc_error *why, proto_serve_summary *sum,
                         nc_error *err)
{
    const char *reason = why->message;
    char what[128], text[PROTO_TEXT_MAX];
    describe(cmd, what, sizeof what);
    snprintf(text, sizeof text, "%s: %s", what, reason);
    /* a retryable failure is the coupler's to handle (it retries with a smaller step); it
     * is not an error of this participant's run */
    if (why->code == PROTO_ERR_STEP_FAILED) sum->retryable++;
    else sum->failed++;
    if (h->report) h->report(ctx, text);
    /* a handler's PROTO_ERR_STEP_FAILED: the coupler may retry the step with a smaller dt */
    return proto_participant_reply_failure(p, text, why->code == PROTO_ERR_STEP_FAILED, err);
}

/* Runs one command: 0 with `reply` filled, -1 with the reason in e. */
static int dispatch(const proto_serve_handlers *h, void *ctx, const proto_message *cmd,
                    proto_message *reply, step_state *st, proto_serve_summary *sum, nc_error *e)
{
    switch (cmd->type) {
    case PROTO_MSG_INTERFACE:
        if (!h->interface) return nc_error_set(e, PROTO_ERR_USAGE, "this participant takes no interface");
        return h->interface(ctx, cmd, reply, e);
    case PROTO_MSG_BEGIN_STEP:
        /* a step begun again without ACCEPT_STEP starts from the last accepted state */
        if (st->open && st->solved && h->restore_state) {
            sum->restores++;
            if (h->restore_state(ctx, cmd, e)) return -1;
        }
        st->open = 0;
        st->solved = 0;
        st->last_ok = 0;
        st->stepped = 1;
        if (h->save_state && h->save_state(ctx, cmd, e)) return -1;
        st->open = 1;
        return 0;
    case PROTO_MSG_SOLVE: {
        if (!st->open) return nc_error_set(e, PROTO_ERR_USAGE, "refused: no step begun (BEGIN_STEP must come first)");
        if (!h->solve) return nc_error_set(e, PROTO_ERR_USAGE, "this participant cannot solve");
        st->last_ok = 0;
        /* every SOLVE after the first of the step starts from the saved state again */
        if (st->solved && h->restore_state) {
            sum->restores++;
            if (h->restore_state(ctx, cmd, e)) return -1;
        }
        st->solved = 1;
        sum->solves++;
        if (h->solve(ctx, cmd, reply, e)) return -1;
        st->last_ok = 1;
        return 0;
    }
    case PROTO_MSG_ACCEPT_STEP:
        if (!st->open) return nc_error_set(e, PROTO_ERR_USAGE, "refused: no step begun (BEGIN_STEP must come first)");
        if (!st->last_ok) return nc_error_set(e, PROTO_ERR_USAGE, "refused: the step has no successful SOLVE to accept");
        /* the step is committed even when writing its output fails */
        st->open = 0;
        st->solved = 0;
        st->last_ok = 0;
        sum->steps_accepted++;
        return h->accept_step ? h->accept_step(ctx, cmd, reply, e) : 0;
    case PROTO_MSG_SHUTDOWN:
        return h->shutdown ? h->shutdown(ctx, cmd, e) : 0;
    case PROTO_MSG_CHECKPOINT:
        if (!h->checkpoint) return nc_error_set(e, PROTO_ERR_USAGE, "this participant cannot checkpoint");
        if (st->open) return nc_error_set(e, PROTO_ERR_USAGE, "refused: a step is open (checkpoint after accept_step)");
        if (!cmd->text[0]) return nc_error_set(e, PROTO_ERR_USAGE, "refused: the checkpoint has no name (text)");
        if (h->checkpoint(ctx, cmd, reply, e)) return -1;
        sum->checkpoints++;
        return 0;
    case PROTO_MSG_RESUME:
        if (!h->resume) return nc_error_set(e, PROTO_ERR_USAGE, "this participant cannot resume");
        if (st->stepped) return nc_error_set(e, PROTO_ERR_USAGE, "refused: resume comes before the first begin_step, once");
        if (!cmd->text[0]) return nc_error_set(e, PROTO_ERR_USAGE, "refused: the checkpoint to resume has no name (text)");
        if (h->resume(ctx, cmd, reply, e)) return -1;
        st->stepped = 1;
        sum->resumed = 1;
        return 0;
    default:
        return nc_error_set(e, PROTO_ERR_USAGE, "refused: '%s' is not a command", proto_type_name(cmd->type));
    }
}

int proto_serve(proto_participant *p, const proto_serve_handlers *h, void *ctx,
                const volatile sig_atomic_t *stop, proto_serve_summary *out, nc_error *err)
{
    proto_serve_summary sum;
    memset(&sum, 0, sizeof sum);
    step_state st = {0, 0, 0, 0};
    proto_message cmd, reply;
    memset(&cmd, 0, sizeof cmd);
    memset(&reply, 0, sizeof reply);
    int rc;
    for (;;) {
        if (stop && *stop) { rc = 1; break; }
        nc_error e;
        nc_error_clear(&e);
        if (proto_participant_receive(p, &cmd, &e)) {
            if (stop && *stop) { rc = 1; break; }   /* the signal interrupted the wait */
            if (e.code == PROTO_ERR_SESSION) {
                sum.refused++;                       /* another coupler: refused, not ours */
                if (h->report) h->report(ctx, e.message);
                continue;
            }
            if (e.code == PROTO_ERR_DECODE || e.code == PROTO_ERR_VERSION) {
                sum.rejected++;                      /* already answered with an error */
                if (h->report) h->report(ctx, e.message);
                continue;
            }
            if (err) *err = e;                       /* idle timeout, transport failure */
            rc = -1;
            break;
        }
        sum.commands++;
        proto_message_init(&reply, cmd.type);
        int failed = dispatch(h, ctx, &cmd, &reply, &st, &sum, &e);
        if (failed ? reply_failure(p, h, ctx, &cmd, &e, &sum, err)
                   : proto_participant_reply(p, &reply, err)) {
            rc = -1;
            break;
        }
        if (cmd.type == PROTO_MSG_SHUTDOWN) { rc = 0; break; }
    }
    sum.step_open = st.open;
    sum.step_solved = st.open && st.solved;
    proto_message_free(&cmd);
    proto_message_free(&reply);
    if (out) *out = sum;
    return rc;
}
