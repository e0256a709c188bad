/* fem_checkpoint — the table of what a FEM checkpoint holds, the model's identity and the
 * rebuilt parts (see fem_checkpoint.h); the file itself is common/nc_checkpoint's. */
#include "fem_checkpoint.h"

#include "nc_file.h"

#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define CK_FORMAT 3   /* layout version of the file (2: the per-set peak forces; 3: a sliding
                         rope's rank-one term no longer in the matrix and its factors) */

/* ---- the table ---------------------------------------------------------------------- */

/* Sizes of the variable parts: written first, and read first on load (they size the rest). */
typedef struct ck_sizes {
    int n_pairs;          /* extra node pairs of the pattern */
    int lin_active, lin_blocks;
    int nnz;              /* stored matrix entries */
    int have_factor, use_lu, saved_factor;
    int n_out;            /* output rows */
} ck_sizes;

/* What is rebuilt from its definition: save points these at the live arrays, load at
 * buffers of its own. */
typedef struct ck_rebuilt {
    int *pairs;
    int *lin_nodes;
    double *lin_K, *lin_C, *lin_u, *lin_v;
    double *factor_x, *saved_factor_x;
} ck_rebuilt;

static void state_entries(nc_ckpt_table *t, const char *group, fem_state *st, size_t ndof)
{
    char name[64];
    snprintf(name, sizeof name, "analysis/%s/time_s", group);
    nc_ckpt_add(t, NULL, name, NC_CKPT_F64, &st->time_s, 1);
    snprintf(name, sizeof name, "analysis/%s/step", group);
    nc_ckpt_add(t, NULL, name, NC_CKPT_LONG, &st->step, 1);
    snprintf(name, sizeof name, "analysis/%s/u", group);
    nc_ckpt_add(t, NULL, name, NC_CKPT_F64, st->u, ndof);
    snprintf(name, sizeof name, "analysis/%s/v", group);
    nc_ckpt_add(t, NULL, name, NC_CKPT_F64, st->v, ndof);
    snprintf(name, sizeof name, "analysis/%s/a", group);
    nc_ckpt_add(t, NULL, name, NC_CKPT_F64, st->a, ndof);
    snprintf(name, sizeof name, "analysis/%s/fd", group);
    nc_ckpt_add(t, NULL, name, NC_CKPT_F64, st->fd, ndof);
    snprintf(name, sizeof name, "analysis/%s/fc", group);
    nc_ckpt_add(t, NULL, name, NC_CKPT_F64, st->fc, ndof);
    /* the element types' history: brake strokes and dissipated energies */
    snprintf(name, sizeof name, "analysis/%s/element_history", group);
    nc_ckpt_add(t, NULL, name, NC_CKPT_F64, st->element_history, (size_t)st->n_history);
}

static void size_entries(nc_ckpt_table *t, ck_sizes *z)
{
    nc_ckpt_add(t, NULL, "pattern/n_pairs", NC_CKPT_INT, &z->n_pairs, 1);
    nc_ckpt_add(t, NULL, "linearisation/active", NC_CKPT_INT, &z->lin_active, 1);
    nc_ckpt_add(t, NULL, "linearisation/n_blocks", NC_CKPT_INT, &z->lin_blocks, 1);
    nc_ckpt_add(t, NULL, "factor/nnz", NC_CKPT_INT, &z->nnz, 1);
    nc_ckpt_add(t, NULL, "factor/current", NC_CKPT_INT, &z->have_factor, 1);
    nc_ckpt_add(t, NULL, "factor/lu", NC_CKPT_INT, &z->use_lu, 1);
    nc_ckpt_add(t, NULL, "factor/saved", NC_CKPT_INT, &z->saved_factor, 1);
    nc_ckpt_add(t, NULL, "output/rows", NC_CKPT_INT, &z->n_out, 1);
}

/* The analysis state. Not in it, because every solve writes them before it reads them:
 * the residual and work vectors (r, rhs, du, u0, w, cg_*, mass_x, mass_y, a_unshifted), the
 * matrix values (reassembled at the first evaluation), lin.df. Derived once from the model
 * at init: eq, dof_of_eq, f_model, mass_diag. */
