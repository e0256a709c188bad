/* fem_analysis — assembly, Newton-Raphson, static load steps and implicit time stepping
 * of the cable net (see fem_analysis.h).
 *
 * One residual/tangent form serves every analysis. With the generalized-alpha weights
 * (alpha_m, alpha_f; Newmark: 0, 0; Bossak: alpha_f = 0) the step equation is
 *   r = F_ext - M (a_am + tau v_af) - (1 - alpha_f) [F_int(u) + C_K v] - alpha_f fd_n
 * with a_am = (1-alpha_m) a_{n+1} + alpha_m a_n, v_af likewise, and the Newmark relations
 * for a_{n+1}, v_{n+1} as functions of u_{n+1}. Its tangent is c_m M + c_k K_T + c_c C_K with
 *   c_m = (1-alpha_m)/(beta dt^2) + tau (1-alpha_f) gamma/(beta dt),
 *   c_k = 1 - alpha_f,   c_c = (1-alpha_f) gamma/(beta dt).
 * The statics is the same with no inertia (c_m = 0, c_k = 1, c_c = 0). The stiffness-
 * proportional damping C_K = kappa K_T(u_n) takes the tangent (eq. (12)) at the start of
 * the step and keeps it over the step (freeze_damping): K_T(u) changes with every slack or
 * taut element, and a C_K(u) would need its derivative in the Newton matrix, without which
 * Newton stalls on a net's slack ropes. With C_K fixed the tangent is exact. The damping stays
 * implicit: a_n keeps the previous step's damping force (shifting a_n to the new C_K, as a
 * step-constant coupling load is, makes the change of C_K explicit, which is unstable for
 * kappa K / M dt >~ 1 on light nodes). F_ext is taken
 * at the end of the step for every method (model loads at the ramp value of t_{n+1};
 * coupling forces are constant over the step anyway). An interface linearisation adds
 * dF = -K (u - u^k) - C (v - v^k) to the coupling force with the weight l_w the step gives
 * the coupling force: l_w = 1 at the end-of-step point; with a step-constant coupling load
 * the force also shifts a_n (by M^-1 F), which the Newmark relations carry into a_n+1 and
 * v_n+1, so a force change moves the step l_w = 1 + (1 - alpha_m) c2 - alpha_m
 * - tau (1 - alpha_f) dt ((1 - gamma) - gamma c2) times as much, c2 = 1/(2 beta) - 1
 * (Newmark: 2). Its tangent is l_k K + l_c C with l_k = l_w, l_c = l_w gamma/(beta dt)
 * (statics: 1, 0). With l_w = 1 there the FEM's answer to a linear force law would not be
 * the coupled solution, and the interface iteration converges linearly at about 1 - 1/l_w
 * (docs/notes/interface_jacobian.md). The shift's effect through C_K = kappa K_T and through
 * the C term's velocity would need M^-1 and is left out: exact for kappa = 0 and C = 0, which
 * is what the DEM sends.
 */
#include "fem_analysis.h"
#include "fem_element.h"
#include "fem_element_cable.h"
#include "nc_clock.h"
#include "nc_lapack.h"

#include <float.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static const char *dof_name(int d)
{
    return d == 0 ? "x" : d == 1 ? "y" : "z";
}

static int state_alloc(fem_state *st, int ndof, int n_history)
{
    memset(st, 0, sizeof *st);
    st->n_history = n_history;
    st->element_history = calloc((size_t)(n_history > 0 ? n_history : 1), sizeof(double));
    st->u = calloc((size_t)ndof, sizeof(double));
    st->v = calloc((size_t)ndof, sizeof(double));
    st->a = calloc((size_t)ndof, sizeof(double));
    st->fd = calloc((size_t)ndof, sizeof(double));
    st->fc = calloc((size_t)ndof, sizeof(double));
    return (st->u && st->v && st->a && st->fd && st->fc && st->element_history) ? 0 : -1;
}

static void state_free(fem_state *st)
{
    free(st->u); free(st->v); free(st->a); free(st->fd); free(st->fc); free(st->element_history);
    memset(st, 0, sizeof *st);
}

static void state_copy(fem_state *dst, const fem_state *src, int ndof)
{
    size_t bytes = (size_t)ndof * sizeof(double);
    dst->time_s = src->time_s;
    dst->step = src->step;
    memcpy(dst->u, src->u, bytes);
    memcpy(dst->v, src->v, bytes);
    memcpy(dst->a, src->a, bytes);
    memcpy(dst->fd, src->fd, bytes);
    memcpy(dst->fc, src->fc, bytes);
    if (src->n_history > 0)
        memcpy(dst->element_history, src->element_history, (size_t)src->n_history * sizeof(double));
}

static const fem_element_ops *element_ops(const fem_model *m, int e)
{
    return fem_element_type(m->set_types[m->element_set[e]].type);
}

/* The view of member b at displacement u with the committed history hist (whole array). */
static void member_ctx(const fem_model *m, int b, const double *u, const double *hist,
                       fem_element_ctx *c)
{
    c->m = m;
    c->member = b;
    c->first = m->member_first[b];
    c->count = m->member_first[b + 1] - c->first;
    c->set = &m->sets[m->element_set[c->first]];
    c->param = m->set_types[m->element_set[c->first]].param;
    c->u = u;
    c->hist = hist ? hist + m->history_offset[b] : NULL;
    c->near_blocks_only = 0;
}

/* model node of position j of a member's chain */
static int chain_node(const fem_model *m, int first, int count, int j)
{
    return j < count ? m->conn[2 * (first + j)] : m->conn[2 * (first + count - 1) + 1];
}

/* The frozen damping matrix C_K: per member kappa K_T, 3x3 for a pair element (the block of
 * its second node's force over the relative velocity), 3n x 3n for a chain of n nodes. */
static int damping_alloc(fem_analysis *s)
{
    const fem_model *m = s->m;
    s->damping_at = malloc(((size_t)m->n_members + 1) * sizeof *s->damping_at);
    if (!s->damping_at) return -1;
    size_t at = 0;
    for (int b = 0; b < m->n_members; b++) {
        const int first = m->member_first[b];
        const size_t dim = 3 * (size_t)(m->member_first[b + 1] - first + 1);
        s->damping_at[b] = at;
        at += element_ops(m, first)->chain ? dim * dim : 9;
    }
    s->damping_at[m->n_members] = at;
    s->damping_K = calloc(at, sizeof(double));
    s->damping_start = calloc(3 * (size_t)m->n_nodes, sizeof(double));
    s->damping_end = calloc(3 * (size_t)m->n_nodes, sizeof(double));
    return s->damping_K && s->damping_start && s->damping_end ? 0 : -1;
}

/* Member b's damping force C_K v: a pair element's force on its second node (the first takes
 * minus it) in out[0..2], a chain member's on each of its n nodes in out[0..3n-1]. */
static void member_damping_force(const fem_analysis *s, int b, const double *v, double *out)
{
    const fem_model *m = s->m;
    const int first = m->member_first[b], count = m->member_first[b + 1] - first;
    const double *C = s->damping_K + s->damping_at[b];
    if (!element_ops(m, first)->chain) {
        const int k = 3 * m->conn[2 * first], l = 3 * m->conn[2 * first + 1];
        for (int i = 0; i < 3; i++) {
            out[i] = 0.0;
            for (int j = 0; j < 3; j++) out[i] += C[3 * i + j] * (v[l + j] - v[k + j]);
        }
        return;
    }
    const int dim = 3 * (count + 1), r = s->lr_of_member ? s->lr_of_member[b] : -1;
    if (r >= 0) {
        /* nodes that are not neighbours are coupled only by the frozen rank-one term
         * c g g^T: the neighbours' blocks less that term, plus the term, in O(n) */
        const double c = s->lr_c_frozen[r], *g = s->lr_gc + s->lr_at[r];
        double gv = 0.0;
        for (int q = 0; q <= count; q++) {
            const int node = 3 * chain_node(m, first, count, q);
            for (int d = 0; d < 3; d++) gv += g[3 * q + d] * v[node + d];
        }
        for (int a = 0; a < dim; a++) {
            const int i = a / 3;
            double cv = c * gv * g[a];
            for (int q = i > 0 ? i - 1 : 0; q <= i + 1 && q <= count; q++) {
                const int node = 3 * chain_node(m, first, count, q);
                for (int d = 0; d < 3; d++)
                    cv += (C[a * dim + 3 * q + d] - c * g[a] * g[3 * q + d]) * v[node + d];
            }
            out[a] = cv;
        }
        return;
    }
    for (int a = 0; a < dim; a++) {
        double cv = 0.0;
        for (int q = 0; q <= count; q++) {
            const int node = 3 * chain_node(m, first, count, q);
            for (int d = 0; d < 3; d++) cv += C[a * dim + 3 * q + d] * v[node + d];
        }
        out[a] = cv;
    }
}

/* f [ndof] += member b's nodal vector mf: a pair element's force on its second node (the
 * first takes minus it), mf[0..2]; a chain member's on each node, mf[0..3n-1]. */
static void add_member_force(const fem_model *m, int b, const double *mf, double *f)
{
    const int first = m->member_first[b], count = m->member_first[b + 1] - first;
    if (!element_ops(m, first)->chain) {
        const int k = 3 * m->conn[2 * first], l = 3 * m->conn[2 * first + 1];
        for (int i = 0; i < 3; i++) {
            f[l + i] += mf[i];
            f[k + i] -= mf[i];
        }
        return;
    }
    for (int j = 0; j <= count; j++)
        for (int i = 0; i < 3; i++) f[3 * chain_node(m, first, count, j) + i] += mf[3 * j + i];
}

/* 1: member b is a chain whose nodes that are not neighbours are coupled only by a rank-one
 * term, kept out of the matrix (fem_element.h chain_rank_one) */
static int split_rank_one(const fem_model *m, int b)
{
    return element_ops(m, m->member_first[b])->chain_rank_one != NULL;
}

/* Pseudo-elements of the pattern for the node pairs of a chain member that are not
 * neighbours (its tangent is dense), in member order, rows i, columns j > i + 1; none for a
 * member whose rank-one term stays out of the matrix. */
static int chain_pair_count(const fem_model *m)
{
    int n = 0;
    for (int b = 0; b < m->n_members; b++) {
        int c = m->member_first[b + 1] - m->member_first[b] + 1;   /* nodes */
        if (c > 2 && !split_rank_one(m, b)) n += (c - 1) * (c - 2) / 2;
    }
    return n;
}

/* The rank-one members' equation lists and term storage (fem_analysis.h). */
static int rank_one_alloc(fem_analysis *s)
{
    const fem_model *m = s->m;
    s->lr_of_member = malloc(((size_t)m->n_members + 1) * sizeof *s->lr_of_member);
    s->lr_at = malloc(((size_t)m->n_members + 1) * sizeof *s->lr_at);
    if (!s->lr_of_member || !s->lr_at) return -1;
    size_t at = 0;
    s->lr_members = 0;
    for (int b = 0; b < m->n_members; b++) {
        s->lr_of_member[b] = -1;
        if (!split_rank_one(m, b)) continue;
        s->lr_of_member[b] = s->lr_members;
        s->lr_at[s->lr_members++] = at;
        at += 3 * (size_t)(m->member_first[b + 1] - m->member_first[b] + 1);
    }
    s->lr_at[s->lr_members] = at;
    const size_t r = (size_t)s->lr_members + 1;
    s->lr_eq = malloc((at + 1) * sizeof *s->lr_eq);
    s->lr_g = calloc(at + 1, sizeof(double));
    s->lr_gc = calloc(at + 1, sizeof(double));
    s->lr_k = calloc(r, sizeof(double));
    s->lr_c = calloc(r, sizeof(double));
    s->lr_c_frozen = calloc(r, sizeof(double));
    s->lr_shift = calloc(at + 1, sizeof(double));
    if (!s->lr_eq || !s->lr_g || !s->lr_gc || !s->lr_k || !s->lr_c || !s->lr_c_frozen ||
        !s->lr_shift)
        return -1;
    for (int b = 0; b < m->n_members; b++) {
        const int r_b = s->lr_of_member[b];
        if (r_b < 0) continue;
        const int first = m->member_first[b], count = m->member_first[b + 1] - first;
        for (int j = 0; j <= count; j++)
            for (int c = 0; c < 3; c++)
                s->lr_eq[s->lr_at[r_b] + 3 * (size_t)j + c] = s->eq[3 * chain_node(m, first, count, j) + c];
    }
    return 0;
}

