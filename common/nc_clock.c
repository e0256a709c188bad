/* nc_clock — monotonic clock (see nc_clock.h). */
#include "nc_clock.h"

#include <time.h>

double nc_clock_now_s(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}