static void analysis_entries(nc_ckpt_table *t, fem_analysis *s)
{
    const size_t ndof = (size_t)s->ndof;
    fem_stats *st = &s->stats;
    state_entries(t, "cur", &s->cur, ndof);
    state_entries(t, "start", &s->start, ndof);          /* start of the last step solved */
    state_entries(t, "saved", &s->saved, ndof);          /* BEGIN_STEP's copy */
    nc_ckpt_add(t, NULL, "analysis/has_saved", NC_CKPT_INT, &s->has_saved, 1);
    nc_ckpt_add(t, NULL, "analysis/f_coupling", NC_CKPT_F64, s->f_coupling, ndof);
    nc_ckpt_add(t, NULL, "analysis/axial", NC_CKPT_F64, s->axial, (size_t)s->m->n_elements);
    /* which matrix form the kept factorisations are of (modified Newton reuses them) */
    nc_ckpt_add(t, NULL, "analysis/factor_cm", NC_CKPT_F64, &s->factor_cm, 1);
    nc_ckpt_add(t, NULL, "analysis/factor_ck", NC_CKPT_F64, &s->factor_ck, 1);
    nc_ckpt_add(t, NULL, "analysis/saved_factor_cm", NC_CKPT_F64, &s->saved_factor_cm, 1);
    nc_ckpt_add(t, NULL, "analysis/saved_factor_ck", NC_CKPT_F64, &s->saved_factor_ck, 1);
    nc_ckpt_add(t, NULL, "analysis/lin_serial", NC_CKPT_LONG, &s->lin_serial, 1);
    nc_ckpt_add(t, NULL, "analysis/factor_lin", NC_CKPT_LONG, &s->factor_lin, 1);
    nc_ckpt_add(t, NULL, "analysis/saved_factor_lin", NC_CKPT_LONG, &s->saved_factor_lin, 1);
    nc_ckpt_add(t, NULL, "analysis/factor_mode", NC_CKPT_INT, &s->factor_mode, 1);
    /* statistics: the summary and the SOLVE replies report them */
    nc_ckpt_add(t, NULL, "stats/iterations", NC_CKPT_INT, &st->iterations, 1);
    nc_ckpt_add(t, NULL, "stats/residual_norm", NC_CKPT_F64, &st->residual_norm, 1);
    nc_ckpt_add(t, NULL, "stats/increment_norm", NC_CKPT_F64, &st->increment_norm, 1);
    nc_ckpt_add(t, NULL, "stats/slack_elements", NC_CKPT_INT, &st->slack_elements, 1);
    nc_ckpt_add(t, NULL, "stats/assemblies", NC_CKPT_LONG, &st->assemblies, 1);
    nc_ckpt_add(t, NULL, "stats/factorizations", NC_CKPT_LONG, &st->factorizations, 1);
    nc_ckpt_add(t, NULL, "stats/lu_factorizations", NC_CKPT_LONG, &st->lu_factorizations, 1);
    nc_ckpt_add(t, NULL, "stats/solves", NC_CKPT_LONG, &st->solves, 1);
    nc_ckpt_add(t, NULL, "stats/line_search_cuts", NC_CKPT_LONG, &st->line_search_cuts, 1);
    nc_ckpt_add(t, NULL, "stats/pattern_growths", NC_CKPT_LONG, &st->pattern_growths, 1);
    nc_ckpt_add(t, NULL, "stats/pcg_solves", NC_CKPT_LONG, &st->pcg_solves, 1);
    nc_ckpt_add(t, NULL, "stats/pcg_iterations", NC_CKPT_LONG, &st->pcg_iterations, 1);
    nc_ckpt_add(t, NULL, "stats/pcg_failures", NC_CKPT_LONG, &st->pcg_failures, 1);
    nc_ckpt_add(t, NULL, "stats/roundoff_converged", NC_CKPT_LONG, &st->roundoff_converged, 1);
    nc_ckpt_add(t, NULL, "stats/gmres_solves", NC_CKPT_LONG, &st->gmres_solves, 1);
    nc_ckpt_add(t, NULL, "stats/gmres_iterations", NC_CKPT_LONG, &st->gmres_iterations, 1);
    nc_ckpt_add(t, NULL, "stats/gmres_failures", NC_CKPT_LONG, &st->gmres_failures, 1);
    nc_ckpt_add(t, NULL, "stats/ldlt_switch_step", NC_CKPT_LONG, &st->ldlt_switch_step, 1);
    nc_ckpt_add(t, NULL, "stats/assembly_s", NC_CKPT_F64, &st->assembly_s, 1);
    nc_ckpt_add(t, NULL, "stats/factor_s", NC_CKPT_F64, &st->factor_s, 1);
    nc_ckpt_add(t, NULL, "stats/solve_s", NC_CKPT_F64, &st->solve_s, 1);
}

