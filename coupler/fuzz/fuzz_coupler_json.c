/* libFuzzer target of coupler.json (cpl_config_load): any input is either read or refused
 * with a message; ASan/UBSan catch the rest. */
#include <stdint.h>
#include <unistd.h>

#include "../cpl_config.h"
#include "../../common/fuzz/nc_fuzz_memfile.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    char path[64];
    int fd = nc_fuzz_memfile(data, size, path, sizeof path);
    if (fd < 0) return 0;
    cpl_config c;
    cpl_config_default(&c);
    nc_error err;
    if (cpl_config_load(&c, path, &err) != 0 && err.message[0] == '\0') __builtin_trap();
    close(fd);
    return 0;
}
