/* cpl_checkpoint — the name of the coupler's checkpoint file (cpl_checkpoint.h). */
#include "cpl_checkpoint.h"

#include <stdio.h>

void cpl_checkpoint_path(const char *output_dir, const char *name, char *out, size_t size)
{
    snprintf(out, size, "%s/checkpoint/coupler_%s.h5", output_dir, name);
}
