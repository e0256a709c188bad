/* netcouple-check — conformance harness for a participant of the netcouple protocol.
 *
 *   netcouple-check [--role fem|dem] [options] -- PROGRAM [ARGS...]
 *   netcouple-check [--role fem|dem] [options] --endpoint EP
 *
 * Plays the coupler against one participant (chk_checks.h says which runs and checks) and
 * prints a PASS/FAIL/WARN/SKIP table. Exit status: 0 when no check failed (with --strict: no
 * check failed or warned), 1 when one did, 2 on bad arguments or when the checks could not
 * run. protocol/check/README.md is the user documentation.
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "chk_checks.h"
#include "chk_report.h"

static void usage(FILE *f)
{
    fprintf(f,
            "usage: netcouple-check [--role fem|dem] [options] -- PROGRAM [ARGS...]\n"
            "       netcouple-check [--role fem|dem] [options] --endpoint EP\n"
            "Plays the coupler against a participant of the netcouple protocol and prints a\n"
            "table of checks. PROGRAM ARGS... is started as a launcher starts it, with\n"
            "  --endpoint tcp://127.0.0.1:* --endpoint-file FILE --output DIR --idle-timeout S\n"
            "appended (three times: a clean run, a run with provoked errors, an idle run).\n"
            "options:\n"
            "  --role fem|dem         the role to check (default: the one its hello names)\n"
            "  --timeout S            reply timeout per command (default 20)\n"
            "  --start-timeout S      time allowed until the endpoint file (default 60)\n"
            "  --idle-timeout S       passed to the clean and error runs (default 60)\n"
            "  --dt S                 step size sent (default 0.001)\n"
            "  --force N              fem: load on the central interface node, -z (default 100)\n"
            "  --interface FILE       dem: interface JSON to send (default: a 3 x 3 net, 0.5 m\n"
            "                         spacing, in the plane z = 0 centred at the origin)\n"
            "  --save-interface FILE  fem: write the interface received (input for --interface)\n"
            "  --work DIR             keep the run folders (logs, outputs) in DIR\n"
            "  --json FILE            also write the table as JSON\n"
            "  --strict               a WARN fails the check too\n"
            "  --no-idle-check        skip the idle run\n"
            "exit status: 0 passed, 1 a check failed, 2 bad arguments or not run\n");
}

static int number(const char *option, const char *text, double low, double *out)
{
    char *end;
    double x = strtod(text, &end);
    if (*end || end == text || !(x >= low) || x != x) {
        fprintf(stderr, "netcouple-check: %s: expected a number >= %g, got \"%s\"\n", option, low, text);
        return -1;
    }
    *out = x;
    return 0;
}

int main(int argc, char **argv)
{
    chk_config cfg;
    memset(&cfg, 0, sizeof cfg);
    cfg.timeout_s = 20;
    cfg.start_timeout_s = 60;
    cfg.idle_timeout_s = 60;
    cfg.dt_s = 1e-3;
    cfg.force_n = 100;
    cfg.idle_check = 1;
    const char *json = NULL;
    int strict = 0;
    for (int i = 1; i < argc; i++) {
        const char *a = argv[i];
        const char *v = i + 1 < argc ? argv[i + 1] : NULL;
        double x;
        if (!strcmp(a, "--")) {
            if (i + 1 >= argc) {
                fprintf(stderr, "netcouple-check: nothing after --: give PROGRAM [ARGS...]\n");
                return 2;
            }
            cfg.program = argv + i + 1;
            break;
        } else if (!strcmp(a, "-h") || !strcmp(a, "--help")) {
            usage(stdout);
            return 0;
        } else if (!strcmp(a, "--strict")) {
            strict = 1;
        } else if (!strcmp(a, "--no-idle-check")) {
            cfg.idle_check = 0;
        } else if (!v) {
            fprintf(stderr, "netcouple-check: %s: unknown option or missing value (see --help)\n", a);
            return 2;
        } else if (!strcmp(a, "--role")) {
            if (strcmp(v, "fem") && strcmp(v, "dem")) {
                fprintf(stderr, "netcouple-check: --role: expected fem or dem, got \"%s\"\n", v);
                return 2;
            }
            cfg.role = v;
            i++;
        } else if (!strcmp(a, "--endpoint")) { cfg.endpoint = v; i++; }
        else if (!strcmp(a, "--interface")) { cfg.interface_file = v; i++; }
        else if (!strcmp(a, "--save-interface")) { cfg.save_interface = v; i++; }
        else if (!strcmp(a, "--work")) { cfg.work_dir = v; i++; }
        else if (!strcmp(a, "--json")) { json = v; i++; }
        else if (!strcmp(a, "--timeout") || !strcmp(a, "--start-timeout") ||
                 !strcmp(a, "--idle-timeout") || !strcmp(a, "--dt") || !strcmp(a, "--force")) {
            if (number(a, v, !strcmp(a, "--force") ? 0.0 : 1e-9, &x)) return 2;
            if (!strcmp(a, "--timeout")) cfg.timeout_s = x;
            else if (!strcmp(a, "--start-timeout")) cfg.start_timeout_s = x;
            else if (!strcmp(a, "--idle-timeout")) cfg.idle_timeout_s = x;
            else if (!strcmp(a, "--dt")) cfg.dt_s = x;
            else cfg.force_n = x;
            i++;
        } else {
            fprintf(stderr, "netcouple-check: unknown option %s (see --help)\n", a);
            return 2;
        }
    }
    if (!cfg.program == !cfg.endpoint) {
        fprintf(stderr, "netcouple-check: give either -- PROGRAM [ARGS...] or --endpoint EP (see --help)\n");
        return 2;
    }
    if (cfg.program && cfg.timeout_s >= cfg.idle_timeout_s) {
        fprintf(stderr, "netcouple-check: --timeout (%g s) must be shorter than --idle-timeout "
                "(%g s), as for the coupler\n", cfg.timeout_s, cfg.idle_timeout_s);
        return 2;
    }
    char program[512] = "";
    if (cfg.program)
        for (char **p = cfg.program; *p; p++)
            snprintf(program + strlen(program), sizeof program - strlen(program), "%s%s",
                     p == cfg.program ? "" : " ", *p);
    else
        snprintf(program, sizeof program, "%s", cfg.endpoint);

    static chk_report report;   /* large: not on the stack */
    chk_report_init(&report, NULL);
    printf("netcouple-check: %s%s%s\n", program, cfg.role ? ", role " : "", cfg.role ? cfg.role : "");
    fflush(stdout);
    nc_error err;
    nc_error_clear(&err);
    if (chk_run(&cfg, &report, &err)) {
        fprintf(stderr, "netcouple-check: %s\n", err.message);
        return 2;
    }
    chk_report_print(&report, stdout);
    size_t warnings = 0;
    for (size_t i = 0; i < report.n_rows; i++) warnings += report.rows[i].verdict == CHK_WARN;
    int failed = report.n_failed > 0 || (strict && warnings > 0);
    if (json && chk_report_write_json(&report, json, program, cfg.role, &err)) {
        fprintf(stderr, "netcouple-check: %s\n", err.message);
        return 2;
    }
    printf("%s\n", failed ? (report.n_failed ? "FAILED: the participant does not conform (see the FAIL rows)"
                                             : "FAILED (--strict): see the WARN rows")
                          : "PASSED: the participant conforms to protocol version 2 as checked");
    return failed ? 1 : 0;
}
