/* test_element_brake — the brake element (fem_element_brake.h) against its closed-form law:
 * the law itself (elastic, plateau with and without hardening, locking, slack, elastic
 * unloading), the consistent tangent against finite differences, a rope with a brake under a
 * prescribed elongation history (static steps: the force follows the law, the dissipated
 * energy equals F_a s_p + k_h s_p^2 / 2, unloading and reloading go along the elastic slope,
 * Newton needs few iterations through the kinks), and a dynamic run (a rope flying off,
 * caught by the brake) whose energy balance closes with the brake's plastic work reported
 * as dissipation. Realistic values: a 16 mm steel rope (E 1e11 Pa, A 1.26e-4 m^2), a ring
 * brake activating at 50 kN with a stroke of 1 m. */
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <setjmp.h>
#include <cmocka.h>
#include "../nc_test_assert.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "../../fem_solver/fem_analysis.h"
#include "../../fem_solver/fem_element_brake.h"

#define KE 2e6      /* N/m */
#define FA 5e4      /* N */
#define SMAX 1.0    /* m */
#define KLOCK 2e7   /* N/m */

static void brake_param(double *p, double kh)
{
    memset(p, 0, FEM_ELEMENT_PARAMS * sizeof *p);
    p[FEM_BRAKE_KE] = KE;
    p[FEM_BRAKE_FA] = FA;
    p[FEM_BRAKE_KH] = kh;
    p[FEM_BRAKE_SMAX] = SMAX;
    p[FEM_BRAKE_KLOCK] = KLOCK;
}

/* The law along an elongation history, checked against the closed forms of each phase. */
static void test_law(void **state)
{
    (void)state;
    for (int hard = 0; hard < 2; hard++) {
        double p[FEM_ELEMENT_PARAMS], kh = hard ? 2e4 : 0.0, kt, sp;
        brake_param(p, kh);
        /* elastic below activation */
        assert_near_rel(fem_brake_force(p, 0.01, 0.0, &kt, &sp), KE * 0.01, 1e-15);
        assert_near(sp, 0.0, 0.0);
        assert_near(kt, KE, 0.0);
        /* plateau: k_e (delta - s) = F_a + k_h s */
        double d = 0.4, s_exp = (KE * d - FA) / (KE + kh);
        double F = fem_brake_force(p, d, 0.0, &kt, &sp);
        assert_near_rel(sp, s_exp, 1e-14);
        assert_near_rel(F, FA + kh * s_exp, 1e-14);
        assert_near_rel(F, KE * (d - sp), 1e-9);
        assert_near(kt, KE * kh / (KE + kh), 1e-9);
        /* unloading from the committed stroke: elastic, stroke kept */
        double F2 = fem_brake_force(p, d - 0.01, sp, &kt, &sp);
        assert_near_rel(F2, F - KE * 0.01, 1e-9);
        assert_near(kt, KE, 0.0);
        assert_near_rel(sp, s_exp, 1e-14);
        /* shorter than its stroke: slack, no compression */
        assert_near(fem_brake_force(p, 0.5 * s_exp, s_exp, &kt, &sp), 0.0, 0.0);
        assert_near(kt, 0.0, 0.0);
        /* beyond the stroke: locked, F = F_y,max + k_lock (e - F_y,max / k_e) */
        double fy = FA + kh * SMAX, ey = fy / KE, dl = SMAX + ey + 0.002;
        F = fem_brake_force(p, dl, s_exp, &kt, &sp);
        assert_near_rel(sp, SMAX, 1e-15);
        assert_near_rel(F, fy + KLOCK * 0.002, 1e-9);
        assert_near(kt, KLOCK, 0.0);
        /* continuous at the lock: just below, on the plateau end */
        F = fem_brake_force(p, SMAX + ey - 1e-9, 0.0, &kt, &sp);
        assert_near_rel(F, fy, 1e-6);
        /* unloading a locked brake is elastic, first along k_lock, then k_e */
        F = fem_brake_force(p, SMAX + 0.5 * ey, SMAX, &kt, &sp);
        assert_near_rel(F, KE * 0.5 * ey, 1e-9);
    }
}

/* Model: anchor (node 0) - brake - node 1 - rope of 5 m in 5 elements - node 6, all on the
 * x axis; y and z of every node held (a straight rope, 1-D). */
