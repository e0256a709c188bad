/* chk_report — the result table of netcouple-check: one row per check (name, verdict,
 * detail), printed as a plain-text table and optionally written as JSON.
 *
 * Verdicts: PASS, FAIL (a required property of protocol/README.md does not hold), WARN (the
 * participant works with the coupler but something is missing or doubtful: reported, does
 * not fail the run), SKIP (not applicable, e.g. restore not announced). The run fails when
 * any row is FAIL. Rows beyond CHK_MAX_ROWS are counted but not kept.
 */
#ifndef CHK_REPORT_H
#define CHK_REPORT_H

#include <stdio.h>
#include "nc_error.h"

#define CHK_MAX_ROWS 96
#define CHK_NAME_MAX 64
#define CHK_DETAIL_MAX 480

typedef enum { CHK_PASS = 0, CHK_FAIL, CHK_WARN, CHK_SKIP } chk_verdict;

typedef struct chk_row {
    char name[CHK_NAME_MAX];
    chk_verdict verdict;
    char detail[CHK_DETAIL_MAX];
} chk_row;

typedef struct chk_report {
    chk_row rows[CHK_MAX_ROWS];
    size_t n_rows;
    size_t n_dropped;      /* rows that did not fit (counted as FAIL when they were FAIL) */
    size_t n_failed;
    FILE *live;            /* when set, each row is also printed here as it is added */
} chk_report;

void chk_report_init(chk_report *r, FILE *live);
void chk_report_add(chk_report *r, const char *name, chk_verdict verdict, const char *format, ...)
    __attribute__((format(printf, 4, 5)));
const char *chk_verdict_name(chk_verdict v);
/* The table: one line per row, then "N passed, N failed, N warnings, N skipped". */
void chk_report_print(const chk_report *r, FILE *f);
/* {"program": ..., "role": ..., "passed": bool, "checks": [{"name","verdict","detail"}]} */
int chk_report_write_json(const chk_report *r, const char *path, const char *program,
                          const char *role, nc_error *err);

#endif
