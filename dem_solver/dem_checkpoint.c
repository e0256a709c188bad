/* dem_checkpoint — the table of the state a coupled DEM run depends on, and its durable
 * saving and checked loading (dem_checkpoint.h). */
#include "dem_checkpoint.h"

#include <errno.h>
#include <fcntl.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "nc_file.h"
#include "nc_h5.h"

#define DEM_CK_FORMAT 1
#define MAX_ITEMS 96

/* The identity of a model: what must agree between the checkpoint and the run resuming it. */
typedef struct identity {
    size_t spheres, bodies, clusters, materials, planes, meshes, net_nodes, net_edges;
    double dt_s;
} identity;

/* The counts that size the variable parts of the state, read before the rest. */
typedef struct sizes {
    size_t contacts;       /* records of the current contact list */
    size_t pairs;          /* entries of the Verlet list */
    int buffers;           /* threads (contact buffers) of the run that saved */
} sizes;

static void identity_of(const dem_sim *s, identity *id)
{
    memset(id, 0, sizeof *id);
    id->spheres = s->model.sph.n;
    id->bodies = s->model.bod.n;
    for (size_t b = 0; b < s->model.bod.n; b++) id->clusters += s->model.bod.is_cluster[b] != 0;
    id->materials = s->model.n_materials;
    id->planes = s->model.n_planes;
    id->meshes = s->model.n_meshes;
    id->net_nodes = s->model.net.active ? s->model.net.n_nodes : 0;
    id->net_edges = s->model.net.active ? s->model.net.n_edges : 0;
    id->dt_s = s->model.prm.dt_s;
}

#define ITEM(n_, t_, p_, c_, w_) ((dem_ck_item){(n_), (t_), (void *)(p_), (c_), (w_), 0})
#define STRIDED(n_, t_, p_, c_, w_, st_) ((dem_ck_item){(n_), (t_), (void *)(p_), (c_), (w_), (st_)})

/* The identity items (compared, never loaded); labels for the messages in `what`. */
static size_t identity_items(dem_sim *s, identity *id, dem_ck_item *it, const char **what)
{
    size_t k = 0;
    const dem_model *m = &s->model;
#define ID(name_, label_, t_, p_, c_, w_) (what[k] = (label_), it[k++] = ITEM(name_, t_, p_, c_, w_))
    ID("/model/spheres", "spheres", DEM_CK_SIZE, &id->spheres, 1, 1);
    ID("/model/bodies", "bodies", DEM_CK_SIZE, &id->bodies, 1, 1);
    ID("/model/clusters", "clusters", DEM_CK_SIZE, &id->clusters, 1, 1);
    ID("/model/materials", "materials", DEM_CK_SIZE, &id->materials, 1, 1);
    ID("/model/planes", "planes", DEM_CK_SIZE, &id->planes, 1, 1);
    ID("/model/meshes", "STL meshes", DEM_CK_SIZE, &id->meshes, 1, 1);
    ID("/model/net_nodes", "interface nodes", DEM_CK_SIZE, &id->net_nodes, 1, 1);
    ID("/model/net_edges", "interface elements", DEM_CK_SIZE, &id->net_edges, 1, 1);
    ID("/model/dt_s", "DEM step dt_s (s)", DEM_CK_F64, &id->dt_s, 1, 1);
    /* with equal counts, what the model is made of */
    ID("/model/sphere_radius", "sphere radii (m)", DEM_CK_F64, m->sph.radius, id->spheres, 1);
    ID("/model/sphere_body", "bodies of the spheres", DEM_CK_I32, m->sph.body, id->spheres, 1);
    ID("/model/sphere_material", "materials of the spheres", DEM_CK_I32, m->sph.material, id->spheres, 1);
    ID("/model/body_mass", "body masses (kg)", DEM_CK_F64, m->bod.mass, id->bodies, 1);
    ID("/model/net_reference", "interface coordinates (m)", DEM_CK_F64, m->net.ref, id->net_nodes, 3);
    ID("/model/net_elements", "interface elements", DEM_CK_I32, m->net.edges, id->net_edges, 2);
#undef ID
    return k;
}

/* THE STATE: everything later results depend on, one line per array. `z` gives the sizes of
 * the variable parts; `threads` 0 leaves out the thread ranges (another thread count: the
 * neighbour list is rebuilt instead, which the results do not depend on in coupled runs,
 * where every BEGIN_STEP rebuilds it anyway). */