static void rope_with_brake(fem_model *m, double kh, double rho)
{
    nc_error err;
    fem_model_init(m, "test-brake");
    assert_int_equal(fem_model_alloc(m, 7, 6, &err), 0);
    m->X[3] = 0.5;                             /* brake: 0.5 m long */
    for (int i = 2; i < 7; i++) m->X[3 * i] = 0.5 + (i - 1);
    for (int e = 0; e < 6; e++) {
        m->conn[2 * e] = e;
        m->conn[2 * e + 1] = e + 1;
    }
    fem_element_set rope, brake;
    memset(&rope, 0, sizeof rope);
    snprintf(rope.name, sizeof rope.name, "rope");
    rope.youngs_modulus_pa = 1e11;
    rope.area_m2 = 1.26e-4;
    rope.density_kg_m3 = rho;
    rope.behaviour = FEM_CABLE;
    brake = rope;
    snprintf(brake.name, sizeof brake.name, "brake");
    brake.density_kg_m3 = 0.0;
    assert_int_equal(fem_model_add_set(m, &rope, &err), 0);
    assert_int_equal(fem_model_add_set(m, &brake, &err), 1);
    m->set_types[1].type = fem_element_find("brake");
    brake_param(m->set_types[1].param, kh);
    m->element_set[0] = 1;
    for (int c = 0; c < 3; c++) m->fixed[c] = 1;
    for (int i = 1; i < 7; i++) m->fixed[3 * i + 1] = m->fixed[3 * i + 2] = 1;
    m->gravity[2] = 0.0;
    m->settings.type = FEM_STATIC;
    m->settings.modified_newton = 0;
    m->settings.residual_tol_n = 1e-6;
    m->settings.relative_tol = 1e-13;
    m->settings.displacement_tol_m = 1e-12;
    m->settings.max_iterations = 30;
}

/* Tangent of the brake member against central differences of its force, on every phase. */
static void test_tangent(void **state)
{
    (void)state;
    fem_model m;
    rope_with_brake(&m, 2e4, 7850);
    nc_error err;
    assert_int_equal(fem_model_finalize(&m, &err), 0);
    const fem_element_ops *ops = fem_element_type(m.set_types[1].type);
    const double lengths[3] = {0.01, 0.3, 1.2};   /* elastic, plastic, locked */
    for (int t = 0; t < 3; t++) {
        double u[21] = {0}, hist[2] = {0, 0};
        u[3] = lengths[t] + 0.02;
        u[4] = 0.05;     /* oblique, so the geometric part counts */
        u[5] = -0.03;
        fem_element_ctx c = {&m, &m.sets[1], m.set_types[1].param, 0, 0, 1, u, hist, 0};
        double f[3], Kb[9], fp[3], fm[3], K2[9];
        int slack;
        ops->pair_response(&c, f, Kb, &slack);
        for (int j = 0; j < 3; j++) {
            double h = 1e-7;
            u[3 + j] += h;
            ops->pair_response(&c, fp, K2, &slack);
            u[3 + j] -= 2 * h;
            ops->pair_response(&c, fm, K2, &slack);
            u[3 + j] += h;
            for (int i = 0; i < 3; i++)
                assert_near(Kb[3 * i + j], (fp[i] - fm[i]) / (2 * h), 1e-6 * fabs(Kb[0]) + 1e-3);
        }
    }
    fem_model_free(&m);
}

/* Prescribed elongation history at the rope's end: up through activation along the plateau,
 * down (elastic unloading), up again (elastic reloading, then the plateau again), into the
 * lock. At each solution: the brake force equals the rope force (statics), the law holds
 * against the measured elongation, the dissipated energy is F_a s_p + k_h s_p^2 / 2 to 1e-9,
 * and Newton takes few iterations (quadratic through the kinks). */
