/* cpl_heartbeat — progress file rewritten by the main thread per step and by a background
 * thread while the main thread waits for a participant. */
#include "cpl_heartbeat.h"

#include <errno.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "nc_clock.h"
#include "nc_file.h"

struct cpl_heartbeat {
    char path[1024];
    double every_s;
    pthread_t thread;
    pthread_mutex_t lock;        /* guards everything below and the file */
    pthread_cond_t wake;
    int stop;
    char state[32];
    char status[512];
    char peer[32];               /* "" while not waiting */
    double wait_since_s, wait_timeout_s;
    double last_write_s;
};

static int write_locked(cpl_heartbeat *hb, double now_s, nc_error *err)
{
    char tmp[1100];
    FILE *f = nc_file_replace_open(hb->path, tmp, sizeof tmp, err);
    if (!f) return -1;
    fprintf(f, "state %s\nstatus %s\n", hb->state, hb->status);
    if (hb->peer[0]) fprintf(f, "waiting %s %.1f\n", hb->peer, now_s - hb->wait_since_s);
    hb->last_write_s = now_s;
    return nc_file_replace_commit(f, tmp, hb->path, err);
}

static void *beat(void *arg)
{
    cpl_heartbeat *hb = arg;
    pthread_mutex_lock(&hb->lock);
    while (!hb->stop) {
        struct timespec until;
        clock_gettime(CLOCK_REALTIME, &until);
        long ns = until.tv_nsec + (long)(hb->every_s * 1e9);
        until.tv_sec += ns / 1000000000L;
        until.tv_nsec = ns % 1000000000L;
        int rc = 0;
        while (!hb->stop && rc != ETIMEDOUT) rc = pthread_cond_timedwait(&hb->wake, &hb->lock, &until);
        if (hb->stop) break;
        double now_s = nc_clock_now_s();
        /* a wait past its own timeout is a coupler that does not work as it should */
        if (hb->peer[0] && now_s - hb->wait_since_s <= hb->wait_timeout_s + CPL_HEARTBEAT_MARGIN_S &&
            now_s - hb->last_write_s >= hb->every_s * 0.5) {
            nc_error err;
            write_locked(hb, now_s, &err);   /* a failure shows at the main thread's next write */
        }
    }
    pthread_mutex_unlock(&hb->lock);
    return NULL;
}

int cpl_heartbeat_start(cpl_heartbeat **out, const char *path, double every_s, nc_error *err)
{
    *out = NULL;
    cpl_heartbeat *hb = calloc(1, sizeof *hb);
    if (!hb) return nc_error_set(err, 1, "%s: out of memory", path);
    snprintf(hb->path, sizeof hb->path, "%s", path);
    hb->every_s = every_s > 0.05 ? every_s : 0.05;
    snprintf(hb->state, sizeof hb->state, "connecting");
    pthread_mutex_init(&hb->lock, NULL);
    pthread_cond_init(&hb->wake, NULL);
    if (write_locked(hb, nc_clock_now_s(), err)) {
        nc_error_prefix(err, "progress file");
        pthread_mutex_destroy(&hb->lock);
        pthread_cond_destroy(&hb->wake);
        free(hb);
        return -1;
    }
    if (pthread_create(&hb->thread, NULL, beat, hb)) {
        pthread_mutex_destroy(&hb->lock);
        pthread_cond_destroy(&hb->wake);
        free(hb);
        return nc_error_set(err, 1, "%s: cannot start the heartbeat thread", path);
    }
    *out = hb;
    return 0;
}

int cpl_heartbeat_update(cpl_heartbeat *hb, const char *state, const char *status,
                         nc_error *err)
{
    if (!hb) return 0;
    pthread_mutex_lock(&hb->lock);
    int changed = state && strcmp(state, hb->state) != 0;
    if (state) snprintf(hb->state, sizeof hb->state, "%s", state);
    if (status) snprintf(hb->status, sizeof hb->status, "%s", status);
    double now_s = nc_clock_now_s();
    int rc = 0;
    if (changed || now_s - hb->last_write_s >= CPL_HEARTBEAT_MIN_INTERVAL_S) {
        rc = write_locked(hb, now_s, err);
        if (rc) nc_error_prefix(err, "progress file");
    }
    pthread_mutex_unlock(&hb->lock);
    return rc;
}

void cpl_heartbeat_wait_begin(cpl_heartbeat *hb, const char *peer, double timeout_s)
{
    if (!hb) return;
    pthread_mutex_lock(&hb->lock);
    snprintf(hb->peer, sizeof hb->peer, "%s", peer);
    hb->wait_since_s = nc_clock_now_s();
    hb->wait_timeout_s = timeout_s;
    pthread_mutex_unlock(&hb->lock);
}

void cpl_heartbeat_wait_end(cpl_heartbeat *hb)
{
    if (!hb) return;
    pthread_mutex_lock(&hb->lock);
    hb->peer[0] = '\0';
    pthread_mutex_unlock(&hb->lock);
}

void cpl_heartbeat_stop(cpl_heartbeat *hb)
{
    if (!hb) return;
    pthread_mutex_lock(&hb->lock);
    hb->stop = 1;
    pthread_cond_signal(&hb->wake);
    pthread_mutex_unlock(&hb->lock);
    pthread_join(hb->thread, NULL);
    pthread_mutex_destroy(&hb->lock);
    pthread_cond_destroy(&hb->wake);
    free(hb);
}