static void rebuilt_entries(nc_ckpt_table *t, const ck_sizes *z, ck_rebuilt *r, size_t ndof)
{
    size_t nb = (size_t)z->lin_blocks, nnz = (size_t)z->nnz;
    nc_ckpt_add(t, NULL, "pattern/pairs", NC_CKPT_INT, r->pairs, 2 * (size_t)z->n_pairs);
    nc_ckpt_add(t, NULL, "linearisation/nodes", NC_CKPT_INT, r->lin_nodes, z->lin_active ? 2 * nb : 0);
    nc_ckpt_add(t, NULL, "linearisation/stiffness", NC_CKPT_F64, r->lin_K, z->lin_active ? 9 * nb : 0);
    nc_ckpt_add(t, NULL, "linearisation/damping", NC_CKPT_F64, r->lin_C, z->lin_active ? 9 * nb : 0);
    nc_ckpt_add(t, NULL, "linearisation/displacement", NC_CKPT_F64, r->lin_u, z->lin_active ? ndof : 0);
    nc_ckpt_add(t, NULL, "linearisation/velocity", NC_CKPT_F64, r->lin_v, z->lin_active ? ndof : 0);
    nc_ckpt_add(t, NULL, "factor/values", NC_CKPT_F64, r->factor_x, z->have_factor ? nnz : 0);
    nc_ckpt_add(t, NULL, "factor/saved_values", NC_CKPT_F64, r->saved_factor_x, z->saved_factor ? nnz : 0);
}

/* The output's counters: which rows of fem.h5 belong to the state, the times the XDMF index
 * lists, the run's largest |u|, each set's largest axial force and when each element first
 * exceeded its breaking load (fem_output_reserve_peaks has sized them). */
static void output_entries(nc_ckpt_table *t, const ck_sizes *z, fem_output *o, const fem_model *m)
{
    nc_ckpt_add(t, NULL, "output/times", NC_CKPT_F64, o->times, (size_t)z->n_out);
    nc_ckpt_add(t, NULL, "output/monitor_rows", NC_CKPT_LONG, &o->n_mon, 1);
    nc_ckpt_add(t, NULL, "output/max_u_m", NC_CKPT_F64, &o->max_u_m, 1);
    nc_ckpt_add(t, NULL, "output/max_u_time_s", NC_CKPT_F64, &o->max_u_time_s, 1);
    nc_ckpt_add(t, NULL, "output/max_u_node", NC_CKPT_INT, &o->max_u_node, 1);
    size_t k = (size_t)m->n_sets;
    nc_ckpt_add(t, NULL, "output/peak_axial_force", NC_CKPT_F64, o->peak_n, k);
    nc_ckpt_add(t, NULL, "output/peak_time_s", NC_CKPT_F64, o->peak_time_s, k);
    nc_ckpt_add(t, NULL, "output/peak_element", NC_CKPT_INT, o->peak_element, k);
    nc_ckpt_add(t, NULL, "output/exceedance_time_s", NC_CKPT_F64, o->exceeded_s, (size_t)m->n_elements);
}

/* ---- the model's identity ------------------------------------------------------------ */

typedef struct ck_header {
    int format;
    long step;
    double time_s;
    int n_nodes, n_elements, ndof, neq, n_iface_nodes, n_monitor;
    long sum_geometry, sum_properties, sum_supports, sum_loads;
} ck_header;

static uint64_t fnv(uint64_t h, const void *data, size_t bytes)
{
    const unsigned char *p = data;
    for (size_t i = 0; i < bytes; i++) {
        h ^= p[i];
        h *= 1099511628211ull;
    }
    return h;
}