/* A free equation that only a rank-one term holds (a rope end pulled along a straight rope
 * in a static analysis: no geometric stiffness along the rope, its stretch all in the term)
 * leaves the matrix singular, and the factorisation that preconditions GMRES fails. Its
 * diagonal gets the term's own diagonal k g_e^2 (lr_shift), which rank_one_apply takes back:
 * the tangent GMRES iterates on stays exact, the preconditioner is regular, and the
 * correction GMRES must find grows from rank one by one per shifted equation. */
static void rank_one_shift(fem_analysis *s, double *x)
{
    for (int r = 0; r < s->lr_members; r++) {
        const size_t at = s->lr_at[r], n = s->lr_at[r + 1] - at;
        for (size_t a = 0; a < n; a++) {
            const int eq = s->lr_eq[at + a];
            const double g = s->lr_g[at + a], term = s->lr_k[r] * g * g;
            s->lr_shift[at + a] = 0.0;
            if (eq < 0 || !(term > 0.0)) continue;
            double *diag = x + s->K.diag[eq];
            if (fabs(*diag) > 1e-10 * term) continue;
            *diag += term;
            s->lr_shift[at + a] = term;
        }
    }
}

/* y += the rank-one terms of the tangent times x, less the diagonal rank_one_shift put into
 * the matrix (both over the free equations) */
static void rank_one_apply(const fem_analysis *s, const double *x, double *y)
{
    for (int r = 0; r < s->lr_members; r++) {
        const int *eq = s->lr_eq + s->lr_at[r];
        const int n = (int)(s->lr_at[r + 1] - s->lr_at[r]);
        const double *shift = s->lr_shift + s->lr_at[r];
        for (int a = 0; a < n; a++)
            if (eq[a] >= 0 && shift[a] != 0.0) y[eq[a]] -= shift[a] * x[eq[a]];
        const double coef[2] = {s->lr_k[r], s->lr_c[r]};
        const double *vec[2] = {s->lr_g + s->lr_at[r], s->lr_gc + s->lr_at[r]};
        for (int t = 0; t < 2; t++) {
            if (coef[t] == 0.0) continue;
            double gx = 0.0;
            for (int a = 0; a < n; a++)
                if (eq[a] >= 0) gx += vec[t][a] * x[eq[a]];
            gx *= coef[t];
            for (int a = 0; a < n; a++)
                if (eq[a] >= 0) y[eq[a]] += gx * vec[t][a];
        }
    }
}

/* The matrix pattern: the elements' couplings and the extra node pairs (each a 2-node
 * pseudo-element without values of its own). s->slot covers both; assembly uses the
 * elements' part. Any factorisation (also the saved one) belongs to the old pattern and is
 * dropped: the next solve factorises afresh. */
static int build_pattern(fem_analysis *s, nc_error *err)
{
    const fem_model *m = s->m;
    const size_t nel = (size_t)m->n_elements, ncp = (size_t)s->n_chain_pairs;
    size_t ne = nel + ncp + (size_t)s->n_pairs;
    int *elem_eq = malloc(6 * ne * sizeof *elem_eq);
    int *slot = malloc(36 * ne * sizeof *slot);
    int *chain = malloc(2 * (ncp + 1) * sizeof *chain);
    if (!elem_eq || !slot || !chain) {
        free(elem_eq);
        free(slot);
        free(chain);
        return nc_error_set(err, 1, "out of memory for the matrix pattern");
    }
    size_t q = 0;
    for (int mb = 0; mb < m->n_members; mb++) {
        int first = m->member_first[mb], count = m->member_first[mb + 1] - first;
        if (split_rank_one(m, mb)) continue;
        for (int i = 0; i <= count; i++)
            for (int j = i + 2; j <= count; j++) {
                chain[2 * q] = chain_node(m, first, count, i);
                chain[2 * q + 1] = chain_node(m, first, count, j);
                q++;
            }
    }
    for (size_t e = 0; e < ne; e++) {
        const int *pair = e < nel ? m->conn + 2 * e : e < nel + ncp ? chain + 2 * (e - nel)
                                                                    : s->pairs + 2 * (e - nel - ncp);
        int a = pair[0], b = pair[1];
        for (int c = 0; c < 3; c++) {
            elem_eq[6 * e + c] = s->eq[3 * a + c];
            elem_eq[6 * e + 3 + c] = s->eq[3 * b + c];
        }
    }
    fem_sparse_free(&s->K);
    memset(&s->K, 0, sizeof s->K);
    int rc = fem_sparse_build(&s->K, s->neq, (int)ne, elem_eq, slot, s->factor_mode, err);
    free(elem_eq);
    free(chain);
    free(s->slot);
    s->slot = slot;
    return rc;
}

/* Adds to the pattern the node pairs of the blocks that have no slot yet. */
static int grow_pattern(fem_analysis *s, int n_blocks, const int *block_nodes, nc_error *err)
{
    int added = 0;
    for (int b = 0; b < n_blocks; b++) {
        int i = block_nodes[2 * b], j = block_nodes[2 * b + 1];
        if (i < 0 || j < 0 || i >= s->m->n_nodes || j >= s->m->n_nodes)
            continue;   /* fem_ijac_set names the block */
        if (i == j || fem_ijac_pair_stored(&s->K, s->eq, i, j)) continue;
        int lo = i < j ? i : j, hi = i < j ? j : i, known = 0;
        for (int p = s->n_pairs - added; p < s->n_pairs && !known; p++)
            known = s->pairs[2 * p] == lo && s->pairs[2 * p + 1] == hi;
        if (known) continue;
        if (s->n_pairs == s->cap_pairs) {
            int cap = s->cap_pairs ? 2 * s->cap_pairs : 64;
            int *grown = realloc(s->pairs, 2 * (size_t)cap * sizeof *grown);
            if (!grown) return nc_error_set(err, 1, "out of memory for %d node pairs", cap);
            s->pairs = grown;
            s->cap_pairs = cap;
        }
        s->pairs[2 * s->n_pairs] = lo;
        s->pairs[2 * s->n_pairs + 1] = hi;
        s->n_pairs++;
        added++;
    }
    if (!added) return 0;
    s->stats.pattern_growths++;
    return build_pattern(s, err);
}

int fem_analysis_set_pattern_pairs(fem_analysis *s, int n_pairs, const int *pairs, nc_error *err)
{
    if (n_pairs < 0) return nc_error_set(err, 1, "%d node pairs", n_pairs);
    for (int p = 0; p < 2 * n_pairs; p++)
        if (pairs[p] < 0 || pairs[p] >= s->m->n_nodes)
            return nc_error_set(err, 1, "node pair %d: node %d is not in the model (0..%d)", p / 2,
                                pairs[p], s->m->n_nodes - 1);
    if (n_pairs > s->cap_pairs) {
        int *grown = realloc(s->pairs, 2 * (size_t)n_pairs * sizeof *grown);
        if (!grown) return nc_error_set(err, 1, "out of memory for %d node pairs", n_pairs);
        s->pairs = grown;
        s->cap_pairs = n_pairs;
    }
    if (n_pairs > 0) memcpy(s->pairs, pairs, 2 * (size_t)n_pairs * sizeof *pairs);
    s->n_pairs = n_pairs;
    return build_pattern(s, err);
}

int fem_analysis_init(fem_analysis *s, const fem_model *m, nc_error *err)
{
    memset(s, 0, sizeof *s);
    s->m = m;
    s->fixed_load_factor = -1.0;
    s->ndof = 3 * m->n_nodes;
    size_t nd = (size_t)s->ndof, ne = (size_t)m->n_elements;
    s->eq = malloc(nd * sizeof *s->eq);
    s->dof_of_eq = malloc(nd * sizeof *s->dof_of_eq);
    int *elem_eq = malloc(6 * ne * sizeof *elem_eq);
    s->f_model = calloc(nd, sizeof(double));
    s->f_coupling = calloc(nd, sizeof(double));
    s->r = calloc(nd, sizeof(double));
    s->w = calloc(nd, sizeof(double));
    s->rhs = calloc(nd, sizeof(double));
    s->du = calloc(nd, sizeof(double));
    s->u0 = calloc(nd, sizeof(double));
    s->cg_r = calloc(nd, sizeof(double));
    s->cg_z = calloc(nd, sizeof(double));
    s->cg_p = calloc(nd, sizeof(double));
    s->cg_q = calloc(nd, sizeof(double));
    s->axial = calloc(ne, sizeof(double));
    s->mass_diag = calloc(nd, sizeof(double));
    s->mass_x = calloc(nd, sizeof(double));
    s->mass_y = calloc(nd, sizeof(double));
    s->a_unshifted = calloc(nd, sizeof(double));
    if (m->kappa_s != 0.0 && damping_alloc(s)) {
        free(elem_eq);
        return nc_error_set(err, 1, "%s: out of memory for the damping matrix", m->source);
    }
    s->factor_mode = m->settings.factorization;
    s->stats.ldlt_switch_step = -1;
    s->n_chain_pairs = chain_pair_count(m);
    size_t nc = 3 * (size_t)m->max_chain_nodes;
    s->chain_f = calloc(nc, sizeof(double));
    s->chain_v = calloc(nc, sizeof(double));
    s->chain_K = calloc(nc * nc, sizeof(double));
    if (!s->chain_f || !s->chain_v || !s->chain_K ||
        !s->mass_diag || !s->mass_x || !s->mass_y || !s->a_unshifted ||
        !s->eq || !s->dof_of_eq || !elem_eq || !s->f_model || !s->f_coupling ||
        !s->r || !s->w || !s->rhs || !s->du || !s->u0 || !s->cg_r || !s->cg_z ||
        !s->cg_p || !s->cg_q || !s->axial || state_alloc(&s->cur, s->ndof, m->history_count) ||
        state_alloc(&s->start, s->ndof, m->history_count) ||
        state_alloc(&s->saved, s->ndof, m->history_count)) {
        free(elem_eq);
        return nc_error_set(err, 1, "%s: out of memory for %d dofs", m->source, s->ndof);
    }
    /* Supported dofs are not unknowns: the pattern holds only free equations, so it never
     * changes whatever the supports do. */
    s->neq = 0;
    for (int i = 0; i < s->ndof; i++) {
        s->eq[i] = m->fixed[i] ? -1 : s->neq;
        if (!m->fixed[i]) s->dof_of_eq[s->neq++] = i;
    }
    for (int e = 0; e < m->n_elements; e++)
        for (int c = 0; c < 3; c++) {
            elem_eq[6 * e + c] = s->eq[3 * m->conn[2 * e] + c];
            elem_eq[6 * e + 3 + c] = s->eq[3 * m->conn[2 * e + 1] + c];
        }
    for (int e = 0; e < m->n_elements; e++) {
        double m11, m12;
        fem_element_bar_mass(m->rhoA[e], m->L0[e], m->lumped_mass, &m11, &m12);
        for (int a = 0; a < 6; a++) {
            int q = elem_eq[6 * e + a];
            if (q >= 0) s->mass_diag[q] += m11;
        }
    }
    free(elem_eq);
    if (rank_one_alloc(s))
        return nc_error_set(err, 1, "%s: out of memory for the sliding ropes' rank-one terms", m->source);
    if (build_pattern(s, err)) return nc_error_prefix(err, "%s", m->source);
    /* model loads at full scale: point loads + self-weight (half of rho A L g per node, which
     * is also the consistent load of a linear element) */
    memcpy(s->f_model, m->f_point, nd * sizeof(double));
    if (m->self_weight)
        for (int e = 0; e < m->n_elements; e++) {
            double half = 0.5 * m->rhoA[e] * m->L0[e];
            for (int c = 0; c < 3; c++) {
                s->f_model[3 * m->conn[2 * e] + c] += half * m->gravity[c];
                s->f_model[3 * m->conn[2 * e + 1] + c] += half * m->gravity[c];
            }
        }
    fem_analysis_update_axial(s);
    return 0;
}

