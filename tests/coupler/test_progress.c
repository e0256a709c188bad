/* Unit tests of cpl_progress with a fake clock: the remaining time follows the rate of the
 * recent wall time (not the rate since the start), the status line shows the engineering
 * quantities, a terminal line is cut to the terminal width, steps whose DEM linearisation
 * left particles out are warned about once. */
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <setjmp.h>
#include <cmocka.h>
#include "../nc_test_assert.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

#include "../../coupler/cpl_progress.h"

typedef struct fake_clock {
    double t_s;
} fake_clock;

static double fake_now(void *ctx)
{
    return ((fake_clock *)ctx)->t_s;
}

/* steps of dt simulated seconds, each taking wall_per_step, until sim reaches `until` */
static void run_steps(cpl_progress *p, fake_clock *c, long *step, double *sim, double dt,
                      double wall_per_step, double until)
{
    while (*sim < until - 1e-12) {
        c->t_s += wall_per_step;
        *sim += dt;
        cpl_step_record rec = {.step = (*step)++, .time_s = *sim, .dt_s = dt, .iterations = 3,
                               .converged = 1, .residual = 1e-9};
        cpl_progress_step(p, &rec, 1);
    }
}

static void test_remaining_time_follows_the_recent_rate(void **state)
{
    (void)state;
    FILE *out = tmpfile();
    assert_non_null(out);
    fake_clock c = {100.0};
    cpl_progress p;
    cpl_progress_init(&p, out, 0, 0, 1e9, 0.0, 10.0, 0.01);
    cpl_progress_use_clock(&p, fake_now, &c);
    assert_true(isnan(cpl_progress_remaining_s(&p)));   /* nothing done yet */
    long step = 0;
    double sim = 0.0;
    /* free flight: 1 simulated second per wall second, for 4 s */
    run_steps(&p, &c, &step, &sim, 0.01, 0.01, 4.0);
    /* the rate so far (the run is shorter than the window): 6 s left at rate 1 */
    assert_near_rel(cpl_progress_remaining_s(&p), 6.0, 1e-6);
    /* contact: ten times slower, for 40 s of wall time (longer than the window) */
    run_steps(&p, &c, &step, &sim, 0.01, 0.1, 8.0);
    /* 2 s left at 0.1 s per wall second = 20 s; the rate since the start
     * (8 s in 44 s) would say 11 s */
    assert_near_rel(cpl_progress_remaining_s(&p), 20.0, 1e-6);
    /* the rock leaves the net: fast again; after a whole window only the new rate counts */
    run_steps(&p, &c, &step, &sim, 0.001, 0.0005, 9.0);   /* 2 sim s per wall s, 0.5 s */
    double mixed = cpl_progress_remaining_s(&p);
    assert_true(mixed > 0.5 && mixed < 20.0);   /* part of the slow window is still in it */
    fake_clock before = c;
    /* a stall: no step for a minute, the estimate grows with it */
    c.t_s += 60.0;
    assert_true(cpl_progress_remaining_s(&p) > mixed);
    c = before;
    /* done: nothing remains */
    run_steps(&p, &c, &step, &sim, 0.001, 0.0005, 10.0);
    assert_near(cpl_progress_remaining_s(&p), 0.0, 0.0);
    fclose(out);
}

