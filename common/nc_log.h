/* nc_log — the few helpers programs share for timing and messages. */
#ifndef NC_LOG_H
#define NC_LOG_H

/* Monotonic wall-clock seconds (for timings and timeouts). */
double nc_now_s(void);

#endif