void fem_analysis_free(fem_analysis *s)
{
    if (!s) return;
    fem_sparse_free(&s->K);
    fem_ijac_free(&s->lin);
    fem_gmres_free(&s->gmres);
    state_free(&s->cur); state_free(&s->start); state_free(&s->saved);
    free(s->eq); free(s->dof_of_eq); free(s->slot); free(s->pairs);
    free(s->f_model); free(s->f_coupling);
    free(s->r); free(s->w); free(s->rhs); free(s->du); free(s->u0);
    free(s->cg_r); free(s->cg_z); free(s->cg_p); free(s->cg_q); free(s->axial);
    free(s->mass_diag); free(s->mass_x); free(s->mass_y); free(s->a_unshifted);
    free(s->chain_f); free(s->chain_v); free(s->chain_K);
    free(s->lr_of_member); free(s->lr_at); free(s->lr_eq); free(s->lr_g); free(s->lr_gc);
    free(s->lr_shift);
    free(s->lr_k); free(s->lr_c); free(s->lr_c_frozen);
    free(s->damping_K); free(s->damping_at); free(s->damping_start); free(s->damping_end);
    memset(s, 0, sizeof *s);
}

double fem_analysis_load_factor(const fem_analysis *s, double time_s)
{
    if (s->fixed_load_factor >= 0.0) return s->fixed_load_factor;
    double ramp = s->m->settings.load_ramp_s;
    if (ramp <= 0) return 1.0;
    return time_s >= ramp ? 1.0 : (time_s <= 0 ? 0.0 : time_s / ramp);
}

/* Adds scale * B (3x3, row-major) to the block of pseudo-element slots sl at node sides
 * (ra, cb) (0: its first node, 1: its second). */
static void scatter_block(double *x, const int *sl, int ra, int cb, const double *B, double scale)
{
    for (int a = 0; a < 3; a++)
        for (int b = 0; b < 3; b++) {
            int slot = sl[6 * (3 * ra + a) + 3 * cb + b];
            if (slot >= 0) x[slot] += scale * B[3 * a + b];
        }
}

/* The slots of block (i, j) of a chain member (first segment `first`, count segments, its
 * non-neighbour pairs from pseudo-element q0 on) and the sides to use. */
static const int *chain_block_slots(const fem_analysis *s, int first, int count, int q0, int i,
                                    int j, int *ra, int *cb)
{
    const int ne = s->m->n_elements;
    if (i == j) {
        *ra = *cb = i < count ? 0 : 1;
        return s->slot + 36 * (size_t)(first + (i < count ? i : count - 1));
    }
    if (j == i + 1 || i == j + 1) {
        int lo = i < j ? i : j;
        *ra = i > j;
        *cb = j > i;
        return s->slot + 36 * (size_t)(first + lo);
    }
    int lo = i < j ? i : j, hi = i < j ? j : i, q = q0;
    for (int r = 0; r < lo; r++) q += count - r - 1 > 0 ? count - r - 1 : 0;  /* row r: j = r+2..count */
    q += hi - lo - 2;
    *ra = i > j;
    *cb = j > i;
    return s->slot + 36 * (size_t)(ne + q);
}

/* A chain member's share of the assembly (see assemble): returns 1 when slack. */
static int assemble_chain(fem_analysis *s, const fem_element_ctx *c, const fem_element_ops *ops,
                          int q0, double c_m, double c_k, double c_c, const double *w,
                          const double *v, int matrix, double *fd, double *scale2)
{
    const fem_model *m = s->m;
    const int n = c->count + 1, dim = 3 * n;
    double *f = s->chain_f, *K = s->chain_K;
    const double *C = s->damping_K ? s->damping_K + s->damping_at[c->member] : NULL;
    /* a rank-one member: K and C less their rank-one terms go into the matrix (neighbour
     * blocks only), the terms themselves to lr_*; the element fills only those blocks of K,
     * without its term (a dense (3n)^2 fill and clear per evaluation otherwise) */
    const int r1 = s->lr_of_member[c->member];
    fem_element_ctx near = *c;
    near.near_blocks_only = matrix && r1 >= 0;
    int slack = ops->chain_response(&near, f, matrix ? K : NULL, s->axial + c->first);
    const double *gc = NULL;
    double c1 = 0.0;
    if (matrix && r1 >= 0) {
        s->lr_k[r1] = c_k * ops->chain_rank_one(c, s->lr_g + s->lr_at[r1]);
        gc = s->lr_gc + s->lr_at[r1];
        c1 = C ? s->lr_c_frozen[r1] : 0.0;
        s->lr_c[r1] = C ? c_c * c1 : 0.0;
    }
    if (C && v) {
        member_damping_force(s, c->member, v, s->chain_v);
        for (int a = 0; a < dim; a++) f[a] += s->chain_v[a];
    }
    for (int j = 0; j < n; j++) {
        const int node = 3 * chain_node(m, c->first, c->count, j);
        for (int i = 0; i < 3; i++) {
            fd[node + i] += f[3 * j + i];
            *scale2 += f[3 * j + i] * f[3 * j + i];
        }
    }
    /* mass per segment, as for a two-node element */
    for (int sg = 0; sg < c->count; sg++) {
        const int e = c->first + sg, k = 3 * m->conn[2 * e], l = 3 * m->conn[2 * e + 1];
        double m11 = 0, m12 = 0;
        if (c_m != 0.0 || w) fem_element_bar_mass(m->rhoA[e], m->L0[e], m->lumped_mass, &m11, &m12);
        if (w)
            for (int i = 0; i < 3; i++) {
                double ik = m11 * w[k + i] + m12 * w[l + i], il = m12 * w[k + i] + m11 * w[l + i];
                s->r[k + i] -= ik;
                s->r[l + i] -= il;
                *scale2 += ik * ik + il * il;
            }
        if (matrix && c_m != 0.0) {
            const double I[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
            const int *sl = s->slot + 36 * (size_t)e;
            scatter_block(s->K.x, sl, 0, 0, I, c_m * m11);
            scatter_block(s->K.x, sl, 1, 1, I, c_m * m11);
            scatter_block(s->K.x, sl, 0, 1, I, c_m * m12);
            scatter_block(s->K.x, sl, 1, 0, I, c_m * m12);
        }
    }
    if (matrix)
        for (int i = 0; i < n; i++)
            for (int j = 0; j < n; j++) {
                if (r1 >= 0 && (i > j + 1 || j > i + 1)) continue;   /* only rank-one there */
                double B[9];
                for (int a = 0; a < 3; a++)
                    for (int b = 0; b < 3; b++)
                        B[3 * a + b] = K[(3 * i + a) * dim + 3 * j + b];
                int ra, cb;
                const int *sl = chain_block_slots(s, c->first, c->count, q0, i, j, &ra, &cb);
                scatter_block(s->K.x, sl, ra, cb, B, c_k);
                if (C && c_c != 0.0) {
                    for (int a = 0; a < 3; a++)
                        for (int b = 0; b < 3; b++)
                            B[3 * a + b] = C[(3 * i + a) * dim + 3 * j + b] -
                                           (gc ? c1 * gc[3 * i + a] * gc[3 * j + b] : 0.0);
                    scatter_block(s->K.x, sl, ra, cb, B, c_c);
                }
            }
    return slack;
}

/* The weights of the step equation's tangent c_m M + c_k K_T + c_c C_K (+ l_k K + l_c C of
 * an interface linearisation), of its internal force, wf = 1 - alpha_f, and of the
 * linearisation's force change, l_w (see the top of this file). */
typedef struct step_weights {
    double c_m, c_k, c_c, l_k, l_c, wf, l_w;
} step_weights;

/* Residual r (all dofs; meaningful on free ones) and, with matrix != 0, the tangent with the
 * weights sw into the fixed pattern. w is the mass-term vector, v the velocity used by the
 * damping C_K and the linearisation's C term (NULL: none), fd_n the alpha_f part. Also fills
 * cur.fd and axial, and lin.df when a linearisation is set. Returns the force scale used by
 * the relative tolerance. */
static double assemble(fem_analysis *s, double lambda, const step_weights *sw, const double *w,
                       const double *v, const double *fd_n, int matrix, const double *hist)
{
    const fem_model *m = s->m;
    const double c_m = sw->c_m, c_k = sw->c_k, c_c = sw->c_c, wf = sw->wf;
    double t0 = nc_clock_now_s();
    const double *u = s->cur.u;
    double *fd = s->cur.fd;
    double *x = s->K.x;
    if (matrix) memset(x, 0, (size_t)s->K.nnz * sizeof *x);
    memset(fd, 0, (size_t)s->ndof * sizeof *fd);
    double scale2 = 0, fext2 = 0;
    if (s->lin.active) {
        fem_ijac_force(&s->lin, u, v);
        const double *df = s->lin.df;
        scale2 += s->lin.force_scale_n * s->lin.force_scale_n;
        for (int i = 0; i < s->ndof; i++) {
            s->r[i] = lambda * s->f_model[i] + s->f_coupling[i] + sw->l_w * df[i];
            fext2 += s->r[i] * s->r[i];
        }
        if (matrix && (sw->l_k != 0.0 || sw->l_c != 0.0)) fem_ijac_scatter(&s->lin, sw->l_k, sw->l_c, x);
    } else {
        for (int i = 0; i < s->ndof; i++) {
            s->r[i] = lambda * s->f_model[i] + s->f_coupling[i];
            fext2 += s->r[i] * s->r[i];
        }
    }
    int slack_count = 0, q0 = 0;
    for (int mb = 0; mb < m->n_members; mb++) {
        const int e = m->member_first[mb];
        const fem_element_ops *ops = element_ops(m, e);
        fem_element_ctx ctx;
        member_ctx(m, mb, u, hist, &ctx);
        if (ops->chain) {
            slack_count += assemble_chain(s, &ctx, ops, q0, c_m, c_k, c_c, w, v, matrix, fd, &scale2);
            if (ctx.count > 1 && s->lr_of_member[mb] < 0) q0 += ctx.count * (ctx.count - 1) / 2;
            continue;
        }
        const int k = 3 * m->conn[2 * e], l = 3 * m->conn[2 * e + 1];
        double f[3], Kb[9];
        int slack;
        s->axial[e] = ops->pair_response(&ctx, f, Kb, &slack);
        slack_count += slack;
        const double *C = s->damping_K ? s->damping_K + s->damping_at[mb] : NULL;
        if (C && v) {
            double cv[3];
            member_damping_force(s, mb, v, cv);
            for (int i = 0; i < 3; i++) f[i] += cv[i];
        }
        for (int c = 0; c < 3; c++) {
            fd[l + c] += f[c];
            fd[k + c] -= f[c];
            scale2 += 2 * f[c] * f[c];
        }
        double m11 = 0, m12 = 0;
        if (c_m != 0.0 || w) fem_element_bar_mass(m->rhoA[e], m->L0[e], m->lumped_mass, &m11, &m12);
        if (w)
            for (int c = 0; c < 3; c++) {
                double ik = m11 * w[k + c] + m12 * w[l + c], il = m12 * w[k + c] + m11 * w[l + c];
                s->r[k + c] -= ik;
                s->r[l + c] -= il;
                /* inertia belongs to the force scale: a node kicked by a rock carries
                 * inertial forces far above the loads, and the residual's rounding floor
                 * (m eps(u) / (beta dt^2)) grows with them */
                scale2 += ik * ik + il * il;
            }
        if (matrix) {
            /* 6x6 element matrix [c_k Kb + c_m m11 I, -c_k Kb + c_m m12 I; ...], scattered
             * through the precomputed slot map (entries with slot -1 are not stored) */
            const int *sl = s->slot + 36 * e;
            for (int a = 0; a < 6; a++)
                for (int b = 0; b < 6; b++) {
                    int slot = sl[6 * a + b];
                    if (slot < 0) continue;
                    int same = (a < 3) == (b < 3);
                    double kc = c_k * Kb[3 * (a % 3) + (b % 3)];
                    if (C) kc += c_c * C[3 * (a % 3) + (b % 3)];
                    double val = same ? kc : -kc;
                    if (a % 3 == b % 3) val += c_m * (same ? m11 : m12);
                    x[slot] += val;
                }
        }
    }
    if (matrix && s->lr_members > 0) rank_one_shift(s, x);
    for (int i = 0; i < s->ndof; i++) {
        s->r[i] -= wf * fd[i] + (fd_n ? (1.0 - wf) * fd_n[i] : 0.0);
    }
    s->stats.slack_elements = slack_count;
    s->stats.assemblies++;
    s->stats.assembly_s += nc_clock_now_s() - t0;
    return sqrt(scale2) + sqrt(fext2);
}

static double residual_norm(const fem_analysis *s)
{
    double r2 = 0;
    for (int q = 0; q < s->neq; q++) {
        double r = s->r[s->dof_of_eq[q]];
        r2 += r * r;
    }
    return sqrt(r2);
}

/* Factorises the current matrix values; names the node when singular. */
static int factorize(fem_analysis *s, nc_error *err)
{
    double t0 = nc_clock_now_s();
    int bad = -1;
    if (fem_sparse_factorize(&s->K, &bad, err)) {
        if (bad >= 0 && bad < s->neq) {
            int dof = s->dof_of_eq[bad];
            nc_error_prefix(err, "node %d (dof %s)", dof / 3, dof_name(dof % 3));
            size_t len = strlen(err->message);
            snprintf(err->message + len, sizeof err->message - len,
                     ": nothing holds this node in that direction (only slack cables, or a flat "
                     "net without prestress in a static analysis?)");
        }
        return -1;
    }
    s->stats.factorizations++;
    if (s->K.use_lu) s->stats.lu_factorizations++;
    if (s->K.switched_to_ldlt && s->factor_mode == 0) {
        s->factor_mode = 1;   /* a rebuilt pattern (its growth) starts as LDL^T */
        s->stats.ldlt_switch_step = s->cur.step;
    }
    s->stats.factor_s += nc_clock_now_s() - t0;
    return 0;
}

/* Solves K du = r on the free equations, factorising first unless `reuse`. */
static int linear_solve(fem_analysis *s, int reuse, nc_error *err)
{
    if (!reuse && factorize(s, err)) return -1;
    s->stats.solves++;
    double t1 = nc_clock_now_s();
    for (int q = 0; q < s->neq; q++) s->rhs[q] = s->r[s->dof_of_eq[q]];
    if (fem_sparse_solve(&s->K, s->rhs, s->du, err)) return -1;
    s->stats.solve_s += nc_clock_now_s() - t1;
    return 0;
}

/* Inexact Newton step with a kept factorisation: conjugate gradients on the current
 * matrix, preconditioned by the kept (slightly outdated) Cholesky factor, until
 * |b - K du| <= FEM_PCG_TOL |b| (an inexact Newton step: the outer iteration still reaches
 * the full Newton tolerance). Returns 0 when converged, 1 when it did not within
 * FEM_PCG_MAX_IT iterations or the matrix is not positive definite along the search
 * direction (the caller then refactorises), -1 on error. */
#define FEM_PCG_TOL 1e-4    /* forcing term of the inexact Newton step */
#define FEM_PCG_MAX_IT 25
/* rounding floor of the Newton iteration (see newton()): a full increment below this many
 * ulps of the largest coordinate, a residual within this factor of the tolerance or within
 * this many ulps of the displacements in the interface linearisation's K (u - u^k) */
#define FEM_ROUNDOFF_ULPS 64.0
#define FEM_ROUNDOFF_TOL_FACTOR 1e3
#define FEM_ROUNDOFF_LIN_ULPS 8.0
#define FEM_PCG_CHEAP 6     /* more CG iterations than this: refactorise next time (measured
                               on the 81x81 benchmark: 6 balances CG cost and factorisations) */

