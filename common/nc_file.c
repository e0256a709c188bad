/* nc_file — input-file folders, relative paths and atomically replaced files. */
#include "nc_file.h"

#include <errno.h>
#include <fcntl.h>
#include <stdio.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

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

int nc_file_make_dirs(const char *path, nc_error *err)
{
    char buf[4096];
    if (!path[0]) return nc_error_set(err, 1, "output folder: empty path");
    if ((size_t)snprintf(buf, sizeof buf, "%s", path) >= sizeof buf)
        return nc_error_set(err, 1, "%s: path too long", path);
    for (char *p = buf + 1; ; p++) {
        if (*p != '/' && *p != '\0') continue;
        char c = *p;
        *p = '\0';
        struct stat st;
        if (mkdir(buf, 0777) != 0 && errno != EEXIST)
            return nc_error_set(err, 1, "%s: cannot create folder: %s", buf, strerror(errno));
        if (stat(buf, &st) != 0 || !S_ISDIR(st.st_mode))
            return nc_error_set(err, 1, "%s: exists and is not a folder", buf);
        if (c == '\0') break;
        *p = c;
    }
    return 0;
}

FILE *nc_file_replace_open(const char *path, char *tmp, size_t tmp_size, nc_error *err)
{
    if ((size_t)snprintf(tmp, tmp_size, "%s.tmp", path) >= tmp_size) {
        nc_error_set(err, 1, "%s: path too long", path);
        return NULL;
    }
    FILE *f = fopen(tmp, "w");
    if (!f) nc_error_set(err, 1, "%s: cannot write: %s", tmp, strerror(errno));
    return f;
}

int nc_file_replace_commit(FILE *f, const char *tmp, const char *path, nc_error *err)
{
    /* the reason of a failed buffered write shows again when the buffer is flushed */
    errno = 0;
    int bad = fflush(f) != 0 || ferror(f);
    int why = bad ? errno : 0;
    if (fclose(f) != 0 && !bad) {
        bad = 1;
        why = errno;
    }
    if (bad) {
        remove(tmp);   /* the previous version of path stays as it was */
        return nc_error_set(err, 1, "%s: cannot write: %s", path, why ? strerror(why) : "write error");
    }
    if (rename(tmp, path) != 0) {
        why = errno;
        remove(tmp);
        return nc_error_set(err, 1, "%s: cannot rename to %s: %s", tmp, path, strerror(why));
    }
    return 0;
}

/* fsync of a folder: the rename in it is durable once it is (some file systems cannot). */
static int sync_folder(const char *dir, nc_error *err)
{
    int fd = open(dir, O_RDONLY | O_DIRECTORY);
    if (fd < 0) return nc_error_set(err, 1, "%s: cannot open the folder to flush it: %s", dir, strerror(errno));
    int rc = fsync(fd), why = errno;
    close(fd);
    if (rc != 0 && why != EINVAL && why != EROFS)
        return nc_error_set(err, 1, "%s: cannot flush the folder to disk: %s", dir, strerror(why));
    return 0;
}

int nc_file_write_durably(const char *path, const void *data, size_t bytes, nc_error *err)
{
    char tmp[4200];
    if ((size_t)snprintf(tmp, sizeof tmp, "%s.tmp", path) >= sizeof tmp)
        return nc_error_set(err, 1, "%s: path too long", path);
    int fd = open(tmp, O_WRONLY | O_CREAT | O_TRUNC, 0644);
    if (fd < 0) return nc_error_set(err, 1, "%s: cannot create: %s", tmp, strerror(errno));
    const char *p = data;
    size_t left = bytes;
    const char *what = NULL;
    int why = 0;
    while (left > 0 && !what) {
        ssize_t w = write(fd, p, left);
        if (w < 0 && errno == EINTR) continue;
        if (w <= 0) {
            what = "cannot write";
            why = w < 0 ? errno : ENOSPC;
        } else {
            p += w;
            left -= (size_t)w;
        }
    }
    if (!what && fsync(fd) != 0) {
        what = "cannot flush to disk";
        why = errno;
    }
    if (close(fd) != 0 && !what) {
        what = "cannot close";
        why = errno;
    }
    if (!what && rename(tmp, path) != 0) {
        why = errno;
        unlink(tmp);
        return nc_error_set(err, 1, "%s: cannot rename %s into place: %s", path, tmp, strerror(why));
    }
    if (what) {
        unlink(tmp);   /* the previous version of path stays as it was */
        return nc_error_set(err, 1, "%s: %s: %s", tmp, what, strerror(why));
    }
    char dir[4200];
    nc_file_dir(path, dir, sizeof dir);
    return sync_folder(dir[0] ? dir : "/", err);
}

int nc_file_write_line(const char *path, const char *line, nc_error *err)
{
    char tmp[1100];
    FILE *f = nc_file_replace_open(path, tmp, sizeof tmp, err);
    if (!f) return -1;
    fprintf(f, "%s\n", line);
    return nc_file_replace_commit(f, tmp, path, err);
}
