/* fem_checkpoint — the table of what a checkpoint holds, its HDF5 file, and the pruning of
 * old checkpoints (see fem_checkpoint.h). */
#include "fem_checkpoint.h"

#include "nc_file.h"

#include <dirent.h>
#include <errno.h>
#include <fcntl.h>
#include <hdf5.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#define CK_FORMAT 1   /* layout version of the file */

void fem_ck_add(fem_ck_table *t, const char *name, fem_ck_type type, void *data, size_t count)
{
    if (t->n == FEM_CK_MAX_ENTRIES) {
        t->overflow = 1;
        return;
    }
    fem_ck_entry *e = &t->entry[t->n++];
    snprintf(e->name, sizeof e->name, "%s", name);
    e->type = type;
    e->data = data;
    e->count = count;
}

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

static void state_entries(fem_ck_table *t, const char *group, fem_state *st, size_t ndof)
{
    char name[64];
    snprintf(name, sizeof name, "analysis/%s/time_s", group);
    fem_ck_add(t, name, FEM_CK_F64, &st->time_s, 1);
    snprintf(name, sizeof name, "analysis/%s/step", group);
    fem_ck_add(t, name, FEM_CK_LONG, &st->step, 1);
    snprintf(name, sizeof name, "analysis/%s/u", group);
    fem_ck_add(t, name, FEM_CK_F64, st->u, ndof);
    snprintf(name, sizeof name, "analysis/%s/v", group);
    fem_ck_add(t, name, FEM_CK_F64, st->v, ndof);
    snprintf(name, sizeof name, "analysis/%s/a", group);
    fem_ck_add(t, name, FEM_CK_F64, st->a, ndof);
    snprintf(name, sizeof name, "analysis/%s/fd", group);
    fem_ck_add(t, name, FEM_CK_F64, st->fd, ndof);
    snprintf(name, sizeof name, "analysis/%s/fc", group);
    fem_ck_add(t, name, FEM_CK_F64, st->fc, ndof);
    /* the element types' history: brake strokes and dissipated energies */
    snprintf(name, sizeof name, "analysis/%s/element_history", group);
    fem_ck_add(t, name, FEM_CK_F64, st->element_history, (size_t)st->n_history);
}

static void size_entries(fem_ck_table *t, ck_sizes *z)
{
    fem_ck_add(t, "pattern/n_pairs", FEM_CK_I32, &z->n_pairs, 1);
    fem_ck_add(t, "linearisation/active", FEM_CK_I32, &z->lin_active, 1);
    fem_ck_add(t, "linearisation/n_blocks", FEM_CK_I32, &z->lin_blocks, 1);
    fem_ck_add(t, "factor/nnz", FEM_CK_I32, &z->nnz, 1);
    fem_ck_add(t, "factor/current", FEM_CK_I32, &z->have_factor, 1);
    fem_ck_add(t, "factor/lu", FEM_CK_I32, &z->use_lu, 1);
    fem_ck_add(t, "factor/saved", FEM_CK_I32, &z->saved_factor, 1);
    fem_ck_add(t, "output/rows", FEM_CK_I32, &z->n_out, 1);
}

/* The analysis state. Not in it, because every solve writes them before it reads them:
 * the residual and work vectors (r, rhs, du, u0, w, cg_*, mass_x, mass_y, a_unshifted), the
 * matrix values (reassembled at the first evaluation), lin.df. Derived once from the model
 * at init: eq, dof_of_eq, f_model, mass_diag. */
