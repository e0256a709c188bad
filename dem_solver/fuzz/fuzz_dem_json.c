/* libFuzzer target of dem.json (dem_config_load): any input is either read or refused with a
 * message; ASan/UBSan catch the rest. */
#include <stdint.h>
#include <unistd.h>

#include "../dem_config.h"
#include "../dem_sim.h"
#include "../../common/fuzz/nc_fuzz_memfile.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    char path[64];
    int fd = nc_fuzz_memfile(data, size, path, sizeof path);
    if (fd < 0) return 0;
    dem_sim s;
    dem_sim_init(&s);
    nc_error err;
    if (dem_config_load(&s, path, &err) != 0 && err.message[0] == '\0') __builtin_trap();
    dem_sim_free(&s);
    close(fd);
    return 0;
}