static double dot(const double *a, const double *b, int n)
{
    double sum = 0;
    for (int i = 0; i < n; i++) sum += a[i] * b[i];
    return sum;
}

static int pcg_solve(fem_analysis *s, nc_error *err)
{
    double t0 = nc_clock_now_s();
    int n = s->neq;
    double *x = s->du, *r = s->cg_r, *z = s->cg_z, *p = s->cg_p, *q = s->cg_q;
    for (int i = 0; i < n; i++) {
        s->rhs[i] = s->r[s->dof_of_eq[i]];
        r[i] = s->rhs[i];
        x[i] = 0.0;
    }
    double bnorm = sqrt(dot(r, r, n));
    if (fem_sparse_solve(&s->K, r, z, err)) return -1;
    memcpy(p, z, (size_t)n * sizeof *p);
    double rz = dot(r, z, n);
    int rc = 1, k;
    for (k = 1; k <= FEM_PCG_MAX_IT; k++) {
        fem_sparse_matvec(&s->K, p, q);
        double pq = dot(p, q, n);
        if (!(pq > 0) || !(rz > 0)) break;
        double alpha = rz / pq;
        for (int i = 0; i < n; i++) {
            x[i] += alpha * p[i];
            r[i] -= alpha * q[i];
        }
        if (sqrt(dot(r, r, n)) <= FEM_PCG_TOL * bnorm) {
            rc = 0;
            break;
        }
        if (fem_sparse_solve(&s->K, r, z, err)) return -1;
        double rz_new = dot(r, z, n);
        double beta = rz_new / rz;
        rz = rz_new;
        for (int i = 0; i < n; i++) p[i] = z[i] + beta * p[i];
    }
    s->stats.pcg_solves++;
    s->stats.pcg_iterations += k > FEM_PCG_MAX_IT ? FEM_PCG_MAX_IT : k;
    if (rc) s->stats.pcg_failures++;
    s->stats.solves++;
    s->stats.solve_s += nc_clock_now_s() - t0;
    return rc;
}

/* The Newton step with an unsymmetric tangent (an interface linearisation with a skew
 * part, fem_gmres.h) or with rank-one terms kept out of the matrix (sliding ropes): GMRES on
 * the matrix plus the skew part and those terms, preconditioned by the factorisation of the
 * matrix (refactorised first with `refactor`; else the kept one); each term costs GMRES at
 * most one iteration more, and keeps a dense block over the rope out of the factor.
 * Returns 0, 1 when GMRES did not reach tol within max_it (du holds its last iterate), -1 on
 * error. */
