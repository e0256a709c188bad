/* libFuzzer target of the STL reader (binary and ASCII): any input is either a welded mesh
 * whose every index is in range, or refused with a message; ASan/UBSan catch the rest. */
#include <stdint.h>
#include <string.h>
#include <unistd.h>

#include "../dem_stl.h"
#include "../../common/fuzz/nc_fuzz_memfile.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    char path[64];
    int fd = nc_fuzz_memfile(data, size, path, sizeof path);
    if (fd < 0) return 0;
    dem_mesh mesh;
    memset(&mesh, 0, sizeof mesh);
    nc_error err;
    if (dem_stl_load(&mesh, path, &err) == 0) {
        if (mesh.n_triangles == 0) __builtin_trap();
        for (size_t i = 0; i < 3 * mesh.n_triangles; i++)
            if (mesh.tri[i] < 0 || (size_t)mesh.tri[i] >= mesh.n_vertices ||
                mesh.tri_edges[i] < 0 || (size_t)mesh.tri_edges[i] >= mesh.n_edges)
                __builtin_trap();
    } else if (err.message[0] == '\0') {
        __builtin_trap();
    }
    dem_mesh_free(&mesh);
    close(fd);
    return 0;
}