static void analysis_entries(fem_ck_table *t, fem_analysis *s)
{
    const size_t ndof = (size_t)s->ndof;
    fem_stats *st = &s->stats;
    state_entries(t, "cur", &s->cur, ndof);
    state_entries(t, "start", &s->start, ndof);          /* start of the last step solved */
    state_entries(t, "saved", &s->saved, ndof);          /* BEGIN_STEP's copy */
    fem_ck_add(t, "analysis/has_saved", FEM_CK_I32, &s->has_saved, 1);
    fem_ck_add(t, "analysis/f_coupling", FEM_CK_F64, s->f_coupling, ndof);
    fem_ck_add(t, "analysis/axial", FEM_CK_F64, s->axial, (size_t)s->m->n_elements);
    /* which matrix form the kept factorisations are of (modified Newton reuses them) */
    fem_ck_add(t, "analysis/factor_cm", FEM_CK_F64, &s->factor_cm, 1);
    fem_ck_add(t, "analysis/factor_ck", FEM_CK_F64, &s->factor_ck, 1);
    fem_ck_add(t, "analysis/saved_factor_cm", FEM_CK_F64, &s->saved_factor_cm, 1);
    fem_ck_add(t, "analysis/saved_factor_ck", FEM_CK_F64, &s->saved_factor_ck, 1);
    fem_ck_add(t, "analysis/lin_serial", FEM_CK_LONG, &s->lin_serial, 1);
    fem_ck_add(t, "analysis/factor_lin", FEM_CK_LONG, &s->factor_lin, 1);
    fem_ck_add(t, "analysis/saved_factor_lin", FEM_CK_LONG, &s->saved_factor_lin, 1);
    /* statistics: the summary and the SOLVE replies report them */
    fem_ck_add(t, "stats/iterations", FEM_CK_I32, &st->iterations, 1);
    fem_ck_add(t, "stats/residual_norm", FEM_CK_F64, &st->residual_norm, 1);
    fem_ck_add(t, "stats/increment_norm", FEM_CK_F64, &st->increment_norm, 1);
    fem_ck_add(t, "stats/slack_elements", FEM_CK_I32, &st->slack_elements, 1);
    fem_ck_add(t, "stats/assemblies", FEM_CK_LONG, &st->assemblies, 1);
    fem_ck_add(t, "stats/factorizations", FEM_CK_LONG, &st->factorizations, 1);
    fem_ck_add(t, "stats/lu_factorizations", FEM_CK_LONG, &st->lu_factorizations, 1);
    fem_ck_add(t, "stats/solves", FEM_CK_LONG, &st->solves, 1);
    fem_ck_add(t, "stats/line_search_cuts", FEM_CK_LONG, &st->line_search_cuts, 1);
    fem_ck_add(t, "stats/pattern_growths", FEM_CK_LONG, &st->pattern_growths, 1);
    fem_ck_add(t, "stats/pcg_solves", FEM_CK_LONG, &st->pcg_solves, 1);
    fem_ck_add(t, "stats/pcg_iterations", FEM_CK_LONG, &st->pcg_iterations, 1);
    fem_ck_add(t, "stats/pcg_failures", FEM_CK_LONG, &st->pcg_failures, 1);
    fem_ck_add(t, "stats/assembly_s", FEM_CK_F64, &st->assembly_s, 1);
    fem_ck_add(t, "stats/factor_s", FEM_CK_F64, &st->factor_s, 1);
    fem_ck_add(t, "stats/solve_s", FEM_CK_F64, &st->solve_s, 1);
}

static void rebuilt_entries(fem_ck_table *t, const ck_sizes *z, ck_rebuilt *r, size_t ndof)
{
    size_t nb = (size_t)z->lin_blocks, nnz = (size_t)z->nnz;
    fem_ck_add(t, "pattern/pairs", FEM_CK_I32, r->pairs, 2 * (size_t)z->n_pairs);
    fem_ck_add(t, "linearisation/nodes", FEM_CK_I32, r->lin_nodes, z->lin_active ? 2 * nb : 0);
    fem_ck_add(t, "linearisation/stiffness", FEM_CK_F64, r->lin_K, z->lin_active ? 9 * nb : 0);
    fem_ck_add(t, "linearisation/damping", FEM_CK_F64, r->lin_C, z->lin_active ? 9 * nb : 0);
    fem_ck_add(t, "linearisation/displacement", FEM_CK_F64, r->lin_u, z->lin_active ? ndof : 0);
    fem_ck_add(t, "linearisation/velocity", FEM_CK_F64, r->lin_v, z->lin_active ? ndof : 0);
    fem_ck_add(t, "factor/values", FEM_CK_F64, r->factor_x, z->have_factor ? nnz : 0);
    fem_ck_add(t, "factor/saved_values", FEM_CK_F64, r->saved_factor_x, z->saved_factor ? nnz : 0);
}

/* The output's counters: which rows of fem.h5 belong to the state, the times the XDMF index
 * lists, the run's largest |u|. */
