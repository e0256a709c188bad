/* fem_element_brake — the brake's law, history and table of operations (see
 * fem_element_brake.h). The law is the elastic-perfectly-plastic (optionally linearly
 * hardening) spring with a stroke limit that barrier models use for their brake elements,
 * returned by the closed-form return mapping of a 1-D linear-hardening spring. */
#include "fem_element_brake.h"
#include "fem_element.h"
#include "fem_element_cable.h"
#include "fem_model.h"
#include "nc_json.h"
#include "nc_plausible.h"

#include <math.h>

double fem_brake_force(const double *p, double delta, double sp0, double *kt, double *sp)
{
    const double ke = p[FEM_BRAKE_KE], fa = p[FEM_BRAKE_FA], kh = p[FEM_BRAKE_KH];
    const double smax = p[FEM_BRAKE_SMAX], kl = p[FEM_BRAKE_KLOCK];
    double s = sp0;
    if (s < smax && ke * (delta - s) > fa + kh * s) {
        /* plastic: k_e (delta - s) = F_a + k_h s */
        double s_new = (ke * delta - fa) / (ke + kh);
        if (s_new <= smax) {
            *sp = s_new;
            *kt = ke * kh / (ke + kh);
            return fa + kh * s_new;
        }
        s = smax;   /* the stroke is used up within this elongation: locked beyond */
    }
    *sp = s;
    double e = delta - s;
    if (e < 0.0) {    /* shorter than its stroke has made it: slack, like the rope */
        *kt = 0.0;
        return 0.0;
    }
    if (s >= smax) {
        double fy = fa + kh * smax, ey = fy / ke;
        if (e > ey) {
            *kt = kl;
            return fy + kl * (e - ey);
        }
    }
    *kt = ke;
    return ke * e;
}

static double brake_delta(const fem_element_ctx *c, double d[3], double *l)
{
    fem_cable_chord(c, d);
    *l = sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
    return *l - c->m->L0[c->first];
}

static double brake_pair(const fem_element_ctx *c, double f_l[3], double Kb[9], int *slack)
{
    double d[3], l, kt, sp;
    double F = fem_brake_force(c->param, brake_delta(c, d, &l), c->hist[0], &kt, &sp);
    /* f_l = F d / l; Kb = d f_l / d d = (F / l) I + (k_t - F / l) d d^T / l^2 */
    double g = F / l, mat = (kt - g) / (l * l);
    for (int i = 0; i < 3; i++) {
        f_l[i] = g * d[i];
        for (int j = 0; j < 3; j++) Kb[3 * i + j] = mat * d[i] * d[j];
        Kb[4 * i] += g;
    }
    if (slack) *slack = F == 0.0 && kt == 0.0;
    return F;
}

static double brake_energy(const fem_element_ctx *c)
{
    const double *p = c->param;
    double d[3], l;
    double sp = c->hist[0], e = brake_delta(c, d, &l) - sp;
    if (e < 0.0) return 0.0;
    const double ke = p[FEM_BRAKE_KE];
    if (sp >= p[FEM_BRAKE_SMAX]) {
        double fy = p[FEM_BRAKE_FA] + p[FEM_BRAKE_KH] * sp, ey = fy / ke;
        if (e > ey) return 0.5 * fy * ey + fy * (e - ey) + 0.5 * p[FEM_BRAKE_KLOCK] * (e - ey) * (e - ey);
    }
    return 0.5 * ke * e * e;
}

static void brake_commit(const fem_element_ctx *c, double *hist_new)
{
    const double *p = c->param;
    double d[3], l, kt, sp, sp0 = c->hist[0];
    fem_brake_force(p, brake_delta(c, d, &l), sp0, &kt, &sp);
    hist_new[0] = sp;
    /* plastic work of the stroke increment, exact for the linear plateau F_y(s) */
    hist_new[1] = c->hist[1] + (p[FEM_BRAKE_FA] + 0.5 * p[FEM_BRAKE_KH] * (sp0 + sp)) * (sp - sp0);
}

static double brake_dissipated(const fem_element_ctx *c) { return c->hist[1]; }
static double brake_stroke(const fem_element_ctx *c) { return c->hist[0]; }

static const char *const brake_keys[] = {"elastic_stiffness_n_per_m", "activation_force_n",
                                         "hardening_stiffness_n_per_m", "max_stroke_m",
                                         "locking_stiffness_n_per_m", NULL};

static int brake_parse(const struct cJSON *o, const char *w, FILE *warnings, double *p,
                       nc_error *err)
{
    if (nc_json_positive(o, w, "elastic_stiffness_n_per_m", &p[FEM_BRAKE_KE], err) ||
        nc_json_positive(o, w, "activation_force_n", &p[FEM_BRAKE_FA], err) ||
        nc_json_number_range_opt(o, w, "hardening_stiffness_n_per_m", 0.0, 0.0, INFINITY,
                                 &p[FEM_BRAKE_KH], err) ||
        nc_json_positive(o, w, "max_stroke_m", &p[FEM_BRAKE_SMAX], err) ||
        nc_json_positive(o, w, "locking_stiffness_n_per_m", &p[FEM_BRAKE_KLOCK], err))
        return -1;
    if (p[FEM_BRAKE_KLOCK] < p[FEM_BRAKE_KE])
        nc_warn(warnings, "%s.locking_stiffness_n_per_m: %g N/m is below the elastic stiffness "
                          "%g N/m (a used-up brake is usually stiffer)",
                w, p[FEM_BRAKE_KLOCK], p[FEM_BRAKE_KE]);
    return 0;
}

const fem_element_ops fem_element_brake_ops = {
    .name = "brake",
    .history_count = 2,
    .keys = brake_keys,
    .parse = brake_parse,
    .pair_response = brake_pair,
    .strain_energy = brake_energy,
    .commit = brake_commit,
    .dissipated = brake_dissipated,
    .stroke = brake_stroke,
};
