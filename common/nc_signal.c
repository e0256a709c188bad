/* nc_signal — the SIGINT/SIGTERM handler of the programs and the flag it sets. */
#include "nc_signal.h"

#include <string.h>

/* the only global of the libraries: a signal handler can only talk through one */
static volatile sig_atomic_t nc_stop_signal = 0;

static void on_stop_signal(int sig)
{
    nc_stop_signal = sig;
}

const volatile sig_atomic_t *nc_signal_catch_stop(void)
{
    struct sigaction sa;
    memset(&sa, 0, sizeof sa);
    sa.sa_handler = on_stop_signal;   /* no SA_RESTART: a blocking wait returns on Ctrl-C */
    sigemptyset(&sa.sa_mask);
    sigaction(SIGINT, &sa, NULL);
    sigaction(SIGTERM, &sa, NULL);
    return &nc_stop_signal;
}
