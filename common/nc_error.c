/* nc_error — formatting of error messages (see nc_error.h). */
#include "nc_error.h"

#include <stdio.h>
#include <string.h>

void nc_error_clear(nc_error *err)
{
    if (!err) return;
    err->code = 0;
    err->message[0] = '\0';
}

int nc_error_vset(nc_error *err, int code, const char *format, va_list args)
{
    if (!err) return -1;
    err->code = code ? code : 1;
    vsnprintf(err->message, sizeof err->message, format, args);
    return -1;
}

int nc_error_set(nc_error *err, int code, const char *format, ...)
{
    va_list args;
    va_start(args, format);
    nc_error_vset(err, code, format, args);
    va_end(args);
    return -1;
}

int nc_error_prefix(nc_error *err, const char *format, ...)
{
    if (!err) return -1;
    char prefix[256];
    char old[NC_ERROR_MESSAGE_MAX];
    va_list args;
    va_start(args, format);
    vsnprintf(prefix, sizeof prefix, format, args);
    va_end(args);
    memcpy(old, err->message, sizeof old);
    size_t used = strlen(prefix);
    memcpy(err->message, prefix, used);
    snprintf(err->message + used, sizeof err->message - used, ": %s", old);
    if (!err->code) err->code = 1;
    return -1;
}
