/* nc_fuzz_memfile — see nc_fuzz_memfile.h. */
#define _GNU_SOURCE
#include "nc_fuzz_memfile.h"

#include <stdio.h>
#include <sys/mman.h>
#include <unistd.h>

int nc_fuzz_memfile(const uint8_t *data, size_t size, char *path, size_t path_size)
{
    int fd = memfd_create("fuzz_input", 0);
    if (fd < 0) return -1;
    size_t done = 0;
    while (done < size) {
        ssize_t n = write(fd, data + done, size - done);
        if (n <= 0) {
            close(fd);
            return -1;
        }
        done += (size_t)n;
    }
    snprintf(path, path_size, "/proc/self/fd/%d", fd);
    return fd;
}
