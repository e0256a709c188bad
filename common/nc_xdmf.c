/* nc_xdmf — an XDMF temporal collection grown in place, one output step at a time. */
#include "nc_xdmf.h"

#include "nc_file.h"

#include <errno.h>
#include <fcntl.h>
#include <stdio.h>
#include <string.h>
#include <sys/uio.h>
#include <unistd.h>

int nc_xdmf_create(nc_xdmf_file *x, const char *path, const char *head, const char *grids,
                   size_t grids_len, const char *tail, nc_error *err)
{
    nc_xdmf_close(x);
    if ((size_t)snprintf(x->path, sizeof x->path, "%s", path) >= sizeof x->path)
        return nc_error_set(err, 1, "%s: path too long", path);
    char tmp[sizeof x->path + 8];
    FILE *f = nc_file_replace_open(path, tmp, sizeof tmp, err);
    if (!f) return -1;
    fputs(head, f);
    if (grids_len) fwrite(grids, 1, grids_len, f);
    fputs(tail, f);
    if (nc_file_replace_commit(f, tmp, path, err)) return -1;
    x->fd = open(path, O_WRONLY | O_CLOEXEC);
    if (x->fd < 0) return nc_error_set(err, 1, "%s: cannot reopen to add steps: %s", path, strerror(errno));
    x->open = 1;
    x->tail_at = (off_t)(strlen(head) + grids_len);
    x->tail = tail;
    return 0;
}

int nc_xdmf_append(nc_xdmf_file *x, const char *grid, size_t grid_len, nc_error *err)
{
    if (!x->open) return nc_error_set(err, 1, "%s: not open for adding steps", x->path);
    size_t tail_len = strlen(x->tail), want = grid_len + tail_len;
    struct iovec v[2] = {{(void *)grid, grid_len}, {(void *)x->tail, tail_len}};
    ssize_t w;
    do w = pwritev(x->fd, v, 2, x->tail_at);
    while (w < 0 && errno == EINTR);
    if (w == (ssize_t)want) {
        x->tail_at += (off_t)grid_len;
        return 0;
    }
    int why = w < 0 ? errno : ENOSPC;   /* a short write to a file: no room for the rest */
    /* the closing tags back where they were (inside the file's old length: needs no room) */
    ssize_t put = pwrite(x->fd, x->tail, tail_len, x->tail_at);
    int restored = put == (ssize_t)tail_len && ftruncate(x->fd, x->tail_at + (off_t)tail_len) == 0;
    return nc_error_set(err, 1, "%s: cannot add an output step: %s%s", x->path, strerror(why),
                        restored ? " (the file still lists the steps before it)" : "");
}

void nc_xdmf_close(nc_xdmf_file *x)
{
    if (x->open) close(x->fd);
    x->open = 0;
}
