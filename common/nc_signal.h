/* nc_signal — the stop request of the command-line programs: SIGINT and SIGTERM set a flag
 * that the run loops poll, so a run ends after its current step (or wait) with its results
 * complete and readable, and the program chooses its exit code (130 / 143).
 */
#ifndef NC_SIGNAL_H
#define NC_SIGNAL_H

#include <signal.h>

/* Installs the handler for SIGINT and SIGTERM and returns the flag it sets: 0 until one of
 * them arrives, then that signal's number. The handler is installed without SA_RESTART, so a
 * blocking wait (a socket poll, a sleep) returns early when the signal arrives. Call once at
 * start-up, from the main thread. */
const volatile sig_atomic_t *nc_signal_catch_stop(void);

#endif
