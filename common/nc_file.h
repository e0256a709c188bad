/* nc_file — small file-system helpers the programs share: the folder of an input file, paths
 * given relative to it, and small files replaced atomically (endpoint files).
 */
#ifndef NC_FILE_H
#define NC_FILE_H

#include <stddef.h>

#include "nc_error.h"

/* The folder part of `path` into dir: "cases/x/in.json" -> "cases/x", "in.json" -> ".",
 * "/in.json" -> "". Truncated to size. */
void nc_file_dir(const char *path, char *dir, size_t size);

/* `path` taken relative to the folder `base_dir` into out: "base_dir/path", or `path` itself
 * when it is absolute or base_dir is NULL or "". Truncated to size. */
void nc_file_join(const char *base_dir, const char *path, char *out, size_t size);

/* Writes `line` and a newline to `path` through "<path>.tmp" and a rename, so a reader polling
 * for the file never sees it half written. */
int nc_file_write_line(const char *path, const char *line, nc_error *err);

#endif
