/* chk_report — the result table of netcouple-check (chk_report.h). */
#include "chk_report.h"

#include <cjson/cJSON.h>
#include <stdarg.h>
#include <stdlib.h>
#include <string.h>

void chk_report_init(chk_report *r, FILE *live)
{
    memset(r, 0, sizeof *r);
    r->live = live;
}

const char *chk_verdict_name(chk_verdict v)
{
    switch (v) {
    case CHK_PASS: return "PASS";
    case CHK_FAIL: return "FAIL";
    case CHK_WARN: return "WARN";
    default: return "SKIP";
    }
}

void chk_report_add(chk_report *r, const char *name, chk_verdict verdict, const char *format, ...)
{
    if (verdict == CHK_FAIL) r->n_failed++;
    if (r->n_rows >= CHK_MAX_ROWS) {
        r->n_dropped++;
        return;
    }
    chk_row *row = &r->rows[r->n_rows++];
    snprintf(row->name, sizeof row->name, "%s", name);
    row->verdict = verdict;
    va_list args;
    va_start(args, format);
    vsnprintf(row->detail, sizeof row->detail, format, args);
    va_end(args);
    /* one line per row: newlines of a participant's message would break the table */
    for (char *c = row->detail; *c; c++)
        if (*c == '\n' || *c == '\r' || *c == '\t') *c = ' ';
    if (r->live) {
        fprintf(r->live, "  %-4s  %-34s %s\n", chk_verdict_name(verdict), row->name, row->detail);
        fflush(r->live);
    }
}

void chk_report_print(const chk_report *r, FILE *f)
{
    size_t count[4] = {0, 0, 0, 0};
    fprintf(f, "%-6s%-35s%s\n", "", "check", "detail");
    for (size_t i = 0; i < r->n_rows; i++) {
        const chk_row *row = &r->rows[i];
        count[row->verdict]++;
        fprintf(f, "%-6s%-35s%s\n", chk_verdict_name(row->verdict), row->name, row->detail);
    }
    if (r->n_dropped)
        fprintf(f, "(%zu more rows not shown)\n", r->n_dropped);
    fprintf(f, "%zu passed, %zu failed, %zu warnings, %zu skipped\n", count[CHK_PASS],
            r->n_failed, count[CHK_WARN], count[CHK_SKIP]);
}

int chk_report_write_json(const chk_report *r, const char *path, const char *program,
                          const char *role, nc_error *err)
{
    cJSON *root = cJSON_CreateObject();
    cJSON *checks = cJSON_CreateArray();
    if (!root || !checks) {
        cJSON_Delete(root);
        cJSON_Delete(checks);
        return nc_error_set(err, 1, "%s: out of memory", path);
    }
    cJSON_AddStringToObject(root, "program", program ? program : "");
    cJSON_AddStringToObject(root, "role", role ? role : "");
    cJSON_AddBoolToObject(root, "passed", r->n_failed == 0);
    cJSON_AddNumberToObject(root, "failed", (double)r->n_failed);
    cJSON_AddItemToObject(root, "checks", checks);
    for (size_t i = 0; i < r->n_rows; i++) {
        cJSON *row = cJSON_CreateObject();
        if (!row) break;
        cJSON_AddStringToObject(row, "name", r->rows[i].name);
        cJSON_AddStringToObject(row, "verdict", chk_verdict_name(r->rows[i].verdict));
        cJSON_AddStringToObject(row, "detail", r->rows[i].detail);
        cJSON_AddItemToArray(checks, row);
    }
    char *text = cJSON_Print(root);
    cJSON_Delete(root);
    if (!text) return nc_error_set(err, 1, "%s: out of memory", path);
    FILE *f = fopen(path, "w");
    int bad = !f || fputs(text, f) < 0 || fputc('\n', f) < 0;
    if (f && fclose(f) != 0) bad = 1;
    free(text);
    if (bad) return nc_error_set(err, 1, "%s: cannot write the JSON report", path);
    return 0;
}
