/* chk_process — the participant under test as a child process (chk_process.h). */
#include "chk_process.h"

#include <errno.h>
#include <fcntl.h>
#include <signal.h>
#include <stdio.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

double chk_now_s(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static void pause_s(double s)
{
    struct timespec ts = {(time_t)s, (long)((s - (double)(time_t)s) * 1e9)};
    nanosleep(&ts, NULL);
}

int chk_process_start(chk_process *p, char *const argv[], const char *log_path, nc_error *err)
{
    memset(p, 0, sizeof *p);
    int log = open(log_path, O_WRONLY | O_CREAT | O_TRUNC, 0644);
    if (log < 0) return nc_error_set(err, 1, "%s: cannot create the log: %s", log_path, strerror(errno));
    /* exec failure is reported through this pipe (closed on a successful exec) */
    int pipefd[2];
    if (pipe(pipefd) != 0) {
        close(log);
        return nc_error_set(err, 1, "cannot create a pipe: %s", strerror(errno));
    }
    fcntl(pipefd[1], F_SETFD, FD_CLOEXEC);
    fflush(NULL);
    pid_t pid = fork();
    if (pid < 0) {
        close(log);
        close(pipefd[0]);
        close(pipefd[1]);
        return nc_error_set(err, 1, "cannot start %s: %s", argv[0], strerror(errno));
    }
    if (pid == 0) {
        setpgid(0, 0);
        int null = open("/dev/null", O_RDONLY);
        if (null >= 0) dup2(null, 0);
        dup2(log, 1);
        dup2(log, 2);
        close(pipefd[0]);
        execvp(argv[0], argv);
        int e = errno;
        if (write(pipefd[1], &e, sizeof e) < 0) _exit(127);
        _exit(127);
    }
    setpgid(pid, pid); /* also from the parent: no race with the first kill */
    close(log);
    close(pipefd[1]);
    int e = 0;
    ssize_t got = read(pipefd[0], &e, sizeof e);
    close(pipefd[0]);
    p->pid = pid;
    p->started_s = chk_now_s();
    if (got == (ssize_t)sizeof e) {
        chk_process_wait(p, 5.0);
        return nc_error_set(err, 1, "cannot run %s: %s", argv[0], strerror(e));
    }
    return 0;
}

static int reap(chk_process *p, int options)
{
    if (!p->pid || p->exited) return p->exited;
    int st = 0;
    pid_t r = waitpid(p->pid, &st, options);
    if (r != p->pid) return 0;
    p->exited = 1;
    p->exited_s = chk_now_s();
    p->status = WIFEXITED(st) ? WEXITSTATUS(st) : WIFSIGNALED(st) ? 128 + WTERMSIG(st) : 255;
    return 1;
}

int chk_process_wait(chk_process *p, double timeout_s)
{
    double until = chk_now_s() + timeout_s;
    for (;;) {
        if (reap(p, WNOHANG)) return 1;
        if (chk_now_s() >= until) return 0;
        pause_s(0.02);
    }
}

void chk_process_stop(chk_process *p, double grace_s)
{
    if (!p->pid || reap(p, WNOHANG)) return;
    kill(-p->pid, SIGTERM);
    kill(-p->pid, SIGCONT);
    if (chk_process_wait(p, grace_s)) return;
    kill(-p->pid, SIGKILL);
    reap(p, 0);
}

int chk_wait_endpoint_file(chk_process *p, const char *path, double timeout_s, char *line,
                           size_t size, nc_error *err)
{
    double until = chk_now_s() + timeout_s;
    for (;;) {
        FILE *f = fopen(path, "r");
        if (f) {
            char buf[512];
            size_t n = fread(buf, 1, sizeof buf - 1, f);
            fclose(f);
            buf[n] = '\0';
            char *nl = strchr(buf, '\n');
            /* written through a rename, so a complete file is there at once; a file without
             * its newline would be a writer that does not follow §7 */
            if (n > 0) {
                if (nl) *nl = '\0';
                snprintf(line, size, "%s", buf);
                return 0;
            }
        }
        if (reap(p, WNOHANG))
            return nc_error_set(err, 1, "the participant exited with status %d before writing %s",
                                p->status, path);
        if (chk_now_s() >= until)
            return nc_error_set(err, 1, "no endpoint file %s within %.0f s", path, timeout_s);
        pause_s(0.02);
    }
}

void chk_last_log_line(const char *log_path, char *out, size_t size)
{
    out[0] = '\0';
    FILE *f = fopen(log_path, "r");
    if (!f) return;
    char buf[1024];
    while (fgets(buf, sizeof buf, f)) {
        size_t n = strlen(buf);
        while (n && (buf[n - 1] == '\n' || buf[n - 1] == '\r' || buf[n - 1] == ' ')) buf[--n] = '\0';
        if (n) snprintf(out, size, "%s", buf);
    }
    fclose(f);
}
