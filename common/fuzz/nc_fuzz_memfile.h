/* nc_fuzz_memfile — the fuzz targets of the file readers hand their input to the reader as a
 * file without touching the disk: an anonymous memory file, opened by its /proc path. */
#ifndef NC_FUZZ_MEMFILE_H
#define NC_FUZZ_MEMFILE_H

#include <stddef.h>
#include <stdint.h>

/* Writes the bytes to a new memory file; path gets "/proc/self/fd/N". Returns the file
 * descriptor (close it after use) or -1. */
int nc_fuzz_memfile(const uint8_t *data, size_t size, char *path, size_t path_size);

#endif
