/* dem_compliance — the coupled step with the structure's compliance (dem_compliance.h). */
#include "dem_compliance.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "dem_sim.h"

extern void dgesv_(const int *n, const int *nrhs, double *a, const int *lda, int *ipiv,
                   double *b, const int *ldb, int *info);

/* Work space of one solve (m = 3 |N|). */
typedef struct work {
    double *ue, *F, *Fbase, *dF, *g, *J, *KN;
    int *pos, *ipiv;
} work;

static void work_free(work *w)
{
    free(w->ue); free(w->F); free(w->Fbase); free(w->dF); free(w->g); free(w->J); free(w->KN);
    free(w->pos); free(w->ipiv);
}

static int work_alloc(work *w, size_t n, size_t m, nc_error *err)
{
    memset(w, 0, sizeof *w);
    w->ue = malloc(3 * n * sizeof *w->ue);
    w->F = malloc(m * sizeof *w->F);
    w->Fbase = malloc(m * sizeof *w->Fbase);
    w->dF = malloc(m * sizeof *w->dF);
    w->g = malloc(m * sizeof *w->g);
    w->J = malloc(m * m * sizeof *w->J);
    w->KN = malloc(m * m * sizeof *w->KN);
    w->pos = malloc(n * sizeof *w->pos);
    w->ipiv = malloc(m * sizeof *w->ipiv);
    if (w->ue && w->F && w->Fbase && w->dF && w->g && w->J && w->KN && w->pos && w->ipiv)
        return 0;
    work_free(w);
    return nc_error_set(err, 1, "dem: out of memory for the compliance of %zu nodes", m / 3);
}

/* u_e = u_in + S (F - F_ref) on N. */
static void wall_end(const dem_compliance *c, const double *disp, const double *F, size_t m,
                     double *ue)
{
    for (size_t a = 0; a < m; a++) {
        double sum = 0.0;
        for (size_t b = 0; b < m; b++)
            sum += c->S[a * m + b] * (F[b] - c->force_ref[3 * (size_t)c->nodes[b / 3] + b % 3]);
        ue[3 * (size_t)c->nodes[a / 3] + a % 3] = disp[3 * (size_t)c->nodes[a / 3] + a % 3] + sum;
    }
}

/* The Newton step dF = -(I + K_NN S)^-1 g; 0, or 1 when the system is singular. */
static int newton_step(const dem_compliance *c, const dem_net_jacobian *jac, work *w, size_t m)
{
    memset(w->KN, 0, m * m * sizeof *w->KN);
    for (size_t b = 0; b < jac->n_blocks; b++) {
        const int a = w->pos[jac->nodes[2 * b]], q = w->pos[jac->nodes[2 * b + 1]];
        if (a < 0 || q < 0) continue;   /* a node outside N stays where the coupler put it */
        for (int r = 0; r < 3; r++)
            for (int t = 0; t < 3; t++)
                w->KN[(3 * (size_t)a + r) * m + 3 * (size_t)q + t] += jac->K[9 * b + 3 * r + t];
    }
    for (size_t r = 0; r < m; r++)        /* column-major for LAPACK */
        for (size_t q = 0; q < m; q++) {
            double sum = r == q ? 1.0 : 0.0;
            for (size_t t = 0; t < m; t++) sum += w->KN[r * m + t] * c->S[t * m + q];
            w->J[q * m + r] = sum;
        }
    for (size_t r = 0; r < m; r++) w->dF[r] = -w->g[r];
    const int mi = (int)m, one = 1;
    int info = 0;
    dgesv_(&mi, &one, w->J, &mi, w->ipiv, w->dF, &mi, &info);
    return info != 0;
}

int dem_sim_solve_with_compliance(dem_sim *s, double dt_step, const double *disp_end,
                                  const double *vel_end, const dem_compliance *cmp,
                                  double *force_out, double *wall_end_disp,
                                  dem_coupled_info *info, dem_net_jacobian *jac,
                                  dem_compliance_stats *st, nc_error *err)
{
    const size_t n = s->model.net.n_nodes, m = 3 * cmp->n_nodes;
    memset(st, 0, sizeof *st);
    if (m == 0) {
        st->evaluations = 1;
        memcpy(wall_end_disp, disp_end, 3 * n * sizeof *wall_end_disp);
        return dem_sim_solve_coupled_jacobian(s, dt_step, disp_end, vel_end, force_out, info,
                                              jac, err);
    }
    work w;
    if (work_alloc(&w, n, m, err)) return -1;
    int rc = -1;
    for (size_t i = 0; i < n; i++) w.pos[i] = -1;
    for (size_t q = 0; q < cmp->n_nodes; q++) {
        if (cmp->nodes[q] < 0 || (size_t)cmp->nodes[q] >= n) {
            nc_error_set(err, 1, "compliance_nodes row %zu: %d is not an interface node (0..%zu)",
                         q, (int)cmp->nodes[q], n - 1);
            goto done;
        }
        if (w.pos[cmp->nodes[q]] >= 0) {
            nc_error_set(err, 1, "compliance_nodes row %zu: node %d is listed twice", q,
                         (int)cmp->nodes[q]);
            goto done;
        }
        w.pos[cmp->nodes[q]] = (int)q;
    }
    for (size_t a = 0; a < m * m; a++)
        if (!isfinite(cmp->S[a])) {
            nc_error_set(err, 1, "compliance: entry (%zu, %zu) is not finite", a / m, a % m);
            goto done;
        }
    for (size_t i = 0; i < 3 * n; i++)
        if (!isfinite(cmp->force_ref[i])) {
            nc_error_set(err, 1, "compliance_force: node %zu is not finite", i / 3);
            goto done;
        }
    memcpy(w.ue, disp_end, 3 * n * sizeof *w.ue);
    for (size_t a = 0; a < m; a++) w.F[a] = cmp->force_ref[3 * (size_t)cmp->nodes[a / 3] + a % 3];
    double g_base = INFINITY, lambda = 1.0;
    for (int e = 0;; e++) {
        if (e > 0 && dem_sim_restore(s, err)) goto done;
        if (dem_sim_solve_coupled_jacobian(s, dt_step, w.ue, vel_end, force_out, info, jac, err))
            goto done;
        st->evaluations = e + 1;
        double g2 = 0.0, f_max = 0.0;
        for (size_t a = 0; a < m; a++) {
            const double fd = force_out[3 * (size_t)cmp->nodes[a / 3] + a % 3];
            w.g[a] = w.F[a] - fd;
            g2 += w.g[a] * w.g[a];
            f_max = fmax(f_max, fabs(fd));
        }
        const double g = sqrt(g2);
        if (e == 0) st->first_mismatch_n = g;
        st->last_mismatch_n = g;
        if (g <= DEM_COMPLIANCE_TOLERANCE * fmax(f_max, 1e-3) ||
            e + 1 >= DEM_COMPLIANCE_MAX_EVALUATIONS)
            break;
        if (g > g_base && lambda > 0.1) {
            /* the step made the mismatch grow (a contact lost or gained on the way): back
             * along it */
            lambda *= 0.5;
        } else {
            g_base = g;
            lambda = 1.0;
            memcpy(w.Fbase, w.F, m * sizeof *w.F);
            if (newton_step(cmp, jac, &w, m)) break;
        }
        for (size_t a = 0; a < m; a++) w.F[a] = w.Fbase[a] + lambda * w.dF[a];
        wall_end(cmp, disp_end, w.F, m, w.ue);
    }
    memcpy(wall_end_disp, w.ue, 3 * n * sizeof *wall_end_disp);
    rc = 0;
done:
    work_free(&w);
    return rc;
}