#define FNV0 1469598103934665603ull

static void model_header(const fem_analysis *s, ck_header *h)
{
    const fem_model *m = s->m;
    size_t nd = (size_t)s->ndof, ne = (size_t)m->n_elements;
    h->format = CK_FORMAT;
    h->n_nodes = m->n_nodes;
    h->n_elements = m->n_elements;
    h->ndof = s->ndof;
    h->neq = s->neq;
    h->n_iface_nodes = m->n_iface_nodes;
    h->n_monitor = m->n_monitor;
    uint64_t g = fnv(fnv(FNV0, m->X, nd * sizeof *m->X), m->conn, 2 * ne * sizeof *m->conn);
    uint64_t p = fnv(fnv(fnv(fnv(FNV0, m->L0, ne * sizeof(double)), m->EA, ne * sizeof(double)),
                         m->AS, ne * sizeof(double)), m->rhoA, ne * sizeof(double));
    uint64_t u = fnv(fnv(FNV0, m->fixed, nd * sizeof *m->fixed), m->u_prescribed, nd * sizeof(double));
    uint64_t l = fnv(FNV0, s->f_model, nd * sizeof(double));
    h->sum_geometry = (long)(g >> 1);
    h->sum_properties = (long)(p >> 1);
    h->sum_supports = (long)(u >> 1);
    h->sum_loads = (long)(l >> 1);
}

static void header_entries(nc_ckpt_table *t, ck_header *h)
{
    nc_ckpt_add(t, NULL, "header/format", NC_CKPT_INT, &h->format, 1);
    nc_ckpt_add(t, NULL, "header/step", NC_CKPT_LONG, &h->step, 1);
    nc_ckpt_add(t, NULL, "header/time_s", NC_CKPT_F64, &h->time_s, 1);
    nc_ckpt_add(t, NULL, "model/n_nodes", NC_CKPT_INT, &h->n_nodes, 1);
    nc_ckpt_add(t, NULL, "model/n_elements", NC_CKPT_INT, &h->n_elements, 1);
    nc_ckpt_add(t, NULL, "model/n_dofs", NC_CKPT_INT, &h->ndof, 1);
    nc_ckpt_add(t, NULL, "model/n_free_dofs", NC_CKPT_INT, &h->neq, 1);
    nc_ckpt_add(t, NULL, "model/n_interface_nodes", NC_CKPT_INT, &h->n_iface_nodes, 1);
    nc_ckpt_add(t, NULL, "model/n_monitor_nodes", NC_CKPT_INT, &h->n_monitor, 1);
    nc_ckpt_add(t, NULL, "model/checksum_geometry", NC_CKPT_LONG, &h->sum_geometry, 1);
    nc_ckpt_add(t, NULL, "model/checksum_properties", NC_CKPT_LONG, &h->sum_properties, 1);
    nc_ckpt_add(t, NULL, "model/checksum_supports", NC_CKPT_LONG, &h->sum_supports, 1);
    nc_ckpt_add(t, NULL, "model/checksum_loads", NC_CKPT_LONG, &h->sum_loads, 1);
}