static void test_status_line_shows_contact_rock_and_deflection(void **state)
{
    (void)state;
    FILE *out = tmpfile();
    assert_non_null(out);
    fake_clock c = {0.0};
    cpl_progress p;
    cpl_progress_init(&p, out, 0, 0, 1e9, 0.0, 1.0, 0.01);
    cpl_progress_use_clock(&p, fake_now, &c);
    char line[512];
    cpl_progress_status(&p, line, sizeof line);
    assert_string_equal(line, "");   /* no step yet */

    cpl_progress_watch w = {.contacts = 0, .max_speed_m_s = 15.0, .kinetic_energy_j = 87500.0,
                            .deflection_m = 0.0};
    cpl_progress_set_watch(&p, &w);
    c.t_s = 10.0;
    cpl_step_record rec = {.step = 9, .time_s = 0.1, .dt_s = 0.01, .iterations = 1,
                           .converged = 1, .residual = 0.0};
    cpl_progress_step(&p, &rec, 1);
    cpl_progress_status(&p, line, sizeof line);
    assert_non_null(strstr(line, "t = 0.1 s (10.0%), 01:30 left |"));
    /* 0.9 s left at 0.01 s per s: 01:30 */
    assert_non_null(strstr(line, "no contact |"));
    assert_non_null(strstr(line, "rock 15 m/s, 87.5 kJ |"));
    assert_non_null(strstr(line, "deflection 0 m (max 0 m)"));

    /* in contact: the largest deflection of the run is kept */
    w = (cpl_progress_watch){.contacts = 3, .max_speed_m_s = 9.5, .kinetic_energy_j = 35000.0,
                             .deflection_m = 0.48};
    cpl_progress_set_watch(&p, &w);
    rec.step = 19;
    rec.time_s = 0.2;
    rec.in_contact = 1;
    c.t_s = 20.0;
    cpl_progress_step(&p, &rec, 1);
    cpl_progress_status(&p, line, sizeof line);
    assert_non_null(strstr(line, "| contact 3 | rock 9.5 m/s, 35 kJ | deflection 0.48 m (max 0.48 m) |"));
    w.deflection_m = 0.31;
    w.contacts = NAN;           /* a DEM that does not count contacts: the force says it */
    w.max_speed_m_s = NAN;      /* nor reports a speed */
    cpl_progress_set_watch(&p, &w);
    rec.step = 29;
    rec.time_s = 0.3;
    c.t_s = 30.0;
    cpl_progress_step(&p, &rec, 1);
    cpl_progress_status(&p, line, sizeof line);
    assert_non_null(strstr(line, "| contact |"));
    assert_non_null(strstr(line, "rock 35 kJ |"));
    assert_non_null(strstr(line, "deflection 0.31 m (max 0.48 m)"));
    assert_null(strstr(line, "m/s"));
    fclose(out);
}

/* progress over 1 s of simulation (dt 0.01 s, status every 10 s) into buf, on clock c */
static FILE *open_progress(cpl_progress *p, char *buf, size_t size, int tty, int quiet,
                           fake_clock *c)
{
    FILE *out = fmemopen(buf, size, "w");
    assert_non_null(out);
    cpl_progress_init(p, out, tty, quiet, 10.0, 0.0, 1.0, 0.01);
    cpl_progress_use_clock(p, fake_now, c);
    return out;
}

static void test_terminal_line_is_cut_to_the_width(void **state)
{
    (void)state;
    char buf[4096] = "";
    fake_clock c = {0.0};
    cpl_progress p;
    FILE *out = open_progress(&p, buf, sizeof buf, 1, 0, &c);
    p.width = 40;
    c.t_s = 1.0;
    cpl_step_record rec = {.step = 0, .time_s = 0.01, .dt_s = 0.01, .iterations = 2,
                           .converged = 1, .residual = 1e-9};
    cpl_progress_step(&p, &rec, 1);
    fflush(out);
    assert_int_equal(buf[0], '\r');
    const char *end = strstr(buf, "\033[K");
    assert_non_null(end);
    assert_int_equal(end - (buf + 1), 39);   /* width - 1 characters, no wrap */
    fclose(out);
}

static void test_dropped_particles_are_warned_about_once(void **state)
{
    (void)state;
    char buf[4096] = "";
    fake_clock c = {0.0};
    cpl_progress p;
    FILE *out = open_progress(&p, buf, sizeof buf, 0, 1, &c);   /* quiet: warnings only */
    const int dropped[4] = {0, 3, 0, 5};
    for (int i = 0; i < 4; i++) {
        cpl_step_record rec = {.step = i, .time_s = 0.01 * (i + 1), .dt_s = 0.01,
                               .iterations = 2, .converged = 1, .residual = 1e-9,
                               .jacobian_dropped = dropped[i]};
        cpl_progress_step(&p, &rec, 1);
    }
    fflush(out);
    const char *want = "step 1 (t = 0.02 s): the DEM left 3 particle(s) out of";
    const char *first = strstr(buf, want);
    assert_non_null(first);
    assert_null(strstr(first + strlen(want), "the DEM left"));
    assert_int_equal(p.jacobian_warnings, 2);
    fclose(out);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_remaining_time_follows_the_recent_rate),
        cmocka_unit_test(test_status_line_shows_contact_rock_and_deflection),
        cmocka_unit_test(test_terminal_line_is_cut_to_the_width),
        cmocka_unit_test(test_dropped_particles_are_warned_about_once),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