static void run_history(double kh)
{
    fem_model m;
    rope_with_brake(&m, kh, 0.0);
    m.fixed[3 * 6] = 1;
    m.u_prescribed[3 * 6] = 1.0;   /* lambda = the end's displacement (m) */
    nc_error err;
    assert_int_equal(fem_model_finalize(&m, &err), 0);
    fem_analysis s;
    assert_int_equal(fem_analysis_init(&s, &m, &err), 0);
    const double k_rope = 1e11 * 1.26e-4 / 5.0;
    double path[200];
    int n = 0;
    for (double U = 0.01; U <= 0.60001; U += 0.03) path[n++] = U;       /* load */
    /* unload by 30 mm: the series compliance 1/k_e + 1/k_rope takes 33 kN off, no slack */
    for (double U = 0.575; U >= 0.54999; U -= 0.005) path[n++] = U;
    for (double U = 0.56; U <= 1.20001; U += 0.02) path[n++] = U;       /* reload, plateau */
    for (double U = 1.21; U <= 1.10001 + SMAX * 0.2; U += 0.01) path[n++] = U;  /* lock */
    double sp_prev = 0.0, F_prev = 0.0, delta_prev = 0.0;
    int plastic_steps = 0, unload_steps = 0, locked = 0, max_it = 0;
    for (int k = 0; k < n; k++) {
        if (fem_analysis_static(&s, path[k], &err)) fail_msg("U = %g: %s", path[k], err.message);
        max_it = s.stats.iterations > max_it ? s.stats.iterations : max_it;
        double F = s.axial[0], delta = s.cur.u[3], sp, dis;
        fem_analysis_element_history_output(&s, NULL, NULL);
        double st[6], di[6];
        fem_analysis_element_history_output(&s, st, di);
        sp = st[0];
        dis = di[0];
        /* statics: one force along the line; the rope's engineering elongation gives it */
        assert_near_rel(s.axial[1], F, 1e-9);
        /* Green strain: N = EA (eps + eps^2 / 2)(1 + eps), eps = the rope's engineering strain */
        double eps = (s.cur.u[18] - s.cur.u[3]) / 5.0;
        assert_near_rel(F, 5.0 * k_rope * (eps + 0.5 * eps * eps) * (1.0 + eps), 1e-9);
        /* the law against the measured elongation */
        double fy = FA + kh * sp;
        if (sp > sp_prev + 1e-12 && sp < SMAX) {   /* flowing: on the plateau */
            assert_near_rel(F, fy, 1e-9);
            plastic_steps++;
        } else if (sp >= SMAX) {
            if (delta - SMAX > (FA + kh * SMAX) / KE) {
                assert_near_rel(F, FA + kh * SMAX + KLOCK * (delta - SMAX - (FA + kh * SMAX) / KE), 1e-8);
                locked++;
            }
        } else {
            assert_near_rel(F, KE * (delta - sp), 1e-9);   /* elastic */
            assert_true(F <= fy * (1 + 1e-12));
            if (delta < delta_prev) {
                assert_near_rel((F - F_prev) / (delta - delta_prev), KE, 1e-6);
                unload_steps++;
            }
        }
        assert_true(sp >= sp_prev - 1e-15);         /* the stroke never goes back */
        assert_near_rel(dis, FA * sp + 0.5 * kh * sp * sp, 1e-9);
        sp_prev = sp;
        F_prev = F;
        delta_prev = delta;
    }
    print_message("k_h %g: %d steps (%d plastic, %d unloading, %d locked), stroke %.4f m, "
                  "dissipated %.4e J, at most %d Newton iterations\n", kh, n, plastic_steps,
                  unload_steps, locked, sp_prev, FA * sp_prev + 0.5 * kh * sp_prev * sp_prev, max_it);
    assert_true(plastic_steps >= 10);
    assert_true(unload_steps >= 5);
    assert_true(locked >= 3);
    assert_near(sp_prev, SMAX, 0.0);
    assert_true(max_it <= 8);
    fem_analysis_free(&s);
    fem_model_free(&m);
}

static void test_history_perfectly_plastic(void **state)
{
    (void)state;
    run_history(0.0);
}

static void test_history_hardening(void **state)
{
    (void)state;
    run_history(2e4);
}

/* A rejected step leaves the history as it was; save/restore brings it back. */
static void test_history_rollback(void **state)
{
    (void)state;
    fem_model m;
    rope_with_brake(&m, 0.0, 0.0);
    m.fixed[3 * 6] = 1;
    m.u_prescribed[3 * 6] = 1.0;
    nc_error err;
    assert_int_equal(fem_model_finalize(&m, &err), 0);
    fem_analysis s;
    assert_int_equal(fem_analysis_init(&s, &m, &err), 0);
    assert_int_equal(m.history_count, 2);
    assert_int_equal(fem_analysis_static(&s, 0.3, &err), 0);
    double sp0 = s.cur.element_history[0];
    assert_true(sp0 > 0.2);
    assert_int_equal(fem_analysis_save(&s, &err), 0);
    assert_int_equal(fem_analysis_static(&s, 0.6, &err), 0);
    assert_true(s.cur.element_history[0] > sp0 + 0.2);
    assert_int_equal(fem_analysis_restore(&s, &err), 0);
    assert_near(s.cur.element_history[0], sp0, 0.0);
    assert_near_rel(s.axial[0], FA, 1e-9);
    fem_analysis_free(&s);
    fem_model_free(&m);
}