static size_t state_items(dem_sim *s, dem_output *o, const sizes *z, int threads, dem_ck_item *it)
{
    dem_model *m = &s->model;
    size_t n = m->sph.n, nb = m->bod.n, nn = m->net.active ? m->net.n_nodes : 0, k = 0;
    /* clock and sub-step count */
    it[k++] = ITEM("/sim/time_s", DEM_CK_F64, &s->time_s, 1, 1);
    it[k++] = ITEM("/sim/step", DEM_CK_LONG, &s->step, 1, 1);
    it[k++] = ITEM("/sim/wall_force", DEM_CK_F64, s->wall_force, s->n_walls, 3);
    /* spheres (world positions and velocities; force and torque of the last sub-step) */
    it[k++] = ITEM("/spheres/position", DEM_CK_F64, m->sph.pos, n, 3);
    it[k++] = ITEM("/spheres/velocity", DEM_CK_F64, m->sph.vel, n, 3);
    it[k++] = ITEM("/spheres/force", DEM_CK_F64, m->sph.force, n, 3);
    it[k++] = ITEM("/spheres/torque", DEM_CK_F64, m->sph.torque, n, 3);
    /* rigid bodies */
    it[k++] = ITEM("/bodies/position", DEM_CK_F64, m->bod.pos, nb, 3);
    it[k++] = ITEM("/bodies/velocity", DEM_CK_F64, m->bod.vel, nb, 3);
    it[k++] = ITEM("/bodies/angular_velocity", DEM_CK_F64, m->bod.omega, nb, 3);
    it[k++] = ITEM("/bodies/angular_momentum", DEM_CK_F64, m->bod.angmom, nb, 3);
    it[k++] = ITEM("/bodies/orientation", DEM_CK_F64, m->bod.quat, nb, 4);
    it[k++] = ITEM("/bodies/force", DEM_CK_F64, m->bod.force, nb, 3);
    it[k++] = ITEM("/bodies/torque", DEM_CK_F64, m->bod.torque, nb, 3);
    /* moving walls where the last sub-step placed them (the free-flight test reads them) */
    it[k++] = STRIDED("/planes/point", DEM_CK_F64, m->n_planes ? m->planes[0].point : NULL,
                      m->n_planes, 3, sizeof(dem_plane));
    it[k++] = STRIDED("/meshes/offset", DEM_CK_F64, m->n_meshes ? m->meshes[0].offset : NULL,
                      m->n_meshes, 3, sizeof(dem_mesh));
    /* the net wall: start of the step, the last received end, current position and velocity,
     * forces and impulse of the last step */
    it[k++] = ITEM("/net/start", DEM_CK_F64, m->net.start, nn, 3);
    it[k++] = ITEM("/net/end", DEM_CK_F64, m->net.end, nn, 3);
    it[k++] = ITEM("/net/end_velocity", DEM_CK_F64, m->net.end_vel, nn, 3);
    it[k++] = ITEM("/net/position", DEM_CK_F64, m->net.cur, nn, 3);
    it[k++] = ITEM("/net/velocity", DEM_CK_F64, m->net.vel, nn, 3);
    it[k++] = ITEM("/net/force", DEM_CK_F64, m->net.force, nn, 3);
    it[k++] = ITEM("/net/impulse", DEM_CK_F64, m->net.impulse, nn, 3);
    /* contacts in their order (the order of every force sum) with their history */
    dem_contacts *c = &s->contact.list;
    it[k++] = ITEM("/contacts/sphere", DEM_CK_I32, c->i, z->contacts, 1);
    it[k++] = ITEM("/contacts/kind", DEM_CK_I32, c->kind, z->contacts, 1);
    it[k++] = ITEM("/contacts/partner", DEM_CK_I32, c->j, z->contacts, 1);
    it[k++] = ITEM("/contacts/aux", DEM_CK_I32, c->aux, z->contacts, 1);
    it[k++] = ITEM("/contacts/tangential_force", DEM_CK_F64, c->ft, z->contacts, 3);
    it[k++] = ITEM("/contacts/kt_prev", DEM_CK_F64, c->kt_prev, z->contacts, 1);
    it[k++] = ITEM("/contacts/fn_prev", DEM_CK_F64, c->fn_prev, z->contacts, 1);
    it[k++] = ITEM("/contacts/overlap", DEM_CK_F64, c->overlap, z->contacts, 1);
    it[k++] = ITEM("/contacts/normal", DEM_CK_F64, c->normal, z->contacts, 3);
    it[k++] = ITEM("/contacts/first", DEM_CK_I32, s->contact.first, n + 1, 1);
    /* the Verlet list, its reference positions and rebuild state */
    it[k++] = ITEM("/neighbors/first", DEM_CK_I32, s->nlist.first, n + 1, 1);
    it[k++] = ITEM("/neighbors/list", DEM_CK_I32, s->nlist.nbr, z->pairs, 1);
    it[k++] = ITEM("/neighbors/position_at_build", DEM_CK_F64, s->nlist.pos_at_build, n, 3);
    it[k++] = ITEM("/neighbors/max_displacement2", DEM_CK_F64, &s->nlist.max_disp2, 1, 1);
    it[k++] = ITEM("/neighbors/rebuild", DEM_CK_INT, &s->nlist.rebuild, 1, 1);
    it[k++] = ITEM("/neighbors/builds", DEM_CK_LONG, &s->nlist.n_builds, 1, 1);
    /* the thread ranges the list was built for */
    if (threads) {
        it[k++] = ITEM("/threads/range_first", DEM_CK_SIZE, s->work.range_first, (size_t)s->work.n_buffers + 1, 1);
        it[k++] = ITEM("/threads/shared_sphere", DEM_CK_U8, s->work.shared_sphere, n, 1);
    }
    /* output counters (the rows of dem.h5 at the checkpoint) */
    it[k++] = ITEM("/output/steps", DEM_CK_LONG, &o->n_out, 1, 1);
    it[k++] = ITEM("/output/net_rows", DEM_CK_LONG, &o->net_rows, 1, 1);
    it[k++] = ITEM("/output/net_written", DEM_CK_INT, &o->net_written, 1, 1);
    return k;
}

