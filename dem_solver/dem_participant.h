/* dem_participant — the DEM as the netcouple protocol participant "dem": its handlers of the
 * serve loop (protocol/proto_serve.h). INTERFACE builds the net wall, BEGIN_STEP saves the
 * complete state (dem_sim_begin_step), a repeated SOLVE restores it (dem_sim_restore; the
 * loop decides when), SOLVE sub-steps the coupling step and replies the time-averaged nodal
 * forces (with the capability "jacobian" their linearisation, with "compliance" a step
 * solved against the structure's compliance at the contact nodes: dem_compliance.h),
 * ACCEPT_STEP writes output when due. The first SOLVE that asks for the Jacobian notes in
 * the progress log when net contacts have the Hertz dashpot of eq. (A.5), whose dF/dδ is
 * unbounded where a contact begins or ends (dem_solver/README.md "Contact model"). The result files are created at the first
 * BEGIN_STEP (with output step 0), never before: CHECKPOINT saves the complete state to
 * checkpoint/dem_<name>.h5 in the output folder (dem_checkpoint.h) and RESUME, before the
 * first BEGIN_STEP, loads it and reopens the result files as they were then
 * (dem_output_resume). The step order and the restore rule are the serve loop's, shared with
 * every other participant.
 */
#ifndef DEM_PARTICIPANT_H
#define DEM_PARTICIPANT_H

#include <signal.h>
#include <stdio.h>
#include "dem_output.h"
#include "dem_sim.h"

typedef struct dem_participant_options {
    const char *endpoint;       /* e.g. tcp://127.0.0.1:* */
    const char *endpoint_file;  /* NULL, or a file to write the bound endpoint into */
    int idle_timeout_ms;        /* <= 0 waits forever */
    FILE *progress;             /* NULL or where progress lines go (the program: stdout) */
    FILE *problems;             /* NULL or where failed commands are logged (stderr) */
} dem_participant_options;

/* What the coupled mode needs of the input beyond dem_config's checks (the net wall
 * material); 0, or -1 with err naming the file and field. dem_participant_run checks it
 * first. */
int dem_participant_check_input(const dem_sim *s, nc_error *err);

/* Serves the coupler with the prepared simulation s, writing results through out.
 * Returns 0 after SHUTDOWN with every command answered, 1 after SHUTDOWN when a command was
 * answered with an error (err says how many), 130 when *stop was set, -1 on an error (idle
 * timeout, transport failure, missing net wall material; err). */
int dem_participant_run(dem_sim *s, dem_output *out, const dem_participant_options *opt,
                        const volatile sig_atomic_t *stop, nc_error *err);

#endif
