/* nc_file — input-file folders, relative paths and atomically replaced small files. */
#include "nc_file.h"

#include <errno.h>
#include <stdio.h>
#include <string.h>

void nc_file_dir(const char *path, char *dir, size_t size)
{
    snprintf(dir, size, "%s", path);
    char *slash = strrchr(dir, '/');
    if (slash) *slash = '\0';
    else snprintf(dir, size, ".");
}

void nc_file_join(const char *base_dir, const char *path, char *out, size_t size)
{
    if (path[0] == '/' || !base_dir || !base_dir[0]) snprintf(out, size, "%s", path);
    else snprintf(out, size, "%s/%s", base_dir, path);
}

int nc_file_write_line(const char *path, const char *line, nc_error *err)
{
    char tmp[1100];
    snprintf(tmp, sizeof tmp, "%s.tmp", path);
    FILE *f = fopen(tmp, "w");
    if (!f) return nc_error_set(err, 1, "%s: cannot write: %s", tmp, strerror(errno));
    fprintf(f, "%s\n", line);
    if (fclose(f)) return nc_error_set(err, 1, "%s: write failed", tmp);
    if (rename(tmp, path)) return nc_error_set(err, 1, "%s: cannot rename to %s", tmp, path);
    return 0;
}