/* The sizes, stored so that a loader can size the variable parts first. */
static size_t size_items(sizes *z, dem_ck_item *it)
{
    it[0] = ITEM("/sizes/contacts", DEM_CK_SIZE, &z->contacts, 1, 1);
    it[1] = ITEM("/sizes/neighbor_pairs", DEM_CK_SIZE, &z->pairs, 1, 1);
    it[2] = ITEM("/sizes/threads", DEM_CK_INT, &z->buffers, 1, 1);
    return 3;
}

/* ---- values in and out of the table --------------------------------------------------------- */

static int stored_as_int(dem_ck_type t)
{
    return t == DEM_CK_I32 || t == DEM_CK_INT || t == DEM_CK_U8;
}

static size_t type_size(dem_ck_type t)
{
    switch (t) {
    case DEM_CK_F64: return sizeof(double);
    case DEM_CK_LONG: return sizeof(long);
    case DEM_CK_SIZE: return sizeof(size_t);
    case DEM_CK_I32: return sizeof(int32_t);
    case DEM_CK_INT: return sizeof(int);
    default: return sizeof(uint8_t);
    }
}

static size_t item_values(const dem_ck_item *it)
{
    return it->count * it->width;
}

/* Copies the item's values into buf (double or int32_t by stored_as_int), or back (load 1). */
static void transfer(const dem_ck_item *it, void *buf, int load)
{
    size_t vs = type_size(it->type), stride = it->stride ? it->stride : it->width * vs;
    double *d = buf;
    int32_t *q = buf;
    for (size_t e = 0; e < it->count; e++) {
        char *base = (char *)it->data + e * stride;
        for (size_t v = 0; v < it->width; v++) {
            void *p = base + v * vs;
            size_t x = e * it->width + v;
            switch (it->type) {
            case DEM_CK_F64: if (load) memcpy(p, d + x, sizeof(double)); else memcpy(d + x, p, sizeof(double)); break;
            case DEM_CK_LONG: if (load) *(long *)p = (long)d[x]; else d[x] = (double)*(long *)p; break;
            case DEM_CK_SIZE: if (load) *(size_t *)p = (size_t)d[x]; else d[x] = (double)*(size_t *)p; break;
            case DEM_CK_I32: if (load) *(int32_t *)p = q[x]; else q[x] = *(int32_t *)p; break;
            case DEM_CK_INT: if (load) *(int *)p = q[x]; else q[x] = *(int *)p; break;
            case DEM_CK_U8: if (load) *(uint8_t *)p = (uint8_t)q[x]; else q[x] = *(uint8_t *)p; break;
            }
        }
    }
}

