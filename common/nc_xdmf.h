/* nc_xdmf — an XDMF temporal collection grown in place, one output step at a time.
 *
 * The file is its head (XML declaration, Domain, the collection's opening tag), the grids of
 * the steps written so far, and its closing tags. nc_xdmf_create() writes the head, the grids
 * already formatted (none for a new run, a checkpoint's steps for a resumed one) and the
 * closing tags through a temporary file and a rename. nc_xdmf_append() then writes one
 * step's grid over the closing tags followed by them again, in one system call: a step costs
 * its own bytes, not the whole file's (rewriting it would cost O(k²) bytes over k steps).
 *
 * Between calls the file is always a complete XDMF document. A failed append (a full disk)
 * puts the closing tags back where they were and cuts the file to its previous length, so
 * the file still lists exactly the steps before it, and the error names the file and the
 * reason.
 */
#ifndef NC_XDMF_H
#define NC_XDMF_H

#include <stddef.h>
#include <sys/types.h>

#include "nc_error.h"

/* All zero (memset, or = {0}) is a closed one. */
typedef struct nc_xdmf_file {
    char path[1100];
    int open;            /* fd is open */
    int fd;
    off_t tail_at;       /* where the closing tags start */
    const char *tail;    /* the closing tags (a string that outlives the file) */
} nc_xdmf_file;

/* Writes path = head + grids[0 .. grids_len) + tail atomically and keeps it open for
 * appending; tail must outlive x. A file x held before is closed first. */
int nc_xdmf_create(nc_xdmf_file *x, const char *path, const char *head, const char *grids,
                   size_t grids_len, const char *tail, nc_error *err);

/* Adds one step's grids (grid_len bytes) before the closing tags. */
int nc_xdmf_append(nc_xdmf_file *x, const char *grid, size_t grid_len, nc_error *err);

/* Closes the file (it stays as written). */
void nc_xdmf_close(nc_xdmf_file *x);

#endif