#define FEM_GMRES_TOL 1e-12  /* relative residual of a step with a fresh factorisation */
#define FEM_GMRES_MAX_IT 60  /* more than the skew part's rank for up to 20 contact nodes */
#define FEM_GMRES_KEPT_MAX_IT 40  /* with a kept factorisation */
#define FEM_GMRES_CHEAP 15   /* more GMRES iterations than this with a kept factorisation:
                                refactorise next time. A fresh one already leaves GMRES the
                                skew part's rank (7-9 on the three-module barrier), and there
                                a factorisation cost about 60 iterations (10 since the sliding
                                ropes' rank-one terms left the matrix): at 6, as for CG,
                                nearly every Newton step refactorised */

static int apply_tangent(void *ctx, const double *x, double *y, nc_error *err)
{
    (void)err;
    fem_analysis *s = ctx;
    fem_sparse_matvec(&s->K, x, y);
    if (s->lin.active) fem_ijac_skew_apply(&s->lin, s->skew_lk, s->skew_lc, x, y);
    rank_one_apply(s, x, y);
    return 0;
}

static int apply_factor(void *ctx, const double *x, double *y, nc_error *err)
{
    fem_analysis *s = ctx;
    return fem_sparse_solve(&s->K, x, y, err);
}

static int skew_solve(fem_analysis *s, int refactor, double tol, int max_it, nc_error *err)
{
    if (refactor && factorize(s, err)) return -1;
    if (fem_gmres_reserve(&s->gmres, s->neq, FEM_GMRES_MAX_IT, err)) return -1;
    double t0 = nc_clock_now_s();
    for (int q = 0; q < s->neq; q++) s->rhs[q] = s->r[s->dof_of_eq[q]];
    int its = 0;
    int rc = fem_gmres_solve(&s->gmres, apply_tangent, apply_factor, s, s->rhs, s->du, tol, max_it,
                             &its, err);
    s->stats.solves++;
    s->stats.gmres_solves++;
    s->stats.gmres_iterations += its;
    if (rc == 1) s->stats.gmres_failures++;
    s->stats.solve_s += nc_clock_now_s() - t0;
    return rc;
}

/* Newmark kinematics of every dof from u_{n+1} and the start state. */
static void update_kinematics(fem_analysis *s, double dt, double beta, double gamma)
{
    const fem_state *n = &s->start;
    fem_state *c = &s->cur;
    double c0 = 1.0 / (beta * dt * dt), c2 = 1.0 / (2.0 * beta) - 1.0;
    for (int i = 0; i < s->ndof; i++) {
        double a = c0 * (c->u[i] - n->u[i] - dt * n->v[i]) - c2 * n->a[i];
        c->a[i] = a;
        c->v[i] = n->v[i] + dt * ((1.0 - gamma) * n->a[i] + gamma * a);
    }
}

typedef struct newton_setup {
    int dynamic;
    double dt, beta, gamma, alpha_m, alpha_f, lambda;
} newton_setup;

/* Kinematics, residual and tangent at the current iterate; returns the residual norm and
 * sets *tol from the force scale. */
static double evaluate(fem_analysis *s, const newton_setup *ns, const step_weights *sw, double *tol)
{
    const fem_model *m = s->m;
    const double *w = NULL, *vk = NULL;
    if (ns->dynamic) {
        update_kinematics(s, ns->dt, ns->beta, ns->gamma);
        for (int i = 0; i < s->ndof; i++) {
            double a_am = (1.0 - ns->alpha_m) * s->cur.a[i] + ns->alpha_m * s->start.a[i];
            double v_af = (1.0 - ns->alpha_f) * s->cur.v[i] + ns->alpha_f * s->start.v[i];
            s->w[i] = a_am + m->tau_per_s * v_af;
        }
        w = s->w;
        vk = s->cur.v;
    }
    /* elements respond from the history committed at the start of the step */
    double scale = assemble(s, ns->lambda, sw, w, vk,
                            ns->dynamic && ns->alpha_f != 0.0 ? s->start.fd : NULL, 1,
                            s->start.element_history);
    *tol = fmax(m->settings.residual_tol_n, m->settings.relative_tol * scale);
    return residual_norm(s);
}

static void set_free_u(fem_analysis *s, double alpha)
{
    for (int q = 0; q < s->neq; q++) s->cur.u[s->dof_of_eq[q]] = s->u0[q] + alpha * s->du[q];
}

/* Tangent weights of the step equation (see the top of this file). */
static step_weights newton_weights(const fem_model *m, const newton_setup *ns)
{
    step_weights sw = {.c_m = 0, .c_k = 1, .c_c = 0, .l_k = 1, .l_c = 0, .wf = 1, .l_w = 1};
    if (ns->dynamic) {
        double bdt = ns->beta * ns->dt;
        sw.c_m = (1.0 - ns->alpha_m) / (bdt * ns->dt) + m->tau_per_s * (1.0 - ns->alpha_f) * ns->gamma / bdt;
        sw.c_k = 1.0 - ns->alpha_f;
        sw.c_c = (1.0 - ns->alpha_f) * ns->gamma / bdt;
        sw.wf = 1.0 - ns->alpha_f;
        if (m->settings.coupling_load_constant) {
            const double c2 = 1.0 / (2.0 * ns->beta) - 1.0;
            sw.l_w = 1.0 + (1.0 - ns->alpha_m) * c2 - ns->alpha_m -
                     m->tau_per_s * (1.0 - ns->alpha_f) * ns->dt * ((1.0 - ns->gamma) - ns->gamma * c2);
        }
        sw.l_k = sw.l_w;
        sw.l_c = sw.l_w * ns->gamma / bdt;
    }
    return sw;
}

/* A pseudo step of fem_analysis_settle takes a Newton step whose residual is up to this many
 * times the last one (a non-monotone line search). A hanging barrier's net has slack cables:
 * a full step moves a node that they leave free until a neighbouring cable is taut, the
 * residual's largest entry travels along a row of nodes one node per iteration, and a line
 * search that wants every residual below the last halves nearly every step (the MEL barrier:
 * 20 of 26 iterations of a pseudo step of 0.064 s). Measured on the initial equilibrium:
 * the MEL barrier 1378 -> 405 Newton iterations, a ten-module barrier 1394 -> 900 and
 * 100 -> 36 s; its static analysis in 5 load steps 11.6 -> 2.8 s
 * (docs/notes/initial_equilibrium.md). The equilibrium is the same to the tolerance where
 * it is unique: the MEL barrier's start moved by 1.1e-6 m, along its frictionless shackles. */
#define FEM_SETTLE_RESIDUAL_GROWTH 3.0

/* Newton iterations for the current step; cur holds the predictor on entry.
 * Converged when the residual norm is below max(residual_tolerance_n, relative_tolerance *
 * force scale) and the last increment's max-norm below displacement_tolerance_m. When only
 * the increment criterion is pending (residual already small) the previous factorisation is
 * reused for that confirming solve. A full step that increases the residual (cables going
 * slack and taut again can make plain Newton cycle; in a pseudo step of fem_analysis_settle:
 * beyond FEM_SETTLE_RESIDUAL_GROWTH times it) is halved up to 4 times and the best of the
 * tried steps is taken. */
static int newton(fem_analysis *s, const newton_setup *ns, nc_error *err)
{
    const fem_model *m = s->m;
    const fem_settings *set = &m->settings;
    const step_weights sw = newton_weights(m, ns);
    s->last_lw = sw.l_w;
    s->last_lk = sw.l_k;
    s->last_lc = sw.l_c;
    s->last_cm = sw.c_m;
    s->last_ck = sw.c_k;
    s->last_velocity_per_m = ns->dynamic ? ns->gamma / (ns->beta * ns->dt) : 0.0;
    double tol, dunorm = 0;
    double rnorm = evaluate(s, ns, &sw, &tol);
    /* a factorisation of the same matrix form kept from an earlier step (modified Newton) */
    int factorized = set->modified_newton && s->K.have_factor && s->factor_cm == sw.c_m &&
                     s->factor_ck == sw.c_k;
    int it, refresh = !factorized;
    double dfull = INFINITY;   /* max-norm of the last full Newton increment */
    double coord_max_m = 0.0;  /* largest nodal coordinate: the scale of its rounding */
    for (int d = 0; d < s->ndof; d++) coord_max_m = fmax(coord_max_m, fabs(m->X[d] + s->cur.u[d]));
    for (it = 1; it <= set->max_iterations + 1 && isfinite(rnorm); it++) {
        /* At the rounding floor: a full Newton increment that cannot change the nodal
         * positions any more (a few ulps of the largest coordinate) leaves a residual that
         * no iteration can reduce. With a stiff interface linearisation or a large inertia
         * term that floor can lie above the tolerance (the tolerance's force scale counts
         * the loads, the inertia and the linearised forces, not the products K u that
         * cancel in them); within FEM_ROUNDOFF_TOL_FACTOR of the tolerance, or within
         * FEM_ROUNDOFF_LIN_ULPS ulps of the displacements in the interface linearisation's
         * K (u - u^k) (a dashpot of eq. (A.5) at a graze: K of 1e13-1e16 N/m, a residual of
         * 1e-3-1 N), such a state is converged as far as double precision allows, and
         * counted. */
        const int small_step = it > 1 && dfull <= FEM_ROUNDOFF_ULPS * DBL_EPSILON * coord_max_m;
        const int at_floor = small_step &&
            (rnorm <= FEM_ROUNDOFF_TOL_FACTOR * tol ||
             (s->lin.active && rnorm <= FEM_ROUNDOFF_LIN_ULPS *
                                        fem_ijac_rounding_n(&s->lin, sw.l_k, sw.l_c, s->cur.u)));
        if ((rnorm <= tol && (it == 1 || dunorm <= set->displacement_tol_m)) || at_floor) {
            s->stats.iterations = it - 1;
            s->stats.residual_norm = rnorm;
            s->stats.increment_norm = dunorm;
            if (at_floor && rnorm > tol) s->stats.roundoff_converged++;
            return 0;
        }
        if (it > set->max_iterations) break;
        /* Full Newton refactorises every iteration. Modified Newton keeps the last
         * factorisation (also from earlier steps, when the matrix form c_m, c_k is the same)
         * and uses it to precondition CG on the current tangent, so the steps are (nearly)
         * exact Newton steps; it refactorises when CG needs too many iterations, after a
         * line-search cut, when the residual contracts too slowly, and in the second half of
         * the iteration budget. Save and restore keep the factorisation with the state, so
         * a repeated step is bit-identical. */
        /* 0: factorise and solve; 1: solve with the kept factorisation (only an increment
         * check is pending); 2: CG preconditioned by the kept factorisation */
        int mode;
        if (!factorized) mode = 0;
        else if (rnorm <= tol) mode = 1;
        /* CG iterates on the current tangent (a linearisation included), so a kept factor
         * is only its preconditioner; a kept LU is used directly, so it is refreshed when
         * the linearisation changed since it was made */
        else if (set->modified_newton && !refresh)
            mode = !s->K.use_lu ? 2 : s->factor_lin == s->lin_serial ? 1 : 0;
        else mode = 0;
        int cg_slow = 0;
        if ((s->lin.active && s->lin.has_skew) || s->lr_members > 0) {
            /* an unsymmetric tangent, or rank-one terms outside the matrix: GMRES around the
             * factorisation of the matrix, an inexact step with a kept factor as CG would
             * make, else to FEM_GMRES_TOL */
            s->skew_lk = sw.l_k;
            s->skew_lc = sw.l_c;
            if (mode == 2) {
                long before = s->stats.gmres_iterations;
                int rc = skew_solve(s, 0, FEM_PCG_TOL, FEM_GMRES_KEPT_MAX_IT, err);
                cg_slow = s->stats.gmres_iterations - before > FEM_GMRES_CHEAP;
                if (rc < 0) return -1;
                if (rc == 1) mode = 0;
            }
            /* not reaching FEM_GMRES_TOL with a fresh factor leaves an inexact step, which
             * the line search below judges like any other */
            if (mode != 2 && skew_solve(s, mode == 0, FEM_GMRES_TOL, FEM_GMRES_MAX_IT, err) < 0)
                return -1;
        } else {
            if (mode == 2) {
                long before = s->stats.pcg_iterations;
                int rc = pcg_solve(s, err);
                cg_slow = s->stats.pcg_iterations - before > FEM_PCG_CHEAP;
                if (rc < 0) return -1;
                if (rc == 1) mode = 0;   /* the kept factor is too far off: refactorise */
            }
            if (mode != 2 && linear_solve(s, mode == 1, err)) return -1;
        }
        if (mode == 0) {
            s->factor_cm = sw.c_m;
            s->factor_ck = sw.c_k;
            s->factor_lin = s->lin_serial;
        }
        factorized = 1;
        double r_before = rnorm;
        double dmax = 0;
        for (int q = 0; q < s->neq; q++) {
            s->u0[q] = s->cur.u[s->dof_of_eq[q]];
            dmax = fmax(dmax, fabs(s->du[q]));
        }
        if (!isfinite(dmax)) { rnorm = NAN; break; }
        dfull = dmax;
        double alpha = 1.0, best_alpha = 1.0, best = INFINITY, trial_tol = tol;
        /* the residual a step may reach and still be taken: the last one, or in the pseudo
         * steps of fem_analysis_settle FEM_SETTLE_RESIDUAL_GROWTH times it */
        const double accept = s->fixed_load_factor >= 0.0 ? FEM_SETTLE_RESIDUAL_GROWTH : 1.0;
        for (int ls = 0; ls <= 4; ls++) {
            set_free_u(s, alpha);
            double r = evaluate(s, ns, &sw, &trial_tol);
            if (r < best) { best = r; best_alpha = alpha; }
            if (r < accept * rnorm || r <= trial_tol) { best = r; best_alpha = alpha; break; }
            alpha *= 0.5;
        }
        if (best_alpha != alpha) {   /* the last trial was not the best one: go back to it */
            set_free_u(s, best_alpha);
            best = evaluate(s, ns, &sw, &trial_tol);
        }
        s->stats.line_search_cuts += best_alpha < 1.0;
        /* refresh when the kept factorisation stops contracting fast, after a line-search cut,
         * and always in the second half of the iteration budget (full Newton) */
        refresh = cg_slow || best_alpha < 1.0 || best > set->contraction * r_before ||
                  2 * it >= set->max_iterations;
        rnorm = best;
        tol = trial_tol;
        dunorm = best_alpha * dmax;
    }
    s->stats.iterations = it - 1;
    s->stats.residual_norm = rnorm;
    /* where it failed: the free dof with the largest residual at the last iterate */
    int worst = -1;
    double worst_n = 0.0;
    for (int q = 0; q < s->neq; q++) {
        const int d = s->dof_of_eq[q];
        if (fabs(s->r[d]) > worst_n) { worst_n = fabs(s->r[d]); worst = d; }
    }
    char where[96] = "";
    if (worst >= 0)
        snprintf(where, sizeof where, "; largest residual %.3g N at node %d (dof %s)", worst_n, worst / 3,
                 dof_name(worst % 3));
    return nc_error_set(err, FEM_ERR_NEWTON,
                        "Newton did not converge in %d iterations (residual %.3g N, tolerance "
                        "%.3g N, last increment %.3g m, tolerance %.3g m%s)",
                        set->max_iterations, rnorm, tol, dunorm, set->displacement_tol_m, where);
}

/* The step converged: every element with history writes it at the solution, from the
 * history committed at the start of the step (cur.element_history = start's until now). */
static void commit_history(fem_analysis *s)
{
    const fem_model *m = s->m;
    if (m->history_count == 0) return;
    for (int b = 0; b < m->n_members; b++) {
        const fem_element_ops *ops = element_ops(m, m->member_first[b]);
        if (!ops->commit) continue;
        fem_element_ctx c;
        member_ctx(m, b, s->cur.u, s->start.element_history, &c);
        ops->commit(&c, s->cur.element_history + m->history_offset[b]);
    }
    fem_analysis_update_axial(s);
}

/* prescribed displacements at load factor lambda */
static void apply_supports(fem_analysis *s, double lambda)
{
    for (int i = 0; i < s->ndof; i++)
        if (s->m->fixed[i]) s->cur.u[i] = lambda * s->m->u_prescribed[i];
}

int fem_analysis_static(fem_analysis *s, double lambda, nc_error *err)
{
    state_copy(&s->start, &s->cur, s->ndof);
    apply_supports(s, lambda);
    newton_setup ns = {0, 0, 0.25, 0.5, 0, 0, lambda};
    if (newton(s, &ns, err)) {
        state_copy(&s->cur, &s->start, s->ndof);
        fem_analysis_update_axial(s);
        return nc_error_prefix(err, "%s: static load factor %g", s->m->source, lambda);
    }
    memset(s->cur.v, 0, (size_t)s->ndof * sizeof(double));
    memset(s->cur.a, 0, (size_t)s->ndof * sizeof(double));
    commit_history(s);
    s->cur.step++;
    s->cur.time_s = lambda;
    return 0;
}

/* The static equilibrium by pseudo-transient continuation: implicit steps from rest, each
 * M (u - u_n) / (beta h^2) + F_int(u) = F_ext (the velocity and acceleration set to 0 before
 * it), with h doubling after every converged step and quartered after a failed one. A plain
 * static Newton from the reference state fails on a barrier: its first iterations slacken
 * net cables and leave nodes that nothing holds (a singular matrix at 1 % of the load); the
 * mass term keeps every step's matrix regular, and as h grows it fades (at h = 1e4 s it is
 * 4e-8 N/m per kg of a node), so the last steps are Newton's on the equilibrium. */
#define FEM_SETTLE_H_MAX_S 1e4
#define FEM_SETTLE_MAX_STEPS 400

int fem_analysis_settle(fem_analysis *s, double lambda, int *iterations, int *steps,
                        nc_error *err)
{
    const fem_settings *set = &s->m->settings;
    const double time0 = s->cur.time_s;
    const long step0 = s->cur.step;
    double h = set->dt_s, last_move = INFINITY;
    int last_node = -1, rc = -1;
    *iterations = 0;
    *steps = 0;
    nc_error_clear(err);   /* what it holds at the end is this call's */
    s->fixed_load_factor = lambda;
    const fem_settle_watch *watch = &s->settle_watch;
    for (int k = 0; k < FEM_SETTLE_MAX_STEPS && rc < 0; k++) {
        if (watch->stop && *watch->stop) {
            nc_error_set(err, FEM_ERR_STOPPED, "%s: stopped by a signal while settling under "
                         "load factor %g (pseudo-time step %d)", s->m->source, lambda, k + 1);
            break;
        }
        memset(s->cur.v, 0, (size_t)s->ndof * sizeof(double));
        memset(s->cur.a, 0, (size_t)s->ndof * sizeof(double));
        const int failed = fem_analysis_step(s, h, err);
        *iterations += s->stats.iterations;
        (*steps)++;
        if (failed) {
            if (err->code != FEM_ERR_NEWTON) break;
            h *= 0.25;
            if (h < 1e-6 * set->dt_s) {
                nc_error_prefix(err, "no equilibrium found by pseudo-time steps");
                break;
            }
            continue;
        }
        last_move = 0.0;
        for (int q = 0; q < s->neq; q++) {
            const int dof = s->dof_of_eq[q];
            const double d = fabs(s->cur.u[dof] - s->start.u[dof]);
            if (d > last_move) {
                last_move = d;
                last_node = dof / 3;
            }
        }
        if (watch->on_step) watch->on_step(watch->ctx, *steps, h, last_move, last_node);
        if (h >= FEM_SETTLE_H_MAX_S && last_move <= set->displacement_tol_m) rc = 0;
        h = fmin(2.0 * h, FEM_SETTLE_H_MAX_S);
    }
    s->fixed_load_factor = -1.0;
    /* at its time and step again; at rest in equilibrium when it succeeded */
    s->cur.time_s = time0;
    s->cur.step = step0;
    if (rc < 0 && err->code != FEM_ERR_NEWTON && err->code != 0) return -1;
    if (rc < 0 && *steps >= FEM_SETTLE_MAX_STEPS)
        return nc_error_set(err, FEM_ERR_NEWTON, "%s: no equilibrium under load factor %g after %d "
                            "pseudo-time steps: node %d still moved %.3g m in the last one "
                            "(displacement_tolerance_m %g)", s->m->source, lambda,
                            FEM_SETTLE_MAX_STEPS, last_node, last_move, set->displacement_tol_m);
    if (rc < 0) return -1;
    nc_error_clear(err);   /* a pseudo step that failed on the way is not a failure */
    memset(s->cur.v, 0, (size_t)s->ndof * sizeof(double));
    memset(s->cur.a, 0, (size_t)s->ndof * sizeof(double));
    return 0;
}

int fem_analysis_initial_equilibrium(fem_analysis *s, int *iterations, int *steps,
                                     nc_error *err)
{
    if (fem_analysis_settle(s, fem_analysis_load_factor(s, 0.0), iterations, steps, err))
        return nc_error_prefix(err, "analysis.initial_state \"static\": the equilibrium under "
                                    "the loads at t = 0");
    return 0;
}

static void method_weights(const fem_settings *set, double *beta, double *gamma, double *am,
                           double *af)
{
    switch (set->integrator) {
    case FEM_GENERALIZED_ALPHA: {
        double r = set->rho_inf;   /* Chung & Hulbert (1993) */
        *am = (2.0 * r - 1.0) / (r + 1.0);
        *af = r / (r + 1.0);
        *gamma = 0.5 - *am + *af;
        *beta = 0.25 * (1.0 - *am + *af) * (1.0 - *am + *af);
        break;
    }
    case FEM_BOSSAK:               /* Wood, Bossak & Zienkiewicz (1980) */
        *am = set->alpha_b;
        *af = 0.0;
        *gamma = 0.5 - *am;
        *beta = 0.25 * (1.0 - *am) * (1.0 - *am);
        break;
    default:
        *am = *af = 0.0;
        *beta = set->beta;
        *gamma = set->gamma;
    }
}

/* C_K = kappa K_T at the state (u, hist) into damping_K, and F_int(u) into fd [ndof]. */
static void freeze_damping(fem_analysis *s, const double *u, const double *hist, double *fd)
{
    const fem_model *m = s->m;
    const double kappa = m->kappa_s;
    memset(fd, 0, (size_t)s->ndof * sizeof *fd);
    for (int b = 0; b < m->n_members; b++) {
        const int first = m->member_first[b];
        const fem_element_ops *ops = element_ops(m, first);
        double *C = s->damping_K + s->damping_at[b];
        const size_t n_c = s->damping_at[b + 1] - s->damping_at[b];
        fem_element_ctx ctx;
        member_ctx(m, b, u, hist, &ctx);
        double pair_f[3], *f = ops->chain ? s->chain_f : pair_f;
        int slack;
        if (ops->chain) ops->chain_response(&ctx, f, C, s->chain_v);   /* chain_v: axial, unused */
        else ops->pair_response(&ctx, f, C, &slack);
        for (size_t i = 0; i < n_c; i++) C[i] *= kappa;
        const int r = s->lr_of_member[b];
        if (r >= 0) s->lr_c_frozen[r] = kappa * ops->chain_rank_one(&ctx, s->lr_gc + s->lr_at[r]);
        add_member_force(m, b, f, fd);
    }
}

/* cur.fc = the coupling force of the last evaluation (at the solution) */
static void store_coupling_force(fem_analysis *s)
{
    if (s->lin.active)
        for (int i = 0; i < s->ndof; i++) s->cur.fc[i] = s->f_coupling[i] + s->lin.df[i];
    else
        memcpy(s->cur.fc, s->f_coupling, (size_t)s->ndof * sizeof(double));
}

int fem_analysis_initial_acceleration(fem_analysis *s, nc_error *err)
{
    const fem_model *m = s->m;
    double lambda = fem_analysis_load_factor(s, s->cur.time_s);
    apply_supports(s, lambda);
    /* matrix = M (c_m = 1, c_k = 0); residual without inertia */
    s->factor_cm = 1.0;
    s->factor_ck = 0.0;
    s->factor_lin = s->lin_serial;
    double tau = m->tau_per_s;
    for (int i = 0; i < s->ndof; i++) s->w[i] = tau * s->cur.v[i];
    if (s->damping_K) freeze_damping(s, s->cur.u, s->cur.element_history, s->damping_start);
    const step_weights mass_only = {.c_m = 1, .c_k = 0, .c_c = 0, .l_k = 0, .l_c = 0, .wf = 1,
                                    .l_w = 1};
    assemble(s, lambda, &mass_only, s->w, s->cur.v, NULL, 1, s->cur.element_history);
    if (linear_solve(s, 0, err)) return nc_error_prefix(err, "%s: initial acceleration (mass matrix)", m->source);
    memset(s->cur.a, 0, (size_t)s->ndof * sizeof(double));
    for (int q = 0; q < s->neq; q++) s->cur.a[s->dof_of_eq[q]] = s->du[q];
    store_coupling_force(s);
    return 0;
}

/* y = M x (all dofs) */
static void mass_multiply(const fem_analysis *s, const double *x, double *y)
{
    const fem_model *m = s->m;
    memset(y, 0, (size_t)s->ndof * sizeof *y);
    for (int e = 0; e < m->n_elements; e++) {
        const int k = 3 * m->conn[2 * e], l = 3 * m->conn[2 * e + 1];
        double m11, m12;
        fem_element_bar_mass(m->rhoA[e], m->L0[e], m->lumped_mass, &m11, &m12);
        for (int c = 0; c < 3; c++) {
            y[k + c] += m11 * x[k + c] + m12 * x[l + c];
            y[l + c] += m12 * x[k + c] + m11 * x[l + c];
        }
    }
}

#define FEM_MASS_CG_TOL 1e-14   /* relative residual of the mass solve */
#define FEM_MASS_CG_MAX_IT 200

/* start.a += M^-1 (to - from) on the free dofs (from NULL: zero): at the start of a step the
 * coupling force changes at t_n from the force a_n was computed with (start.fc) to this
 * step's (f_coupling), and the trapezoidal (Newmark) and alpha-weighted updates then use it
 * over the whole step; after a step solved with an interface linearisation, by the
 * linearisation's force change (lin.df), which acts over the whole step as well.
 * Jacobi-preconditioned CG, matrix free: M of bar elements is well conditioned (spectrum of
 * D^-1 M within [0.5, 1.5]), so this converges in a few tens of iterations (1 with a lumped
 * mass). */
static int shift_start_acceleration(fem_analysis *s, const double *to, const double *from,
                                    nc_error *err)
{
    const int n = s->neq;
    double *r = s->cg_r, *z = s->cg_z, *p = s->cg_p, *q = s->cg_q, *x = s->du;
    double b2 = 0;
    for (int e = 0; e < n; e++) {
        int d = s->dof_of_eq[e];
        r[e] = to[d] - (from ? from[d] : 0.0);
        b2 += r[e] * r[e];
        x[e] = 0;
    }
    if (b2 == 0) return 0;
    for (int e = 0; e < n; e++) { z[e] = r[e] / s->mass_diag[e]; p[e] = z[e]; }
    double rz = dot(r, z, n);
    const double tol2 = FEM_MASS_CG_TOL * FEM_MASS_CG_TOL * b2;
    int it = 0;
    for (; it < FEM_MASS_CG_MAX_IT && dot(r, r, n) > tol2; it++) {
        memset(s->mass_x, 0, (size_t)s->ndof * sizeof(double));
        for (int e = 0; e < n; e++) s->mass_x[s->dof_of_eq[e]] = p[e];
        mass_multiply(s, s->mass_x, s->mass_y);
        for (int e = 0; e < n; e++) q[e] = s->mass_y[s->dof_of_eq[e]];
        double step = rz / dot(p, q, n);
        for (int e = 0; e < n; e++) { x[e] += step * p[e]; r[e] -= step * q[e]; }
        for (int e = 0; e < n; e++) z[e] = r[e] / s->mass_diag[e];
        double rz_new = dot(r, z, n);
        for (int e = 0; e < n; e++) p[e] = z[e] + (rz_new / rz) * p[e];
        rz = rz_new;
    }
    if (it == FEM_MASS_CG_MAX_IT)
        return nc_error_set(err, 3, "mass-matrix solve for the coupling-load shift did not converge in %d iterations",
                            FEM_MASS_CG_MAX_IT);
    for (int e = 0; e < n; e++) s->start.a[s->dof_of_eq[e]] += x[e];
    return 0;
}

/* Undoes begin_dynamic_step's shift of the start acceleration, before the state returns to
 * the start of the step. */
static void unshift_start(fem_analysis *s)
{
    if (s->m->settings.coupling_load_constant)
        memcpy(s->start.a, s->a_unshifted, (size_t)s->ndof * sizeof(double));
}

/* The start of a dynamic step: start state saved, the step's damping C_K frozen (and the
 * damping force a_n stands for, start.fd - F_int(u_n), kept for the energy balance), the
 * start acceleration shifted for a step-constant coupling load, integrator weights and the
 * end-of-step load factor in ns. */
static int begin_dynamic_step(fem_analysis *s, double dt_s, newton_setup *ns, nc_error *err)
{
    const fem_settings *set = &s->m->settings;
    state_copy(&s->start, &s->cur, s->ndof);
    if (s->damping_K) {
        freeze_damping(s, s->start.u, s->start.element_history, s->damping_start);
        for (int i = 0; i < s->ndof; i++) s->damping_start[i] = s->start.fd[i] - s->damping_start[i];
    }
    if (set->coupling_load_constant) {
        memcpy(s->a_unshifted, s->start.a, (size_t)s->ndof * sizeof(double));
        if (shift_start_acceleration(s, s->f_coupling, s->start.fc, err)) {
            unshift_start(s);
            return nc_error_prefix(err, "%s: step %ld", s->m->source, s->start.step);
        }
    }
    *ns = (newton_setup){1, dt_s, 0, 0, 0, 0, 0};
    method_weights(set, &ns->beta, &ns->gamma, &ns->alpha_m, &ns->alpha_f);
    ns->lambda = fem_analysis_load_factor(s, s->cur.time_s + dt_s);
    return 0;
}

int fem_analysis_step(fem_analysis *s, double dt_s, nc_error *err)
{
    return fem_analysis_step_from(s, dt_s, NULL, err);
}

int fem_analysis_step_from(fem_analysis *s, double dt_s, const double *u_guess, nc_error *err)
{
    newton_setup ns;
    if (begin_dynamic_step(s, dt_s, &ns, err)) return -1;
    double t1 = s->cur.time_s + dt_s;
    /* predictor: the start-of-step displacement (for these stiff, strongly nonlinear nets it
     * did better than the constant-acceleration predictor) or the caller's guess, supports
     * at their end value */
    apply_supports(s, ns.lambda);
    if (u_guess)
        for (int q = 0; q < s->neq; q++) s->cur.u[s->dof_of_eq[q]] = u_guess[s->dof_of_eq[q]];
    /* with a step-constant coupling load the linearisation's force change acts over the
     * whole step too: Newton solved for u with its weight l_w (newton_weights), and a_n, then
     * a_n+1 and v_n+1, follow it here (the top of this file) */
    int rc = newton(s, &ns, err);
    if (rc == 0 && s->m->settings.coupling_load_constant && s->lin.active) {
        rc = shift_start_acceleration(s, s->lin.df, NULL, err);
        if (rc == 0) update_kinematics(s, ns.dt, ns.beta, ns.gamma);
    }
    if (rc) {
        /* leave the state as it was before the call */
        unshift_start(s);
        state_copy(&s->cur, &s->start, s->ndof);
        fem_analysis_update_axial(s);
        return nc_error_prefix(err, "%s: step %ld (t = %g s -> %g s)", s->m->source,
                               s->start.step, s->start.time_s, t1);
    }
    s->cur.time_s = t1;
    s->cur.step = s->start.step + 1;
    store_coupling_force(s);
    commit_history(s);
    return 0;
}

int fem_analysis_step_residual(fem_analysis *s, double dt_s, const double *u_end, double *r,
                               nc_error *err)
{
    newton_setup ns;
    if (begin_dynamic_step(s, dt_s, &ns, err)) return -1;
    for (int q = 0; q < s->neq; q++) s->cur.u[s->dof_of_eq[q]] = u_end[s->dof_of_eq[q]];
    apply_supports(s, ns.lambda);
    const step_weights sw = newton_weights(s->m, &ns);
    double tol;
    evaluate(s, &ns, &sw, &tol);
    memcpy(r, s->r, (size_t)s->ndof * sizeof(double));
    unshift_start(s);
    state_copy(&s->cur, &s->start, s->ndof);
    fem_analysis_update_axial(s);
    return 0;
}

void fem_analysis_tangent_apply(const fem_analysis *s, const double *x, double *y)
{
    fem_sparse_matvec(&s->K, x, y);
    rank_one_apply(s, x, y);
}

int fem_analysis_set_linearisation(fem_analysis *s, const double *u_ref, const double *v_ref,
                                   int n_blocks, const int *block_nodes, const double *K_blocks,
                                   const double *C_blocks, nc_error *err)
{
    s->lin_serial++;
    /* a particle touching nodes of different elements couples them: grow the pattern */
    if (grow_pattern(s, n_blocks, block_nodes, err) ||
        fem_ijac_set(&s->lin, s->ndof, s->eq, &s->K, u_ref, v_ref, n_blocks, block_nodes,
                     K_blocks, C_blocks, err))
        return nc_error_prefix(err, "%s", s->m->source);
    return 0;
}

void fem_analysis_clear_linearisation(fem_analysis *s)
{
    if (s->lin.active) s->lin_serial++;
    fem_ijac_clear(&s->lin);
}

int fem_analysis_compliance(fem_analysis *s, int n, const int *dofs, double *S, int n_rows,
                            const int *row_dofs, double *S_rows, nc_error *err)
{
    const size_t nn = (size_t)n * (size_t)n;
    if (!S_rows) n_rows = 0;
    /* SB: n rows of the compliance dofs, then n_rows of row_dofs (row-major) */
    double *SB = calloc(nn + (size_t)n_rows * (size_t)n, sizeof *SB);
    double *M = calloc(nn, sizeof *M), *rhs = calloc((size_t)s->neq, sizeof *rhs);
    int *pos = malloc((size_t)s->ndof * sizeof *pos), *ipiv = malloc((size_t)n * sizeof *ipiv);
    int rc = -1;
    if (!SB || !M || !rhs || !pos || !ipiv) {
        nc_error_set(err, 1, "out of memory for the interface compliance");
        goto done;
    }
    /* GMRES only for what the factor leaves out (a skew part, rank-one terms) */
    const int gmres = (s->lin.active && s->lin.has_skew) || s->lr_members > 0;
    if (gmres && fem_gmres_reserve(&s->gmres, s->neq, FEM_GMRES_MAX_IT, err)) goto done;
    for (int d = 0; d < s->ndof; d++) pos[d] = -1;
    for (int a = 0; a < n; a++) pos[dofs[a]] = a;
    s->skew_lk = s->last_lk;
    s->skew_lc = s->last_lc;
    /* the matrix holds the tangent at the solution (its last evaluation): a fresh factor
     * leaves GMRES the skew part and the rank-one terms */
    if (factorize(s, err)) goto done;
    s->factor_cm = s->last_cm;
    s->factor_ck = s->last_ck;
    s->factor_lin = s->lin_serial;
    /* S_B: columns of the solved step matrix's inverse (the linearisation in it) */
    for (int b = 0; b < n; b++) {
        const int qb = s->eq[dofs[b]];
        if (qb < 0) continue;
        memset(rhs, 0, (size_t)s->neq * sizeof *rhs);
        rhs[qb] = 1.0;
        int its = 0;
        if (gmres ? fem_gmres_solve(&s->gmres, apply_tangent, apply_factor, s, rhs, s->du,
                                    FEM_GMRES_TOL, FEM_GMRES_MAX_IT, &its, err) < 0
                  : fem_sparse_solve(&s->K, rhs, s->du, err) != 0)
            goto done;
        for (int a = 0; a < n; a++) {
            const int qa = s->eq[dofs[a]];
            SB[(size_t)a * n + b] = qa < 0 ? 0.0 : s->du[qa];
        }
        for (int a = 0; a < n_rows; a++) {
            const int qa = s->eq[row_dofs[a]];
            SB[(size_t)(n + a) * n + b] = qa < 0 ? 0.0 : s->du[qa];
        }
    }
    /* Kd: the linearisation's tangent on the dofs; M = I - Kd S_B, S = S_B M^-1 */
    double *Kd = S;
    memset(Kd, 0, nn * sizeof *Kd);
    if (s->lin.active)
        for (int k = 0; k < s->lin.n_blocks; k++) {
            const int ni = s->lin.nodes[2 * k], nj = s->lin.nodes[2 * k + 1];
            for (int r = 0; r < 3; r++)
                for (int c = 0; c < 3; c++) {
                    const int a = pos[3 * ni + r], b = pos[3 * nj + c];
                    if (a < 0 || b < 0 || s->eq[3 * ni + r] < 0 || s->eq[3 * nj + c] < 0) continue;
                    Kd[(size_t)a * n + b] += s->last_lk * s->lin.K[9 * k + 3 * r + c] +
                                             (s->lin.C ? s->last_lc * s->lin.C[9 * k + 3 * r + c] : 0.0);
                }
        }
    for (int a = 0; a < n; a++)
        for (int b = 0; b < n; b++) {
            double sum = a == b ? 1.0 : 0.0;
            for (int c = 0; c < n; c++) sum -= Kd[(size_t)a * n + c] * SB[(size_t)c * n + b];
            M[(size_t)a * n + b] = sum;
        }
    /* row-major M read as column-major is M^T: M^T X = S_B^T gives X = S^T column-major,
     * which is S row-major; the rows of row_dofs take the same M^-1 (Woodbury: the
     * structure alone answers a force on the compliance dofs with A^-1 P M^-1 everywhere) */
    int info = 0, n_rhs = n + n_rows;
    dgesv_(&n, &n_rhs, M, &n, ipiv, SB, &n, &info);
    if (info != 0) {
        nc_error_set(err, 1, "interface compliance: singular system (LAPACK info %d)", info);
        goto done;
    }
    for (size_t k = 0; k < nn; k++) S[k] = s->last_lw * SB[k];
    for (size_t k = 0; k < (size_t)n_rows * (size_t)n; k++) S_rows[k] = s->last_lw * SB[nn + k];
    rc = 0;
done:
    free(SB); free(M); free(rhs); free(pos); free(ipiv);
    return rc;
}

int fem_analysis_save(fem_analysis *s, nc_error *err)
{
    state_copy(&s->saved, &s->cur, s->ndof);
    s->has_saved = 1;
    s->saved_factor_cm = s->factor_cm;
    s->saved_factor_ck = s->factor_ck;
    s->saved_factor_lin = s->factor_lin;
    return fem_sparse_save_factor(&s->K, err);
}

int fem_analysis_restore(fem_analysis *s, nc_error *err)
{
    if (!s->has_saved) return nc_error_set(err, 1, "restore requested but no start-of-step state was saved");
    state_copy(&s->cur, &s->saved, s->ndof);
    fem_analysis_update_axial(s);
    s->factor_cm = s->saved_factor_cm;
    s->factor_ck = s->saved_factor_ck;
    s->factor_lin = s->saved_factor_lin;
    return fem_sparse_restore_factor(&s->K, err);
}

void fem_analysis_update_axial(fem_analysis *s)
{
    const fem_model *m = s->m;
    int slack = 0;
    for (int b = 0; b < m->n_members; b++) {
        const int e = m->member_first[b];
        const fem_element_ops *ops = element_ops(m, e);
        fem_element_ctx c;
        member_ctx(m, b, s->cur.u, s->cur.element_history, &c);
        if (ops->chain) {
            slack += ops->chain_response(&c, s->chain_f, NULL, s->axial + e);
            continue;
        }
        double f[3], Kb[9];
        int sl;
        s->axial[e] = ops->pair_response(&c, f, Kb, &sl);
        slack += sl;
    }
    s->stats.slack_elements = slack;
}

void fem_analysis_node_balance(const fem_analysis *s, double lambda, double *f)
{
    /* the order of operations of the reactions before the element seam, so reactions are
     * unchanged for cables */
    const fem_model *m = s->m;
    const double *u = s->cur.u, *v = s->cur.v, *a = s->cur.a;
    const double tau = m->tau_per_s;
    for (int i = 0; i < 3 * m->n_nodes; i++) f[i] = -lambda * s->f_model[i] - s->f_coupling[i];
    for (int b = 0; b < m->n_members; b++) {
        const int first = m->member_first[b];
        const fem_element_ops *ops = element_ops(m, first);
        fem_element_ctx ctx;
        member_ctx(m, b, u, s->cur.element_history, &ctx);
        if (ops->chain) {
            const int n = ctx.count + 1;
            double *fc = s->chain_f, *cv = s->chain_v;
            /* the work arrays are scratch: nothing of the state lives there */
            ops->chain_response(&ctx, fc, NULL, cv);
            if (s->damping_K) member_damping_force(s, b, v, cv);
            for (int j = 0; j < n; j++) {
                const int node = 3 * chain_node(m, first, ctx.count, j);
                for (int c = 0; c < 3; c++) f[node + c] += fc[3 * j + c] + (s->damping_K ? cv[3 * j + c] : 0.0);
            }
        }
        for (int e = first; e < m->member_first[b + 1]; e++) {
            const int k = 3 * m->conn[2 * e], l = 3 * m->conn[2 * e + 1];
            double fl[3] = {0, 0, 0}, Kb[9] = {0}, cv[3] = {0, 0, 0};
            int slack;
            if (!ops->chain) ops->pair_response(&ctx, fl, Kb, &slack);
            if (!ops->chain && s->damping_K) member_damping_force(s, b, v, cv);
            double m11, m12;
            fem_element_bar_mass(m->rhoA[e], m->L0[e], m->lumped_mass, &m11, &m12);
            for (int c = 0; c < 3; c++) {
                f[l + c] += fl[c] + cv[c];
                f[k + c] -= fl[c] + cv[c];
                double wk = a[k + c] + tau * v[k + c], wl = a[l + c] + tau * v[l + c];
                f[k + c] += m11 * wk + m12 * wl;
                f[l + c] += m12 * wk + m11 * wl;
            }
        }
    }
}

int fem_analysis_element_history_output(const fem_analysis *s, double *stroke, double *dissipated)
{
    const fem_model *m = s->m;
    int any = 0;
    for (int b = 0; b < m->n_members; b++) {
        const int first = m->member_first[b];
        const fem_element_ops *ops = element_ops(m, first);
        fem_element_ctx c;
        member_ctx(m, b, s->cur.u, s->cur.element_history, &c);
        double st = ops->stroke ? ops->stroke(&c) : 0.0;
        double di = ops->dissipated ? ops->dissipated(&c) : 0.0;
        any |= ops->stroke || ops->dissipated;
        for (int e = first; e < m->member_first[b + 1]; e++) {
            if (stroke) stroke[e] = st;
            if (dissipated) dissipated[e] = di;
        }
    }
    return any;
}

static void method_weights(const fem_settings *set, double *beta, double *gamma, double *am,
                           double *af);

/* Kinetic and strain energy of the state u, v with history hist, and the energy the
 * elements have dissipated up to that history (NULL: not wanted). */
static void state_energy(const fem_analysis *s, const double *u, const double *v,
                         const double *hist, double *kinetic, double *strain, double *dissipated)
{
    const fem_model *m = s->m;
    double T = 0, W = 0, D = 0;
    for (int e = 0; e < m->n_elements; e++) {
        const int k = 3 * m->conn[2 * e], l = 3 * m->conn[2 * e + 1];
        double m11, m12;
        fem_element_bar_mass(m->rhoA[e], m->L0[e], m->lumped_mass, &m11, &m12);
        for (int c = 0; c < 3; c++)
            T += 0.5 * (m11 * (v[k + c] * v[k + c] + v[l + c] * v[l + c]) + 2.0 * m12 * v[k + c] * v[l + c]);
    }
    for (int b = 0; b < m->n_members; b++) {
        const fem_element_ops *ops = element_ops(m, m->member_first[b]);
        fem_element_ctx c;
        member_ctx(m, b, u, hist, &c);
        W += ops->strain_energy(&c);
        if (ops->dissipated) D += ops->dissipated(&c);
    }
    *kinetic = T;
    *strain = W;
    if (dissipated) *dissipated = D;
}

double fem_analysis_energy(const fem_analysis *s, double *kinetic, double *strain)
{
    double T, W;
    state_energy(s, s->cur.u, s->cur.v, s->cur.element_history, &T, &W, NULL);
    if (kinetic) *kinetic = T;
    if (strain) *strain = W;
    return T + W;
}

/* f = C_K v [ndof], the damping force of the step's C_K at the velocities v */
static void damping_force(const fem_analysis *s, const double *v, double *f)
{
    const fem_model *m = s->m;
    memset(f, 0, (size_t)s->ndof * sizeof *f);
    for (int b = 0; b < m->n_members; b++) {
        double pair_cv[3], *cv = element_ops(m, m->member_first[b])->chain ? s->chain_v : pair_cv;
        member_damping_force(s, b, v, cv);
        add_member_force(m, b, cv, f);
    }
}

int fem_analysis_step_energy(const fem_analysis *s, int inertia, fem_step_energy *e)
{
    const fem_model *m = s->m;
    const double dt = s->cur.time_s - s->start.time_s;
    if (!(dt > 0.0)) return -1;
    double T0 = 0, W0, D0, T1 = 0, W1, D1;
    state_energy(s, s->start.u, s->start.v, s->start.element_history, &T0, &W0, &D0);
    state_energy(s, s->cur.u, s->cur.v, s->cur.element_history, &T1, &W1, &D1);
    if (!inertia) T0 = T1 = 0.0;
    /* quasi-static coupling solves at the full load (fem_analysis_static(s, 1, ...)) */
    const double lam0 = inertia ? fem_analysis_load_factor(s, s->start.time_s) : 1.0;
    const double lam1 = inertia ? fem_analysis_load_factor(s, s->cur.time_s) : 1.0;
    /* the coupling force the start-of-step acceleration stands for: with "step_constant" it
     * was shifted to this step's force */
    const double *fc0 = m->settings.coupling_load_constant ? s->cur.fc : s->start.fc;
    /* the loads' weights of the velocity update v_n+1 - v_n = dt ((1 - gamma) a_n + gamma
     * a_n+1): the impulse the integrator takes from the start and the end force */
    double beta, gamma = 0.5, am, af;
    if (inertia) method_weights(&m->settings, &beta, &gamma, &am, &af);
    double load_work = 0, coupling_work = 0, v0 = 0, v1 = 0;
    for (int q = 0; q < s->neq; q++) {
        int i = s->dof_of_eq[q];
        double du = s->cur.u[i] - s->start.u[i];
        load_work += 0.5 * (lam0 + lam1) * s->f_model[i] * du;
        coupling_work += ((1.0 - gamma) * fc0[i] + gamma * s->cur.fc[i]) * du;
        v0 -= lam0 * s->f_model[i] * s->start.u[i];
        v1 -= lam1 * s->f_model[i] * s->cur.u[i];
    }
    /* Rayleigh: tau M at the mid-step velocity; C_K = kappa K_T(u_n) as the integrator applies
     * it, like the coupling force: the damping force a_n stands for (the previous step's C_K)
     * and the end's with the load weights */
    double rayleigh = 0;
    if (inertia && (m->tau_per_s != 0.0 || s->damping_K)) {
        for (int e = 0; e < m->n_elements; e++) {
            const int k = 3 * m->conn[2 * e], l = 3 * m->conn[2 * e + 1];
            double vk[3], vl[3], m11, m12;
            for (int c = 0; c < 3; c++) {
                vk[c] = 0.5 * (s->start.v[k + c] + s->cur.v[k + c]);
                vl[c] = 0.5 * (s->start.v[l + c] + s->cur.v[l + c]);
            }
            fem_element_bar_mass(m->rhoA[e], m->L0[e], m->lumped_mass, &m11, &m12);
            for (int c = 0; c < 3; c++)
                rayleigh += m->tau_per_s * (m11 * (vk[c] * vk[c] + vl[c] * vl[c]) + 2.0 * m12 * vk[c] * vl[c]);
        }
        rayleigh *= dt;
        if (s->damping_K) {
            damping_force(s, s->cur.v, s->damping_end);
            for (int q = 0; q < s->neq; q++) {
                int i = s->dof_of_eq[q];
                rayleigh += ((1.0 - gamma) * s->damping_start[i] + gamma * s->damping_end[i]) *
                            (s->cur.u[i] - s->start.u[i]);
            }
        }
    }
    e->kinetic_j = T1;
    e->strain_j = W1;
    e->load_potential_j = v1;
    e->load_work_j = load_work;
    e->load_input_j = load_work + (v1 - v0);
    e->coupling_work_j = coupling_work;
    e->rayleigh_j = rayleigh;
    e->element_dissipation_j = D1 - D0;
    e->element_dissipated_j = D1;
    e->numerical_j = load_work + coupling_work - (T1 + W1 - T0 - W0) - rayleigh - (D1 - D0);
    return 0;
}
