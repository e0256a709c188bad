/* libFuzzer target of fem.json (fem_input_load): any input is either a finalised model or a
 * refusal with a message; ASan/UBSan catch the rest. */
#include <stdint.h>
#include <unistd.h>

#include "../fem_input.h"
#include "../../common/fuzz/nc_fuzz_memfile.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    char path[64];
    int fd = nc_fuzz_memfile(data, size, path, sizeof path);
    if (fd < 0) return 0;
    fem_model m;
    nc_error err;
    int rc = fem_input_load(path, &m, &err);
    if (rc == 0) {
        for (int e = 0; e < 2 * m.n_elements; e++)
            if (m.conn[e] < 0 || m.conn[e] >= m.n_nodes) __builtin_trap();
    } else if (err.message[0] == '\0') {
        __builtin_trap();
    }
    fem_model_free(&m);
    close(fd);
    return 0;
}
