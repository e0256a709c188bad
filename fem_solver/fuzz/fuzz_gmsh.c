/* libFuzzer target of the Gmsh reader (2.2 and 4.1): any input is either read into a mesh
 * whose every index is in range, or refused with a message; ASan/UBSan catch the rest. */
#include <stdint.h>
#include <unistd.h>

#include "../fem_mesh_gmsh.h"
#include "../../common/fuzz/nc_fuzz_memfile.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    char path[64];
    int fd = nc_fuzz_memfile(data, size, path, sizeof path);
    if (fd < 0) return 0;
    fem_gmsh_mesh g;
    nc_error err;
    if (fem_gmsh_read(path, &g, &err) == 0) {
        for (int i = 0; i < 2 * g.n_lines; i++)
            if (g.lines[i] < 0 || g.lines[i] >= g.n_nodes) __builtin_trap();
        for (int i = 0; i < g.n_points; i++)
            if (g.points[i] < 0 || g.points[i] >= g.n_nodes) __builtin_trap();
        double sum = 0;
        for (int i = 0; i < 3 * g.n_nodes; i++) sum += g.X[i];
        if (sum != sum) __builtin_trap(); /* non-finite coordinates are refused */
        fem_gmsh_free(&g);
    } else if (err.message[0] == '\0') {
        __builtin_trap(); /* every refusal says why */
    }
    close(fd);
    return 0;
}
