/* fem_test_util — linked into every fem_solver test (see fem_test_util.h). */
#include "fem_test_util.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

void fem_test_line(fem_model *m, int n_el, double length, double E, double A, double rho,
                   double S_pre, fem_behaviour behaviour, int fix_ends)
{
    nc_error err;
    fem_model_init(m, "test-line");
    fem_model_alloc(m, n_el + 1, n_el, &err);
    for (int i = 0; i <= n_el; i++) m->X[3 * i] = length * i / n_el;
    for (int e = 0; e < n_el; e++) {
        m->conn[2 * e] = e;
        m->conn[2 * e + 1] = e + 1;
    }
    fem_element_set set;
    memset(&set, 0, sizeof set);
    snprintf(set.name, sizeof set.name, "line");
    set.youngs_modulus_pa = E;
    set.area_m2 = A;
    set.density_kg_m3 = rho;
    set.prestress_pa = S_pre;
    set.behaviour = behaviour;
    fem_model_add_set(m, &set, &err);
    if (fix_ends)
        for (int c = 0; c < 3; c++) m->fixed[c] = m->fixed[3 * n_el + c] = 1;
}

const fem_node_set *fem_test_net(fem_model *m, int n, const fem_element_set *set, nc_error *err)
{
    const double origin[3] = {0, 0, 0}, edge1[3] = {1, 0, 0}, edge2[3] = {0, 1, 0};
    fem_model_init(m, "test-net");
    if (fem_model_add_set(m, set, err) != 0) return NULL;
    if (fem_model_generate_net(m, origin, edge1, edge2, n, n, 0, err)) return NULL;
    const fem_node_set *b = fem_model_find_node_set(m, "boundary");
    if (!b) {
        nc_error_set(err, 1, "test-net: no boundary node set");
        return NULL;
    }
    for (int i = 0; i < b->count; i++)
        for (int c = 0; c < 3; c++) m->fixed[3 * b->nodes[i] + c] = 1;
    return b;
}

const char *fem_test_write(const char *name, const char *text)
{
    static char paths[8][512];
    static int next = 0;
    char *path = paths[next++ % 8];
    const char *dir = getenv("NC_TMP");
    if (!dir || !*dir) dir = "/tmp";
    snprintf(path, 512, "%s/%d-%s", dir, (int)getpid(), name);
    FILE *f = fopen(path, "w");
    if (f) {
        fputs(text, f);
        fclose(f);
    }
    return path;
}

pid_t fem_test_spawn(const char *json, const char *outdir, const char *epfile, const char *idle_s)
{
    const char *bin = getenv("NC_BIN");
    char prog[1024];
    snprintf(prog, sizeof prog, "%s/fem_solver", bin ? bin : "bin");
    unlink(epfile);
    pid_t pid = fork();
    if (pid == 0) {
        if (!freopen("/dev/null", "w", stdout)) _exit(126);
        execl(prog, prog, json, "--endpoint", "tcp://127.0.0.1:*", "--endpoint-file", epfile,
              "--output", outdir, "--idle-timeout", idle_s, (char *)NULL);
        _exit(127);
    }
    return pid;
}

int fem_test_read_endpoint(const char *file, char *ep, size_t size)
{
    for (int i = 0; i < 300; i++) {   /* up to 30 s (sanitizer builds start slowly) */
        FILE *f = fopen(file, "r");
        if (f) {
            int ok = fgets(ep, (int)size, f) != NULL;
            fclose(f);
            if (ok) {
                ep[strcspn(ep, "\n")] = '\0';
                return 0;
            }
        }
        usleep(100000);
    }
    return -1;
}

int fem_test_wait_exit(pid_t pid, double timeout_s)
{
    for (int i = 0; i < (int)(timeout_s * 10); i++) {
        int status;
        if (waitpid(pid, &status, WNOHANG) == pid) return WIFEXITED(status) ? WEXITSTATUS(status) : 128;
        usleep(100000);
    }
    kill(pid, SIGKILL);
    waitpid(pid, NULL, 0);
    return -1;
}
