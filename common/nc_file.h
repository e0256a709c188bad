/* nc_file — small file-system helpers the programs share: the folder of an input file, paths
 * given relative to it, output folders created with their parents, and files replaced atomically (endpoint files, XDMF descriptions) or durably as well (checkpoints and their manifest).
 */
#ifndef NC_FILE_H
#define NC_FILE_H

#include <stddef.h>
#include <stdio.h>

#include "nc_error.h"

/* The folder part of `path` into dir: "cases/x/in.json" -> "cases/x", "in.json" -> ".",
 * "/in.json" -> "". Truncated to size. */
void nc_file_dir(const char *path, char *dir, size_t size);

/* `path` taken relative to the folder `base_dir` into out: "base_dir/path", or `path` itself
 * when it is absolute or base_dir is NULL or "". Truncated to size. */
void nc_file_join(const char *base_dir, const char *path, char *out, size_t size);

/* Creates the folder `path` and its missing parents (like `mkdir -p`); an existing folder is
 * fine. Fails naming the folder and the OS reason. */
int nc_file_make_dirs(const char *path, nc_error *err);

/* Replacing a file atomically: nc_file_replace_open() opens "<path>.tmp" for writing (its name
 * into tmp), the caller writes, nc_file_replace_commit() closes it, checks that every write
 * succeeded and renames it over path, so a reader never sees a half-written file. On an error
 * both return NULL / -1 with err set (commit has closed the file either way). */
FILE *nc_file_replace_open(const char *path, char *tmp, size_t tmp_size, nc_error *err);
int nc_file_replace_commit(FILE *f, const char *tmp, const char *path, nc_error *err);

/* Replacing a file durably: `bytes` of data are written to "<path>.tmp" (plain system calls,
 * so a full disk is reported with the operating system's reason), flushed to disk (fsync),
 * renamed over path and the folder flushed, so that once it returns 0 the new file survives a
 * crash. On an error the previous version of path is as it was, "<path>.tmp" is removed and
 * the message names the file and the reason. */
int nc_file_write_durably(const char *path, const void *data, size_t bytes, nc_error *err);

/* Writes `line` and a newline to `path` through "<path>.tmp" and a rename, so a reader polling
 * for the file never sees it half written. */
int nc_file_write_line(const char *path, const char *line, nc_error *err);

#endif