static void *value_buffer(const dem_ck_item *it)
{
    size_t n = item_values(it);
    return malloc((n ? n : 1) * (stored_as_int(it->type) ? sizeof(int32_t) : sizeof(double)));
}

static int write_item(nc_h5_file *f, const dem_ck_item *it, nc_error *err)
{
    void *buf = value_buffer(it);
    if (!buf) return nc_error_set(err, 1, "%s: out of memory for %s", f->path, it->name);
    if (it->count) transfer(it, buf, 0);
    hsize_t dims[2] = {it->count, it->width};
    int rc = nc_h5_write(f, it->name, stored_as_int(it->type) ? NC_H5_I32 : NC_H5_F64,
                         it->width == 1 ? 1 : 2, dims, buf, err);
    free(buf);
    return rc;
}

/* Reads the dataset of `it` into a new buffer (*out), checking its shape. */
static int read_item(hid_t file, const char *path, const dem_ck_item *it, void **out, nc_error *err)
{
    *out = NULL;
    if (H5Lexists(file, it->name, H5P_DEFAULT) <= 0)
        return nc_error_set(err, 1, "%s: has no dataset %s (not a complete dem_solver checkpoint)",
                            path, it->name);
    hid_t d = H5Dopen2(file, it->name, H5P_DEFAULT);
    if (d < 0) return nc_error_set(err, 1, "%s: cannot open dataset %s", path, it->name);
    hid_t space = H5Dget_space(d), type = H5Dget_type(d);
    int rank = H5Sget_simple_extent_ndims(space);
    hsize_t dims[2] = {0, 0};
    if (rank >= 1 && rank <= 2) H5Sget_simple_extent_dims(space, dims, NULL);
    H5T_class_t cls = H5Tget_class(type);
    H5Sclose(space);
    H5Tclose(type);
    int want_rank = it->width == 1 ? 1 : 2, is_int = stored_as_int(it->type);
    if (rank != want_rank || dims[0] != it->count || (rank == 2 && dims[1] != it->width) ||
        cls != (is_int ? H5T_INTEGER : H5T_FLOAT)) {
        H5Dclose(d);
        return nc_error_set(err, 1, "%s: dataset %s holds %llu x %llu values, this model needs "
                            "%zu x %zu", path, it->name, (unsigned long long)dims[0],
                            (unsigned long long)(rank == 2 ? dims[1] : 1), it->count, it->width);
    }
    void *buf = value_buffer(it);
    int ok = buf != NULL;
    if (ok && item_values(it) > 0)
        ok = H5Dread(d, is_int ? H5T_NATIVE_INT32 : H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL,
                     H5P_DEFAULT, buf) >= 0;
    H5Dclose(d);
    if (!ok) {
        free(buf);
        return nc_error_set(err, 1, "%s: cannot read dataset %s", path, it->name);
    }
    *out = buf;
    return 0;
}

/* Reads small items straight into their places (sizes, run header). */
static int read_into(hid_t file, const char *path, const dem_ck_item *it, size_t n, nc_error *err)
{
    for (size_t k = 0; k < n; k++) {
        void *buf;
        if (read_item(file, path, &it[k], &buf, err)) return -1;
        transfer(&it[k], buf, 1);
        free(buf);
    }
    return 0;
}

/* ---- saving ---------------------------------------------------------------------------------- */

static int sync_path(const char *path, int directory, nc_error *err)
{
    int fd = open(path, directory ? O_RDONLY | O_DIRECTORY : O_RDONLY);
    if (fd < 0 || fsync(fd) != 0) {
        int e = errno;
        if (fd >= 0) close(fd);
        return nc_error_set(err, 1, "%s: cannot flush to the disk: %s", path, strerror(e));
    }
    close(fd);
    return 0;
}

