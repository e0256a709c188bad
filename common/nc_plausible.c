/* nc_plausible — the shared warning writer (nc_plausible.h). */
#include "nc_plausible.h"

#include <stdarg.h>

void nc_warn(FILE *sink, const char *format, ...)
{
    if (!sink) return;
    va_list args;
    va_start(args, format);
    fputs("warning: ", sink);
    vfprintf(sink, format, args);
    fputc('\n', sink);
    va_end(args);
}
