/* nc_clock — a monotonic wall clock for timings, timeouts and progress. */
#ifndef NC_CLOCK_H
#define NC_CLOCK_H

/* Monotonic wall-clock seconds (for timings and timeouts). */
double nc_clock_now_s(void);

#endif