int dem_checkpoint_save(const char *path, const char *name, dem_sim *s, dem_output *o,
                        const dem_ck_item *extra, size_t n_extra, long step, double time_s,
                        nc_error *err)
{
    identity id;
    identity_of(s, &id);
    sizes z = {s->contact.list.n, s->nlist.first ? (size_t)s->nlist.first[s->model.sph.n] : 0,
               s->work.n_buffers};
    int format = DEM_CK_FORMAT;
    dem_ck_item it[MAX_ITEMS];
    const char *what[MAX_ITEMS];
    size_t k = 0;
    it[k++] = ITEM("/run/format", DEM_CK_INT, &format, 1, 1);
    it[k++] = ITEM("/run/step", DEM_CK_LONG, &step, 1, 1);
    it[k++] = ITEM("/run/time_s", DEM_CK_F64, &time_s, 1, 1);
    k += identity_items(s, &id, it + k, what + k);
    k += size_items(&z, it + k);
    k += state_items(s, o, &z, 1, it + k);
    if (k + n_extra > MAX_ITEMS) return nc_error_set(err, 1, "dem: checkpoint table too long");
    memcpy(it + k, extra, n_extra * sizeof *extra);
    k += n_extra;

    char tmp[1100];
    snprintf(tmp, sizeof tmp, "%s.tmp", path);
    nc_h5_file f;
    if (nc_h5_create(&f, tmp, err)) return -1;
    int rc = 0;
    for (size_t q = 0; q < k && rc == 0; q++) rc = write_item(&f, &it[q], err);
    rc = rc || nc_h5_attr_string(&f, "/", "program", "netcouple dem_solver", err) ||
         nc_h5_attr_string(&f, "/", "checkpoint", name, err) || nc_h5_flush(&f, err);
    nc_h5_close(&f);
    if (rc == 0 && f.failed) rc = nc_error_set(err, 1, "%s: cannot close the HDF5 file", tmp);
    char dir[1100];
    nc_file_dir(path, dir, sizeof dir);
    if (rc == 0) rc = sync_path(tmp, 0, err);
    if (rc == 0 && rename(tmp, path) != 0)
        rc = nc_error_set(err, 1, "%s: cannot rename to %s: %s", tmp, path, strerror(errno));
    if (rc) {
        remove(tmp);
        return -1;
    }
    return sync_path(dir[0] ? dir : "/", 1, err);
}

/* ---- loading --------------------------------------------------------------------------------- */

static void describe_value(char *out, size_t size, const dem_ck_item *it, const void *buf, size_t x)
{
    if (stored_as_int(it->type)) snprintf(out, size, "%d", ((const int32_t *)buf)[x]);
    else snprintf(out, size, "%.17g", ((const double *)buf)[x]);
}

/* Compares the identity stored in the file with this model's; names the first difference. */
static int check_identity(hid_t file, const char *path, const dem_ck_item *it, const char **what,
                          size_t n, nc_error *err)
{
    for (size_t k = 0; k < n; k++) {
        /* the arrays only once the counts that size them agree (read_item checks the shape) */
        void *stored, *mine = value_buffer(&it[k]);
        if (!mine) return nc_error_set(err, 1, "%s: out of memory", path);
        if (it[k].count) transfer(&it[k], mine, 0);
        if (read_item(file, path, &it[k], &stored, err)) {
            free(mine);
            return -1;
        }
        size_t vs = stored_as_int(it[k].type) ? sizeof(int32_t) : sizeof(double);
        size_t nv = item_values(&it[k]), x = 0;
        while (x < nv && memcmp((char *)stored + x * vs, (char *)mine + x * vs, vs) == 0) x++;
        int rc = 0;
        if (x < nv) {
            char a[40], b[40];
            describe_value(a, sizeof a, &it[k], stored, x);
            describe_value(b, sizeof b, &it[k], mine, x);
            if (nv == 1)
                rc = nc_error_set(err, 1, "%s: is a checkpoint of another model: %s %s in the "
                                  "checkpoint, %s in this model", path, what[k], a, b);
            else
                rc = nc_error_set(err, 1, "%s: is a checkpoint of another model: %s differ "
                                  "(entry %zu: %s in the checkpoint, %s in this model)", path,
                                  what[k], x / it[k].width, a, b);
        }
        free(stored);
        free(mine);
        if (rc) return -1;
    }
    return 0;
}