int fem_checkpoint_name_check(const char *name, nc_error *err)
{
    size_t n = strlen(name);
    if (n == 0 || n > 64)
        return nc_error_set(err, 1, "checkpoint name \"%s\": expected 1 to 64 characters", name);
    for (size_t i = 0; i < n; i++) {
        char c = name[i];
        if (!((c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') ||
              c == '_' || c == '-'))
            return nc_error_set(err, 1, "checkpoint name \"%s\": only letters, digits, '_' and '-' are allowed",
                                name);
    }
    return 0;
}

void fem_checkpoint_path(const char *dir, const char *name, char *out, size_t size)
{
    snprintf(out, size, "%s/checkpoint/fem_%s.h5", dir, name);
}

/* The table of one checkpoint: header, sizes, analysis, rebuilt parts, output, extra. */
static void full_table(nc_ckpt_table *t, ck_header *h, ck_sizes *z, ck_rebuilt *r,
                       fem_analysis *s, fem_output *o, const nc_ckpt_table *extra)
{
    nc_ckpt_clear(t);
    header_entries(t, h);
    size_entries(t, z);
    analysis_entries(t, s);
    rebuilt_entries(t, z, r, (size_t)s->ndof);
    output_entries(t, z, o, s->m);
    nc_ckpt_add_table(t, extra);
}

int fem_checkpoint_save(const char *dir, const char *name, long step, double time_s,
                        fem_analysis *s, fem_output *o, const nc_ckpt_table *extra, nc_error *err)
{
    if (fem_checkpoint_name_check(name, err)) return -1;
    char ck[700], path[800], file[128];
    snprintf(ck, sizeof ck, "%s/checkpoint", dir);
    fem_checkpoint_path(dir, name, path, sizeof path);
    snprintf(file, sizeof file, "fem_%s.h5", name);
    if (nc_file_make_dirs(ck, err) || fem_output_reserve_peaks(o, s->m, err)) return -1;

    ck_header h;
    memset(&h, 0, sizeof h);
    model_header(s, &h);
    h.step = step;
    h.time_s = time_s;
    ck_sizes z = {s->n_pairs, s->lin.active, s->lin.active ? s->lin.n_blocks : 0, s->K.nnz,
                  s->K.have_factor, s->K.use_lu, s->K.saved_valid, o->n_out};
    ck_rebuilt r = {s->pairs, s->lin.nodes, s->lin.K, s->lin.C, s->lin.u_ref, s->lin.v_ref,
                    s->K.factor_x, s->K.saved_factor_x};
    nc_ckpt_table t = {0};
    full_table(&t, &h, &z, &r, s, o, extra);
    int rc = nc_ckpt_save(&t, path, err);
    nc_ckpt_table_free(&t);
    if (rc) return -1;
    /* the new one and the newest one before it (by step) stay */
    nc_ckpt_prune_by_step(ck, "fem_", file, "/header/step", step, 1);
    return 0;
}

/* The header read from a checkpoint against this model, step and time. */
static int check_header(const char *path, const ck_header *have, const ck_header *want,
                        long step, double time_s, nc_error *err)
{
    if (have->format != CK_FORMAT)
        return nc_error_set(err, 1, "%s: checkpoint format %d, this fem_solver reads %d", path,
                            have->format, CK_FORMAT);
    struct { const char *what; long there, here; } counts[] = {
        {"nodes", have->n_nodes, want->n_nodes},
        {"elements", have->n_elements, want->n_elements},
        {"dofs", have->ndof, want->ndof},
        {"free dofs (supports)", have->neq, want->neq},
        {"interface nodes", have->n_iface_nodes, want->n_iface_nodes},
        {"monitor nodes", have->n_monitor, want->n_monitor}};
    for (size_t i = 0; i < sizeof counts / sizeof *counts; i++)
        if (counts[i].there != counts[i].here)
            return nc_error_set(err, 1, "%s: a checkpoint of another model: %ld %s there, %ld in "
                                "this one", path, counts[i].there, counts[i].what, counts[i].here);
    struct { const char *what; long there, here; } sums[] = {
        {"node coordinates or elements", have->sum_geometry, want->sum_geometry},
        {"element properties (E, A, prestress, density)", have->sum_properties, want->sum_properties},
        {"supports", have->sum_supports, want->sum_supports},
        {"loads (point loads, self-weight)", have->sum_loads, want->sum_loads}};
    for (size_t i = 0; i < sizeof sums / sizeof *sums; i++)
        if (sums[i].there != sums[i].here)
            return nc_error_set(err, 1, "%s: a checkpoint of another model: the same counts, but "
                                "other %s", path, sums[i].what);
    if (have->step != step || have->time_s != time_s)
        return nc_error_set(err, 1, "%s: holds step %ld at t = %.17g s, resume asked for step %ld "
                            "at t = %.17g s", path, have->step, have->time_s, step, time_s);
    return 0;
}

int fem_checkpoint_load(const char *dir, const char *name, long step, double time_s,
                        fem_analysis *s, fem_output *o, const nc_ckpt_table *extra, nc_error *err)
{
    if (fem_checkpoint_name_check(name, err)) return -1;
    char path[800];
    fem_checkpoint_path(dir, name, path, sizeof path);
    int rc = -1;
    nc_ckpt_table t = {0};
    ck_rebuilt r;
    memset(&r, 0, sizeof r);
    /* 1. is it this model's, of this step? (nothing of s is changed before) */
    ck_header have, want;
    memset(&have, 0, sizeof have);
    memset(&want, 0, sizeof want);
    model_header(s, &want);
    header_entries(&t, &have);
    if (nc_ckpt_load(&t, path, err) || check_header(path, &have, &want, step, time_s, err))
        goto done;
    /* 2. the sizes of the variable parts */
    ck_sizes z;
    memset(&z, 0, sizeof z);
    nc_ckpt_clear(&t);
    size_entries(&t, &z);
    if (nc_ckpt_load(&t, path, err)) goto done;
    if (z.n_pairs < 0 || z.n_pairs > 64 * s->m->n_nodes || z.lin_blocks < 0 ||
        z.lin_blocks > 64 * s->m->n_nodes || z.nnz <= 0 || z.n_out < 0) {
        nc_error_set(err, 1, "%s: damaged (pattern pairs %d, blocks %d, matrix entries %d, "
                     "output rows %d)", path, z.n_pairs, z.lin_blocks, z.nnz, z.n_out);
        goto done;
    }
    size_t ndof = (size_t)s->ndof, nb = (size_t)z.lin_blocks, nnz = (size_t)z.nnz;
    r.pairs = malloc(2 * (size_t)z.n_pairs * sizeof(int) + 8);
    r.lin_nodes = malloc(2 * nb * sizeof(int) + 8);
    r.lin_K = malloc(9 * nb * sizeof(double) + 8);
    r.lin_C = malloc(9 * nb * sizeof(double) + 8);
    r.lin_u = malloc(ndof * sizeof(double) + 8);
    r.lin_v = malloc(ndof * sizeof(double) + 8);
    r.factor_x = malloc(nnz * sizeof(double));
    r.saved_factor_x = malloc(nnz * sizeof(double));
    if (!r.pairs || !r.lin_nodes || !r.lin_K || !r.lin_C || !r.lin_u || !r.lin_v || !r.factor_x ||
        !r.saved_factor_x || fem_output_reserve_times(o, z.n_out, err) ||
        fem_output_reserve_peaks(o, s->m, err)) {
        nc_error_set(err, 1, "%s: out of memory", path);
        goto done;
    }
    /* 3. everything */
    full_table(&t, &have, &z, &r, s, o, extra);
    if (nc_ckpt_load(&t, path, err)) goto done;
    o->n_out = z.n_out;
    /* 4. rebuild the pattern, the linearisation and the kept factorisations */
    if (fem_analysis_set_pattern_pairs(s, z.n_pairs, r.pairs, err)) {
        nc_error_prefix(err, "%s", path);
        goto done;
    }
    if (s->K.nnz != z.nnz) {
        nc_error_set(err, 1, "%s: the rebuilt matrix pattern has %d entries, the checkpoint's %d",
                     path, s->K.nnz, z.nnz);
        goto done;
    }
    if (z.lin_active) {
        if (fem_ijac_set(&s->lin, s->ndof, s->eq, &s->K, r.lin_u, r.lin_v, z.lin_blocks,
                         r.lin_nodes, r.lin_K, r.lin_C, err)) {
            nc_error_prefix(err, "%s", path);
            goto done;
        }
    } else {
        fem_ijac_clear(&s->lin);
    }
    if (fem_sparse_refactor(&s->K, z.have_factor ? r.factor_x : NULL,
                            z.saved_factor ? r.saved_factor_x : NULL, err)) {
        nc_error_prefix(err, "%s", path);
        goto done;
    }
    if (s->K.use_lu != z.use_lu) {
        nc_error_set(err, 1, "%s: the factorisation was %s, refactorising gave %s", path,
                     z.use_lu ? "LU" : "Cholesky", s->K.use_lu ? "LU" : "Cholesky");
        goto done;
    }
    rc = 0;
done:
    nc_ckpt_table_free(&t);
    free(r.pairs); free(r.lin_nodes); free(r.lin_K); free(r.lin_C); free(r.lin_u); free(r.lin_v);
    free(r.factor_x); free(r.saved_factor_x);
    return rc;
}
