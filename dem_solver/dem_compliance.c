/* dem_compliance — the coupled step with the structure's compliance (dem_compliance.h). */
#include "dem_compliance.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "dem_sim.h"
#include "nc_lapack.h"

/* Work space of one solve (m = 3 |N|). */
typedef struct work {
    double *ue, *F, *Fbase, *Fbest, *dF, *g, *gbase, *J, *KN;
    int *pos, *ipiv;
    size_t *cols;   /* a row of K_NN's non-zero columns */
} work;

static void work_free(work *w)
{
    free(w->ue); free(w->F); free(w->Fbase); free(w->Fbest); free(w->dF); free(w->g);
    free(w->gbase); free(w->J); free(w->KN); free(w->pos); free(w->ipiv); free(w->cols);
}

static int work_alloc(work *w, size_t n, size_t m, nc_error *err)
{
    memset(w, 0, sizeof *w);
    w->ue = malloc(3 * n * sizeof *w->ue);
    w->F = malloc(m * sizeof *w->F);
    w->Fbase = malloc(m * sizeof *w->Fbase);
    w->Fbest = malloc(m * sizeof *w->Fbest);
    w->dF = malloc(m * sizeof *w->dF);
    w->g = malloc(m * sizeof *w->g);
    w->gbase = malloc(m * sizeof *w->gbase);
    w->J = malloc(m * m * sizeof *w->J);
    w->KN = malloc(m * m * sizeof *w->KN);
    w->pos = malloc(n * sizeof *w->pos);
    w->ipiv = malloc(m * sizeof *w->ipiv);
    w->cols = malloc(m * sizeof *w->cols);
    if (w->ue && w->F && w->Fbase && w->Fbest && w->dF && w->g && w->gbase && w->J && w->KN &&
        w->pos && w->ipiv && w->cols)
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

/* J = I + K_NN S of the last evaluation's K, column-major for LAPACK. K_NN has a few blocks
 * per row (the contact nodes'; with compliance_proximity most of N is out of contact): the
 * product runs over each row's non-zero columns only, in the order of the dense product,
 * which it matches bit for bit (m = 102: 1e6 multiplications an evaluation before). */
static void build_jacobian(const dem_compliance *c, const dem_net_jacobian *jac, work *w,
                           size_t m)
{
    memset(w->KN, 0, m * m * sizeof *w->KN);
    for (size_t b = 0; b < jac->n_blocks; b++) {
        const int a = w->pos[jac->nodes[2 * b]], q = w->pos[jac->nodes[2 * b + 1]];
        if (a < 0 || q < 0) continue;   /* a node outside N stays where the coupler put it */
        for (int r = 0; r < 3; r++)
            for (int t = 0; t < 3; t++)
                w->KN[(3 * (size_t)a + r) * m + 3 * (size_t)q + t] += jac->K[9 * b + 3 * r + t];
    }
    for (size_t r = 0; r < m; r++) {
        size_t n_cols = 0;
        for (size_t t = 0; t < m; t++)
            if (w->KN[r * m + t] != 0.0) w->cols[n_cols++] = t;
        for (size_t q = 0; q < m; q++) {
            double sum = r == q ? 1.0 : 0.0;
            for (size_t k = 0; k < n_cols; k++)
                sum += w->KN[r * m + w->cols[k]] * c->S[w->cols[k] * m + q];
            w->J[q * m + r] = sum;
        }
    }
}

/* The Newton direction dF = -J^-1 g (J is overwritten); 0, or 1 when J is singular. */
static int newton_direction(work *w, size_t m)
{
    for (size_t r = 0; r < m; r++) w->dF[r] = -w->g[r];
    const int mi = (int)m, one = 1;
    int info = 0;
    dgesv_(&mi, &one, w->J, &mi, w->ipiv, w->dF, &mi, &info);
    return info != 0;
}

/* Along the Newton direction d from the base F_b: the share of the base's mismatch g_b left,
 * sigma = g . g_b / |g_b|^2 (1 at the base, 0 where the mismatch along g_b is gone), and its
 * derivative in the step length, (J d) . g_b / |g_b|^2, from the evaluation's own J. */
static void share_left(const work *w, size_t m, double *sigma, double *slope)
{
    double gg = 0.0, gb2 = 0.0, jd = 0.0;
    for (size_t r = 0; r < m; r++) {
        double Jd = 0.0;
        for (size_t q = 0; q < m; q++) Jd += w->J[q * m + r] * w->dF[q];
        gg += w->g[r] * w->gbase[r];
        gb2 += w->gbase[r] * w->gbase[r];
        jd += Jd * w->gbase[r];
    }
    *sigma = gg / gb2;
    *slope = jd / gb2;
}

/* One evaluation: the coupled step from the restored start with the wall ending at
 * u_e(F); w->g = F - F_dem on N; returns |g|, or -1 on a failure (err). *solved: |g| is
 * within DEM_COMPLIANCE_TOLERANCE. */
static double evaluate(dem_sim *s, double dt_step, const double *disp_end, const double *vel_end,
                       const dem_compliance *c, work *w, size_t m, int restore, double *force_out,
                       dem_coupled_info *info, dem_net_jacobian *jac, int *solved,
                       nc_error *err)
{
    wall_end(c, disp_end, w->F, m, w->ue);
    if ((restore && dem_sim_restore(s, err)) ||
        dem_sim_solve_coupled_jacobian(s, dt_step, w->ue, vel_end, force_out, info, jac, err))
        return -1.0;
    double g2 = 0.0, f_max = 0.0;
    for (size_t a = 0; a < m; a++) {
        const double fd = force_out[3 * (size_t)c->nodes[a / 3] + a % 3];
        w->g[a] = w->F[a] - fd;
        g2 += w->g[a] * w->g[a];
        f_max = fmax(f_max, fabs(fd));
    }
    const double g = sqrt(g2);
    *solved = g <= DEM_COMPLIANCE_TOLERANCE * fmax(f_max, 1e-3);
    return g;
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
    memcpy(w.ue, disp_end, 3 * n * sizeof *w.ue);   /* nodes outside N stay there */
    for (size_t a = 0; a < m; a++) w.F[a] = cmp->force_ref[3 * (size_t)cmp->nodes[a / 3] + a % 3];
    /* Newton from a base evaluation, a step that does not lower the mismatch searched along
     * its direction d. Where it went past the root along d (sigma <= 0: typically a contact
     * gained, which the base's K, zero without contact, did not know, so that the full step
     * lands millimetres deep), the root is bracketed and found by Newton on the step length
     * with each evaluation's own J, bisecting where that leaves the bracket, stalls or does
     * not halve sigma; a point leaving at most DEM_COMPLIANCE_SHARE_LEFT of the base's
     * mismatch along d, and less mismatch, is the next base (or more mismatch, at most
     * DEM_COMPLIANCE_UPHILL_BASES times: the line from a base whose K lacked a contact the
     * search then met, a node coming into touch, has no root; the point where its mismatch
     * along d is gone has that contact and its K). Where the mismatch grew without
     * passing the root, the step is halved. Halving alone, without the bracket, went back to
     * contact-free points whose K is zero again, whose Newton step returned to the deep one:
     * a cycle until the last evaluation (docs/notes/interface_jacobian.md "The structure's
     * compliance in the DEM", item 6). The best evaluation is the one returned. */
    double g_base = INFINITY, g_best = INFINITY, g = INFINITY;
    double lambda = 0.0, lambda_lo = 0.0, lambda_hi = NAN, step_before = NAN, sigma_before = NAN;
    int solved = 0, uphill = 0;
    for (int e = 0;; e++) {
        g = evaluate(s, dt_step, disp_end, vel_end, cmp, &w, m, e > 0, force_out, info, jac,
                     &solved, err);
        if (g < 0.0) goto done;
        st->evaluations = e + 1;
        if (e == 0) st->first_mismatch_n = g;
        if (g < g_best) {
            g_best = g;
            memcpy(w.Fbest, w.F, m * sizeof *w.F);
        }
        if (solved || e + 2 >= DEM_COMPLIANCE_MAX_EVALUATIONS)   /* one left for the best */
            break;
        build_jacobian(cmp, jac, &w, m);
        int new_base = g_base == INFINITY;
        if (!new_base) {
            double sigma, slope;
            share_left(&w, m, &sigma, &slope);
            if (isnan(lambda_hi) && sigma > 0.0) {
                /* not past the root along d: Newton's step where the mismatch fell, else halved
                 * (a point after four halvings is taken all the same) */
                new_base = g <= g_base || lambda < DEM_COMPLIANCE_SMALLEST_STEP;
                if (!new_base) lambda *= 0.5;
            } else {
                if (sigma <= 0.0) lambda_hi = lambda;
                else lambda_lo = lambda;
                /* a larger mismatch than the base's is taken too, a few times: there d has
                 * crossed its root, and what is left lies across d (a contact the base's K
                 * did not have), which that point's own K knows */
                new_base = fabs(sigma) <= DEM_COMPLIANCE_SHARE_LEFT &&
                           (g < g_base || uphill < DEM_COMPLIANCE_UPHILL_BASES);
                if (new_base && !(g < g_base)) uphill++;
                if (!new_base) {
                    /* a bracket narrower than rounding: the mismatch jumps across the root
                     * along d, nothing left to find on it */
                    if (lambda_hi - lambda_lo <= 1e-12) break;
                    double next = slope < 0.0 ? lambda - sigma / slope : NAN;
                    if (!(next > lambda_lo && next < lambda_hi) ||
                        (!isnan(step_before) && fabs(next - lambda) > 0.5 * step_before) ||
                        fabs(sigma) > 0.5 * fabs(sigma_before))
                        next = 0.5 * (lambda_lo + lambda_hi);
                    step_before = fabs(next - lambda);
                    sigma_before = sigma;
                    lambda = next;
                }
            }
        }
        if (new_base) {
            g_base = g;
            memcpy(w.Fbase, w.F, m * sizeof *w.F);
            memcpy(w.gbase, w.g, m * sizeof *w.g);
            if (newton_direction(&w, m)) break;
            lambda = 1.0;
            lambda_lo = 0.0;
            lambda_hi = step_before = sigma_before = NAN;
        }
        for (size_t a = 0; a < m; a++) w.F[a] = w.Fbase[a] + lambda * w.dF[a];
    }
    if (g > g_best) {
        /* the search ended on a worse evaluation than its best: back to that one */
        memcpy(w.F, w.Fbest, m * sizeof *w.F);
        g = evaluate(s, dt_step, disp_end, vel_end, cmp, &w, m, 1, force_out, info, jac, &solved,
                     err);
        if (g < 0.0) goto done;
        st->evaluations++;
    }
    st->last_mismatch_n = g;
    memcpy(wall_end_disp, w.ue, 3 * n * sizeof *wall_end_disp);
    rc = 0;
done:
    work_free(&w);
    return rc;
}