/* Room for the variable parts (contact records, Verlet pairs) of the state to be loaded. */
static int reserve_state(dem_sim *s, const sizes *z, nc_error *err)
{
    if (dem_contacts_reserve(&s->contact.list, z->contacts, err)) return -1;
    if (z->pairs > s->nlist.cap) {
        int32_t *p = realloc(s->nlist.nbr, (z->pairs + 64) * sizeof *p);
        if (!p) return nc_error_set(err, 1, "dem: out of memory for %zu neighbour pairs", z->pairs);
        s->nlist.nbr = p;
        s->nlist.cap = z->pairs + 64;
    }
    return 0;
}

int dem_checkpoint_load(const char *path, dem_sim *s, dem_output *o, const dem_ck_item *extra,
                        size_t n_extra, long step, double time_s, nc_error *err)
{
    nc_h5_quiet();
    if (access(path, R_OK) != 0)
        return nc_error_set(err, 1, "%s: cannot read the checkpoint: %s", path, strerror(errno));
    if (H5Fis_hdf5(path) <= 0)
        return nc_error_set(err, 1, "%s: is not an HDF5 file (not a dem_solver checkpoint)", path);
    hid_t file = H5Fopen(path, H5F_ACC_RDONLY, H5P_DEFAULT);
    if (file < 0) return nc_error_set(err, 1, "%s: cannot open the checkpoint", path);
    int rc = -1;
    void *bufs[MAX_ITEMS] = {0};
    dem_ck_item it[MAX_ITEMS];
    const char *what[MAX_ITEMS];
    size_t k = 0;
    int format = 0;
    long saved_step = -1;
    double saved_time = 0.0;
    identity id;
    identity_of(s, &id);
    sizes z;
    dem_ck_item run[3] = {ITEM("/run/format", DEM_CK_INT, &format, 1, 1),
                          ITEM("/run/step", DEM_CK_LONG, &saved_step, 1, 1),
                          ITEM("/run/time_s", DEM_CK_F64, &saved_time, 1, 1)};
    if (H5Lexists(file, "/run", H5P_DEFAULT) <= 0) {
        nc_error_set(err, 1, "%s: is not a dem_solver checkpoint (no /run)", path);
        goto done;
    }
    if (read_into(file, path, run, 3, err)) goto done;
    if (format != DEM_CK_FORMAT) {
        nc_error_set(err, 1, "%s: checkpoint format %d, this dem_solver reads %d", path, format,
                     DEM_CK_FORMAT);
        goto done;
    }
    k = identity_items(s, &id, it, what);
    if (check_identity(file, path, it, what, k, err)) goto done;
    if (saved_step != step || !(fabs(saved_time - time_s) <= 1e-9)) {
        nc_error_set(err, 1, "%s: is the checkpoint of step %ld at t = %.9g s, RESUME asks for "
                     "step %ld at t = %.9g s", path, saved_step, saved_time, step, time_s);
        goto done;
    }
    dem_ck_item zi[3];
    size_items(&z, zi);
    if (read_into(file, path, zi, 3, err)) goto done;
    if (z.pairs > (size_t)INT32_MAX || z.contacts > (size_t)INT32_MAX) {
        nc_error_set(err, 1, "%s: implausible sizes in /sizes", path);
        goto done;
    }
    int same_threads = z.buffers == s->work.n_buffers;
    k = state_items(s, o, &z, same_threads, it);
    if (k + n_extra > MAX_ITEMS) {
        nc_error_set(err, 1, "dem: checkpoint table too long");
        goto done;
    }
    memcpy(it + k, extra, n_extra * sizeof *extra);
    k += n_extra;
    /* everything into memory first: a failure from here on leaves the state untouched */
    for (size_t q = 0; q < k; q++)
        if (read_item(file, path, &it[q], &bufs[q], err)) goto done;
    if (reserve_state(s, &z, err)) goto done;
    /* the pointers may have moved with the reservation */
    k = state_items(s, o, &z, same_threads, it);
    memcpy(it + k, extra, n_extra * sizeof *extra);
    k += n_extra;
    for (size_t q = 0; q < k; q++) transfer(&it[q], bufs[q], 1);
    s->contact.list.n = z.contacts;
    /* thread ranges of another thread count cannot be used: rebuild the list at the next step */
    if (!same_threads) s->nlist.rebuild = 1;
    s->snap.valid = 0;
    rc = 0;
done:
    for (size_t q = 0; q < MAX_ITEMS; q++) free(bufs[q]);
    H5Fclose(file);
    return rc;
}