/* Dynamics: the rope (7850 kg/m^3, 5 m, about 5 kg) moves away from the anchor at 20 m/s
 * (989 J); the brake (F_a 5 kN, k_h 2e4 N/m) stops it, dissipating nearly all of that.
 * Newmark (1/4, 1/2) over 60 ms with step dt: returns the accumulated numerical term and
 * checks that kinetic + strain + the brake's dissipation + the numerical terms add up to the
 * input (the bookkeeping, to 1e-12) and that the brake's reported dissipation is its plastic
 * work F_a s_p + k_h s_p^2 / 2. */
static double run_dynamic(double dt, double *E0_out)
{
    fem_model m;
    rope_with_brake(&m, 2e4, 7850);
    m.settings.type = FEM_DYNAMIC;
    m.settings.residual_tol_n = 1e-4;
    m.settings.relative_tol = 1e-12;
    m.settings.displacement_tol_m = 1e-12;
    nc_error err;
    m.set_types[1].param[FEM_BRAKE_FA] = 5e3;
    assert_int_equal(fem_model_finalize(&m, &err), 0);
    fem_analysis s;
    assert_int_equal(fem_analysis_init(&s, &m, &err), 0);
    for (int i = 1; i < 7; i++) s.cur.v[3 * i] = 20.0;
    assert_int_equal(fem_analysis_initial_acceleration(&s, &err), 0);
    double E0 = fem_analysis_energy(&s, NULL, NULL), numerical = 0, dissipation = 0, worst = 0;
    for (int k = 0; k < (int)(0.06 / dt + 0.5); k++) {
        if (fem_analysis_step(&s, dt, &err)) fail_msg("step %d: %s", k, err.message);
        fem_step_energy e;
        assert_int_equal(fem_analysis_step_energy(&s, 1, &e), 0);
        numerical += e.numerical_j;
        dissipation += e.element_dissipation_j;
        assert_true(e.element_dissipation_j >= 0.0);
        assert_near_rel(e.element_dissipated_j, dissipation, 1e-9);
        double T, W;
        fem_analysis_energy(&s, &T, &W);
        worst = fmax(worst, fabs(T + W + dissipation + numerical - E0));
    }
    double sp = s.cur.element_history[0];
    print_message("dt %.2e s: input %.4f J, dissipated %.4f J (stroke %.4f m), kinetic + strain "
                  "%.4f J, numerical %.3e J, bookkeeping %.3e J\n", dt, E0, dissipation, sp,
                  fem_analysis_energy(&s, NULL, NULL), numerical, worst);
    assert_near_rel(E0, 0.5 * 7850 * 1.26e-4 * 5.0 * 400.0, 1e-12);
    assert_true(dissipation > 0.9 * E0);                 /* the brake did the work */
    assert_near_rel(dissipation, 5e3 * sp + 0.5 * 2e4 * sp * sp, 1e-9);
    assert_below(worst, 1e-12 * E0);
    fem_analysis_free(&s);
    fem_model_free(&m);
    *E0_out = E0;
    return numerical;
}

/* The energy balance closes: the numerical term (the trapezoidal rule's error at the law's
 * kinks, the rope going slack and taut, and the Green strain's nonlinearity) converges at
 * second order (observed 7.7e-6 of the input at dt = 1e-5 s, 2.8e-7 at 2.5e-6 s: 1/27 for a
 * quarter of the step; asserted below 1/10) and is below 1e-6 of the input energy at
 * dt = 2.5e-6 s (the tolerance of test_energy.c). */
static void test_dynamic_energy(void **state)
{
    (void)state;
    double E0;
    double coarse = run_dynamic(1e-5, &E0), fine = run_dynamic(2.5e-6, &E0);
    assert_below(fabs(fine), 0.1 * fabs(coarse));
    assert_below(fabs(fine), 1e-6 * E0);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_law),
        cmocka_unit_test(test_tangent),
        cmocka_unit_test(test_history_perfectly_plastic),
        cmocka_unit_test(test_history_hardening),
        cmocka_unit_test(test_history_rollback),
        cmocka_unit_test(test_dynamic_energy),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
