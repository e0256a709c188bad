/* chk_process — the participant under test as a child process: started the way a launcher
 * starts it (protocol/README.md §7; scripts/run_case.sh), watched for its endpoint file and its
 * exit status, and stopped.
 *
 * The child runs in its own process group (a PROGRAM that is a wrapper script is stopped with
 * everything it started), with stdin from /dev/null and stdout + stderr into a log file.
 * Exit status: the program's exit code, or 128 + signal number when a signal ended it.
 */
#ifndef CHK_PROCESS_H
#define CHK_PROCESS_H

#include <sys/types.h>
#include "nc_error.h"

typedef struct chk_process {
    pid_t pid;          /* 0: not started */
    int exited;         /* the status below is known */
    int status;         /* exit code, or 128 + signal */
    double started_s;   /* monotonic clock at start */
    double exited_s;    /* monotonic clock when the exit was seen */
} chk_process;

double chk_now_s(void);   /* monotonic clock [s] */

/* Starts argv[0] (looked up in PATH) with argv; output into log_path. */
int chk_process_start(chk_process *p, char *const argv[], const char *log_path, nc_error *err);
/* Waits up to timeout_s for the exit; 1 when it has exited (p->status), 0 when still running. */
int chk_process_wait(chk_process *p, double timeout_s);
/* SIGTERM to the group, SIGKILL after grace_s; reaps the child. No-op when it has exited. */
void chk_process_stop(chk_process *p, double grace_s);
/* Waits until `path` exists and holds one complete line (a launcher's endpoint file), at most
 * timeout_s, while the process runs. 0 with the line (without its newline) in `line`; -1 with
 * a reason: timeout, or the process exited first (its status named). */
int chk_wait_endpoint_file(chk_process *p, const char *path, double timeout_s, char *line,
                           size_t size, nc_error *err);
/* The last non-empty line of a log file, for messages ("" when there is none). */
void chk_last_log_line(const char *log_path, char *out, size_t size);

#endif