static void output_entries(fem_ck_table *t, const ck_sizes *z, fem_output *o)
{
    fem_ck_add(t, "output/times", FEM_CK_F64, o->times, (size_t)z->n_out);
    fem_ck_add(t, "output/monitor_rows", FEM_CK_LONG, &o->n_mon, 1);
    fem_ck_add(t, "output/max_u_m", FEM_CK_F64, &o->max_u_m, 1);
    fem_ck_add(t, "output/max_u_time_s", FEM_CK_F64, &o->max_u_time_s, 1);
    fem_ck_add(t, "output/max_u_node", FEM_CK_I32, &o->max_u_node, 1);
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

static void header_entries(fem_ck_table *t, ck_header *h)
{
    fem_ck_add(t, "header/format", FEM_CK_I32, &h->format, 1);
    fem_ck_add(t, "header/step", FEM_CK_LONG, &h->step, 1);
    fem_ck_add(t, "header/time_s", FEM_CK_F64, &h->time_s, 1);
    fem_ck_add(t, "model/n_nodes", FEM_CK_I32, &h->n_nodes, 1);
    fem_ck_add(t, "model/n_elements", FEM_CK_I32, &h->n_elements, 1);
    fem_ck_add(t, "model/n_dofs", FEM_CK_I32, &h->ndof, 1);
    fem_ck_add(t, "model/n_free_dofs", FEM_CK_I32, &h->neq, 1);
    fem_ck_add(t, "model/n_interface_nodes", FEM_CK_I32, &h->n_iface_nodes, 1);
    fem_ck_add(t, "model/n_monitor_nodes", FEM_CK_I32, &h->n_monitor, 1);
    fem_ck_add(t, "model/checksum_geometry", FEM_CK_LONG, &h->sum_geometry, 1);
    fem_ck_add(t, "model/checksum_properties", FEM_CK_LONG, &h->sum_properties, 1);
    fem_ck_add(t, "model/checksum_supports", FEM_CK_LONG, &h->sum_supports, 1);
    fem_ck_add(t, "model/checksum_loads", FEM_CK_LONG, &h->sum_loads, 1);
}

/* ---- HDF5 ---------------------------------------------------------------------------- */

static hid_t mem_type(fem_ck_type t)
{
    return t == FEM_CK_F64 ? H5T_NATIVE_DOUBLE : t == FEM_CK_I32 ? H5T_NATIVE_INT
         : t == FEM_CK_LONG ? H5T_NATIVE_LONG : H5T_NATIVE_UCHAR;
}

static hid_t file_type(fem_ck_type t)
{
    return t == FEM_CK_F64 ? H5T_IEEE_F64LE : t == FEM_CK_I32 ? H5T_STD_I32LE
         : t == FEM_CK_LONG ? H5T_STD_I64LE : H5T_STD_U8LE;
}

static int write_entries(hid_t f, const fem_ck_table *t, const char *path, nc_error *err)
{
    hid_t lcpl = H5Pcreate(H5P_LINK_CREATE);
    H5Pset_create_intermediate_group(lcpl, 1);
    int rc = 0;
    for (int i = 0; i < t->n && !rc; i++) {
        const fem_ck_entry *e = &t->entry[i];
        hsize_t dims[1] = {(hsize_t)e->count};
        hid_t space = H5Screate_simple(1, dims, NULL);
        hid_t d = space < 0 ? -1 : H5Dcreate2(f, e->name, file_type(e->type), space, lcpl,
                                              H5P_DEFAULT, H5P_DEFAULT);
        if (d < 0 || (e->count > 0 && H5Dwrite(d, mem_type(e->type), H5S_ALL, H5S_ALL,
                                               H5P_DEFAULT, e->data) < 0))
            rc = nc_error_set(err, 1, "%s: cannot write %s", path, e->name);
        if (d >= 0) H5Dclose(d);
        if (space >= 0) H5Sclose(space);
    }
    H5Pclose(lcpl);
    return rc;
}

static int read_entries(hid_t f, const fem_ck_table *t, const char *path, nc_error *err)
{
    for (int i = 0; i < t->n; i++) {
        const fem_ck_entry *e = &t->entry[i];
        if (H5Lexists(f, e->name, H5P_DEFAULT) <= 0)
            return nc_error_set(err, 1, "%s: has no %s (not a fem_solver checkpoint of this version?)",
                                path, e->name);
        hid_t d = H5Dopen2(f, e->name, H5P_DEFAULT);
        if (d < 0) return nc_error_set(err, 1, "%s: cannot open %s", path, e->name);
        hid_t space = H5Dget_space(d), type = H5Dget_type(d);
        hssize_t count = space >= 0 ? H5Sget_simple_extent_npoints(space) : -1;
        int want_float = e->type == FEM_CK_F64;
        H5T_class_t cls = type >= 0 ? H5Tget_class(type) : H5T_NO_CLASS;
        int rc = 0;
        if (count < 0 || (size_t)count != e->count)
            rc = nc_error_set(err, 1, "%s: %s holds %lld values, this model needs %zu", path,
                              e->name, (long long)count, e->count);
        else if (cls != (want_float ? H5T_FLOAT : H5T_INTEGER))
            rc = nc_error_set(err, 1, "%s: %s is not of type %s", path, e->name,
                              want_float ? "float" : "integer");
        else if (e->count > 0 && H5Dread(d, mem_type(e->type), H5S_ALL, H5S_ALL, H5P_DEFAULT, e->data) < 0)
            rc = nc_error_set(err, 1, "%s: cannot read %s", path, e->name);
        if (type >= 0) H5Tclose(type);
        if (space >= 0) H5Sclose(space);
        H5Dclose(d);
        if (rc) return -1;
    }
    return 0;
}

/* Writes `bytes` to tmp, fsyncs it, renames it to path and fsyncs the folder `dir`. */
static int write_durably(const char *dir, const char *tmp, const char *path, const void *data,
                         size_t bytes, nc_error *err)
{
    int fd = open(tmp, O_WRONLY | O_CREAT | O_TRUNC, 0644);
    if (fd < 0) return nc_error_set(err, 1, "%s: cannot create: %s", tmp, strerror(errno));
    const char *p = data;
    size_t left = bytes;
    while (left > 0) {
        ssize_t w = write(fd, p, left);
        if (w < 0 && errno == EINTR) continue;
        if (w <= 0) {
            int e = w < 0 ? errno : ENOSPC;
            close(fd);
            unlink(tmp);
            return nc_error_set(err, 1, "%s: cannot write: %s", tmp, strerror(e));
        }
        p += w;
        left -= (size_t)w;
    }
    if (fsync(fd) != 0) {
        int e = errno;
        close(fd);
        unlink(tmp);
        return nc_error_set(err, 1, "%s: cannot flush to disk: %s", tmp, strerror(e));
    }
    if (close(fd) != 0) {
        int e = errno;
        unlink(tmp);
        return nc_error_set(err, 1, "%s: cannot close: %s", tmp, strerror(e));
    }
    if (rename(tmp, path) != 0) {
        int e = errno;
        unlink(tmp);
        return nc_error_set(err, 1, "%s: cannot rename to %s: %s", tmp, path, strerror(e));
    }
    int dfd = open(dir, O_RDONLY | O_DIRECTORY);
    if (dfd >= 0) {   /* the rename itself is durable once the folder is */
        int rc = fsync(dfd);
        int e = errno;
        close(dfd);
        if (rc != 0) return nc_error_set(err, 1, "%s: cannot flush the folder to disk: %s", dir, strerror(e));
    }
    return 0;
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
static int full_table(fem_ck_table *t, ck_header *h, ck_sizes *z, ck_rebuilt *r, fem_analysis *s,
                      fem_output *o, const fem_ck_table *extra)
{
    t->n = 0;
    t->overflow = 0;
    header_entries(t, h);
    size_entries(t, z);
    analysis_entries(t, s);
    rebuilt_entries(t, z, r, (size_t)s->ndof);
    output_entries(t, z, o);
    if (extra)
        for (int i = 0; i < extra->n; i++) {
            const fem_ck_entry *e = &extra->entry[i];
            fem_ck_add(t, e->name, e->type, e->data, e->count);
        }
    return t->overflow || (extra && extra->overflow) ? -1 : 0;
}

/* Step recorded in a checkpoint file, -1 when it cannot be read. */
static long file_step(const char *path)
{
    htri_t ok = H5Fis_hdf5(path);
    if (ok <= 0) return -1;
    hid_t f = H5Fopen(path, H5F_ACC_RDONLY, H5P_DEFAULT);
    if (f < 0) return -1;
    long step = -1;
    hid_t d = H5Lexists(f, "header/step", H5P_DEFAULT) > 0 ? H5Dopen2(f, "header/step", H5P_DEFAULT) : -1;
    if (d >= 0) {
        if (H5Dread(d, H5T_NATIVE_LONG, H5S_ALL, H5S_ALL, H5P_DEFAULT, &step) < 0) step = -1;
        H5Dclose(d);
    }
    H5Fclose(f);
    return step;
}

/* Deletes the fem checkpoints of folder `ck` older than the newest one before `keep`
 * (step `step`); later ones and unreadable ones are left. */
static void prune(const char *ck, const char *keep, long step)
{
    DIR *d = opendir(ck);
    if (!d) return;
    char (*names)[300] = NULL;
    long *steps = NULL;
    double *mtimes = NULL;
    int n = 0, cap = 0;
    struct dirent *de;
    while ((de = readdir(d))) {
        size_t len = strlen(de->d_name);
        if (len < 8 || len >= 300 || strncmp(de->d_name, "fem_", 4) != 0 ||
            strcmp(de->d_name + len - 3, ".h5") != 0 || strcmp(de->d_name, keep) == 0)
            continue;
        char path[1024];
        snprintf(path, sizeof path, "%s/%s", ck, de->d_name);
        long s = file_step(path);
        struct stat stt;
        if (s < 0 || s > step || stat(path, &stt) != 0) continue;
        if (n == cap) {
            int c = cap ? 2 * cap : 16;
            void *a = realloc(names, (size_t)c * sizeof *names);
            if (a) names = a;
            void *b = a ? realloc(steps, (size_t)c * sizeof *steps) : NULL;
            if (b) steps = b;
            void *m = b ? realloc(mtimes, (size_t)c * sizeof *mtimes) : NULL;
            if (m) mtimes = m;
            if (!m) break;
            cap = c;
        }
        snprintf(names[n], sizeof names[n], "%s", de->d_name);
        steps[n] = s;
        mtimes[n] = (double)stt.st_mtim.tv_sec + 1e-9 * (double)stt.st_mtim.tv_nsec;
        n++;
    }
    closedir(d);
    int newest = -1;
    for (int i = 0; i < n; i++)
        if (newest < 0 || steps[i] > steps[newest] ||
            (steps[i] == steps[newest] && mtimes[i] > mtimes[newest]))
            newest = i;
    for (int i = 0; i < n; i++) {
        if (i == newest) continue;
        char path[1024];
        snprintf(path, sizeof path, "%s/%s", ck, names[i]);
        unlink(path);
    }
    free(names);
    free(steps);
    free(mtimes);
}

int fem_checkpoint_save(const char *dir, const char *name, long step, double time_s,
                        fem_analysis *s, fem_output *o, const fem_ck_table *extra, nc_error *err)
{
    if (fem_checkpoint_name_check(name, err)) return -1;
    char ck[700], path[800], tmp[810], file[128];
    snprintf(ck, sizeof ck, "%s/checkpoint", dir);
    fem_checkpoint_path(dir, name, path, sizeof path);
    snprintf(tmp, sizeof tmp, "%s.tmp", path);
    snprintf(file, sizeof file, "fem_%s.h5", name);
    if (nc_file_make_dirs(ck, err)) return -1;

    ck_header h;
    memset(&h, 0, sizeof h);
    model_header(s, &h);
    h.step = step;
    h.time_s = time_s;
    ck_sizes z = {s->n_pairs, s->lin.active, s->lin.active ? s->lin.n_blocks : 0, s->K.nnz,
                  s->K.have_factor, s->K.use_lu, s->K.saved_valid, o->n_out};
    ck_rebuilt r = {s->pairs, s->lin.nodes, s->lin.K, s->lin.C, s->lin.u_ref, s->lin.v_ref,
                    s->K.factor_x, s->K.saved_factor_x};
    fem_ck_table *t = malloc(sizeof *t);
    if (!t) return nc_error_set(err, 1, "%s: out of memory", path);
    if (full_table(t, &h, &z, &r, s, o, extra)) {
        free(t);
        return nc_error_set(err, 1, "%s: more than %d entries in the checkpoint table", path,
                            FEM_CK_MAX_ENTRIES);
    }
    /* built in memory (HDF5's core driver), then written with plain system calls, whose
     * errors (a full disk) are reported exactly and leave no half-written file */
    size_t bytes_hint = 1u << 20;
    hid_t fapl = H5Pcreate(H5P_FILE_ACCESS);
    H5Pset_fapl_core(fapl, bytes_hint, 0);
    hid_t f = H5Fcreate(file, H5F_ACC_TRUNC, H5P_DEFAULT, fapl);
    H5Pclose(fapl);
    if (f < 0) {
        free(t);
        return nc_error_set(err, 1, "%s: cannot create the checkpoint in memory", path);
    }
    int rc = write_entries(f, t, path, err);
    free(t);
    void *image = NULL;
    ssize_t size = -1;
    if (!rc && H5Fflush(f, H5F_SCOPE_GLOBAL) >= 0) size = H5Fget_file_image(f, NULL, 0);
    if (!rc && size > 0 && (image = malloc((size_t)size)) != NULL &&
        H5Fget_file_image(f, image, (size_t)size) != size) {
        free(image);
        image = NULL;
    }
    H5Fclose(f);
    if (!rc && !image) rc = nc_error_set(err, 1, "%s: cannot build the checkpoint image", path);
    if (!rc) rc = write_durably(ck, tmp, path, image, (size_t)size, err);
    free(image);
    if (rc) return -1;
    prune(ck, file, step);
    return 0;
}

/* Reads the entries of t from f; the header part is compared with this model first. */
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
                        fem_analysis *s, fem_output *o, const fem_ck_table *extra, nc_error *err)
{
    if (fem_checkpoint_name_check(name, err)) return -1;
    char path[800];
    fem_checkpoint_path(dir, name, path, sizeof path);
    struct stat st;
    if (stat(path, &st) != 0)
        return nc_error_set(err, 1, "%s: cannot read the checkpoint: %s", path, strerror(errno));
    if (H5Fis_hdf5(path) <= 0)
        return nc_error_set(err, 1, "%s: not a readable HDF5 file (damaged checkpoint?)", path);
    hid_t f = H5Fopen(path, H5F_ACC_RDONLY, H5P_DEFAULT);
    if (f < 0) return nc_error_set(err, 1, "%s: cannot open the checkpoint", path);
    int rc = -1;
    fem_ck_table *t = malloc(sizeof *t);
    ck_rebuilt r;
    memset(&r, 0, sizeof r);
    if (!t) {
        nc_error_set(err, 1, "%s: out of memory", path);
        goto done;
    }
    /* 1. is it this model's, of this step? (nothing of s is changed before) */
    ck_header have, want;
    memset(&have, 0, sizeof have);
    memset(&want, 0, sizeof want);
    model_header(s, &want);
    t->n = t->overflow = 0;
    header_entries(t, &have);
    if (read_entries(f, t, path, err) || check_header(path, &have, &want, step, time_s, err))
        goto done;
    /* 2. the sizes of the variable parts */
    ck_sizes z;
    memset(&z, 0, sizeof z);
    t->n = 0;
    size_entries(t, &z);
    if (read_entries(f, t, path, err)) goto done;
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
        !r.saved_factor_x || fem_output_reserve_times(o, z.n_out, err)) {
        nc_error_set(err, 1, "%s: out of memory", path);
        goto done;
    }
    /* 3. everything */
    if (full_table(t, &have, &z, &r, s, o, extra)) {
        nc_error_set(err, 1, "%s: more than %d entries in the checkpoint table", path, FEM_CK_MAX_ENTRIES);
        goto done;
    }
    if (read_entries(f, t, path, err)) goto done;
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
    H5Fclose(f);
    free(t);
    free(r.pairs); free(r.lin_nodes); free(r.lin_K); free(r.lin_C); free(r.lin_u); free(r.lin_v);
    free(r.factor_x); free(r.saved_factor_x);
    return rc;
}
