/* nc_error — the one error convention of netcouple.
 *
 * Every function that can fail returns int: 0 on success, -1 on failure, and fills the
 * caller's nc_error with a human-readable message naming what was wrong (file, field, peer).
 * Libraries never print and never exit; programs print err.message and choose the exit code.
 * Passing err == NULL is allowed: the message is then dropped.
 */
#ifndef NC_ERROR_H
#define NC_ERROR_H

#include <stdarg.h>

#define NC_ERROR_MESSAGE_MAX 1024

typedef struct nc_error {
    int code;                            /* 0 = no error; otherwise a module-specific code */
    char message[NC_ERROR_MESSAGE_MAX];  /* "file.json: field 'nodes[3]': expected ..." */
} nc_error;

/* Clears err (code 0, empty message). */
void nc_error_clear(nc_error *err);

/* Sets err->code = code and formats the message; always returns -1 so callers can write
 * `return nc_error_set(err, 1, "...", ...);`. */
int nc_error_set(nc_error *err, int code, const char *format, ...)
    __attribute__((format(printf, 3, 4)));
int nc_error_vset(nc_error *err, int code, const char *format, va_list args);

/* Puts "<prefix>: " in front of the current message (e.g. a file name); returns -1. */
int nc_error_prefix(nc_error *err, const char *format, ...)
    __attribute__((format(printf, 2, 3)));

#endif
