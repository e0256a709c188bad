/* dem_checkpoint — the table of the state a coupled DEM run depends on, the model's identity
 * checked on loading, and the sizes read first (dem_checkpoint.h); the file itself is
 * common/nc_checkpoint's. */
#include "dem_checkpoint.h"

#include <math.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define DEM_CK_FORMAT 3   /* 2: counts stored as 64-bit integers; 3: a net node contact keyed by
                             its rope (aux), one per rope through the node */

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

#define ITEM(t_, n_, ty_, p_, c_, w_) nc_ckpt_add_rows((t_), NULL, (n_), (ty_), (void *)(p_), (c_), (w_), 0)
#define STRIDED(t_, n_, ty_, p_, c_, w_, st_) \
    nc_ckpt_add_rows((t_), NULL, (n_), (ty_), (void *)(p_), (c_), (w_), (st_))

/* The run header: format, and the step and time of the command. */
static void run_entries(nc_ckpt_table *t, int *format, long *step, double *time_s)
{
    ITEM(t, "/run/format", NC_CKPT_INT, format, 1, 1);
    ITEM(t, "/run/step", NC_CKPT_LONG, step, 1, 1);
    ITEM(t, "/run/time_s", NC_CKPT_F64, time_s, 1, 1);
}

/* The identity's counts, compared one by one (labels for the messages). */
static const struct { const char *name, *label; size_t offset; } ID_COUNTS[] = {
    {"/model/spheres", "spheres", offsetof(identity, spheres)},
    {"/model/bodies", "bodies", offsetof(identity, bodies)},
    {"/model/clusters", "clusters", offsetof(identity, clusters)},
    {"/model/materials", "materials", offsetof(identity, materials)},
    {"/model/planes", "planes", offsetof(identity, planes)},
    {"/model/meshes", "STL meshes", offsetof(identity, meshes)},
    {"/model/net_nodes", "interface nodes", offsetof(identity, net_nodes)},
    {"/model/net_edges", "interface elements", offsetof(identity, net_edges)},
};
#define N_ID_COUNTS (sizeof ID_COUNTS / sizeof *ID_COUNTS)

static void identity_count_entries(nc_ckpt_table *t, identity *id)
{
    for (size_t k = 0; k < N_ID_COUNTS; k++)
        ITEM(t, ID_COUNTS[k].name, NC_CKPT_SIZE, (char *)id + ID_COUNTS[k].offset, 1, 1);
    ITEM(t, "/model/dt_s", NC_CKPT_F64, &id->dt_s, 1, 1);
}

/* With equal counts, what the model is made of: {dataset, label, type, values, rows, width}. */
typedef struct id_array {
    const char *name, *label;
    nc_ckpt_type type;
    void *data;
    size_t rows, width;
} id_array;

static size_t identity_arrays(dem_sim *s, const identity *id, id_array *a)
{
    const dem_model *m = &s->model;
    size_t k = 0;
    a[k++] = (id_array){"/model/sphere_radius", "sphere radii (m)", NC_CKPT_F64, m->sph.radius, id->spheres, 1};
    a[k++] = (id_array){"/model/sphere_body", "bodies of the spheres", NC_CKPT_I32, m->sph.body, id->spheres, 1};
    a[k++] = (id_array){"/model/sphere_material", "materials of the spheres", NC_CKPT_I32, m->sph.material, id->spheres, 1};
    a[k++] = (id_array){"/model/body_mass", "body masses (kg)", NC_CKPT_F64, m->bod.mass, id->bodies, 1};
    a[k++] = (id_array){"/model/net_reference", "interface coordinates (m)", NC_CKPT_F64, m->net.ref, id->net_nodes, 3};
    a[k++] = (id_array){"/model/net_elements", "interface elements", NC_CKPT_I32, m->net.edges, id->net_edges, 2};
    return k;
}
#define N_ID_ARRAYS 6

static void identity_entries(nc_ckpt_table *t, dem_sim *s, identity *id)
{
    identity_count_entries(t, id);
    id_array a[N_ID_ARRAYS];
    size_t n = identity_arrays(s, id, a);
    for (size_t k = 0; k < n; k++) ITEM(t, a[k].name, a[k].type, a[k].data, a[k].rows, a[k].width);
}

/* THE STATE: everything later results depend on, one line per array. `z` gives the sizes of
 * the variable parts; `threads` 0 leaves out the thread ranges (another thread count: the
 * neighbour list is rebuilt instead, which the results do not depend on in coupled runs,
 * where every BEGIN_STEP rebuilds it anyway). */
static void state_entries(nc_ckpt_table *t, dem_sim *s, dem_output *o, const sizes *z, int threads)
{
    dem_model *m = &s->model;
    size_t n = m->sph.n, nb = m->bod.n, nn = m->net.active ? m->net.n_nodes : 0;
    /* clock and sub-step count */
    ITEM(t, "/sim/time_s", NC_CKPT_F64, &s->time_s, 1, 1);
    ITEM(t, "/sim/step", NC_CKPT_LONG, &s->step, 1, 1);
    ITEM(t, "/sim/wall_force", NC_CKPT_F64, s->wall_force, s->n_walls, 3);
    /* spheres (world positions and velocities; force and torque of the last sub-step) */
    ITEM(t, "/spheres/position", NC_CKPT_F64, m->sph.pos, n, 3);
    ITEM(t, "/spheres/velocity", NC_CKPT_F64, m->sph.vel, n, 3);
    ITEM(t, "/spheres/force", NC_CKPT_F64, m->sph.force, n, 3);
    ITEM(t, "/spheres/torque", NC_CKPT_F64, m->sph.torque, n, 3);
    /* rigid bodies */
    ITEM(t, "/bodies/position", NC_CKPT_F64, m->bod.pos, nb, 3);
    ITEM(t, "/bodies/velocity", NC_CKPT_F64, m->bod.vel, nb, 3);
    ITEM(t, "/bodies/angular_velocity", NC_CKPT_F64, m->bod.omega, nb, 3);
    ITEM(t, "/bodies/angular_momentum", NC_CKPT_F64, m->bod.angmom, nb, 3);
    ITEM(t, "/bodies/orientation", NC_CKPT_F64, m->bod.quat, nb, 4);
    ITEM(t, "/bodies/force", NC_CKPT_F64, m->bod.force, nb, 3);
    ITEM(t, "/bodies/torque", NC_CKPT_F64, m->bod.torque, nb, 3);
    /* moving walls where the last sub-step placed them (the free-flight test reads them) */
    STRIDED(t, "/planes/point", NC_CKPT_F64, m->n_planes ? m->planes[0].point : NULL,
                      m->n_planes, 3, sizeof(dem_plane));
    STRIDED(t, "/meshes/offset", NC_CKPT_F64, m->n_meshes ? m->meshes[0].offset : NULL,
                      m->n_meshes, 3, sizeof(dem_mesh));
    /* the net wall: start of the step, the last received end, current position and velocity,
     * forces and impulse of the last step */
    ITEM(t, "/net/start", NC_CKPT_F64, m->net.start, nn, 3);
    ITEM(t, "/net/end", NC_CKPT_F64, m->net.end, nn, 3);
    ITEM(t, "/net/end_velocity", NC_CKPT_F64, m->net.end_vel, nn, 3);
    ITEM(t, "/net/position", NC_CKPT_F64, m->net.cur, nn, 3);
    ITEM(t, "/net/velocity", NC_CKPT_F64, m->net.vel, nn, 3);
    ITEM(t, "/net/force", NC_CKPT_F64, m->net.force, nn, 3);
    ITEM(t, "/net/impulse", NC_CKPT_F64, m->net.impulse, nn, 3);
    /* contacts in their order (the order of every force sum) with their history */
    dem_contacts *c = &s->contact.list;
    ITEM(t, "/contacts/sphere", NC_CKPT_I32, c->i, z->contacts, 1);
    ITEM(t, "/contacts/kind", NC_CKPT_I32, c->kind, z->contacts, 1);
    ITEM(t, "/contacts/partner", NC_CKPT_I32, c->j, z->contacts, 1);
    ITEM(t, "/contacts/aux", NC_CKPT_I32, c->aux, z->contacts, 1);
    ITEM(t, "/contacts/tangential_force", NC_CKPT_F64, c->ft, z->contacts, 3);
    ITEM(t, "/contacts/kt_prev", NC_CKPT_F64, c->kt_prev, z->contacts, 1);
    ITEM(t, "/contacts/fn_prev", NC_CKPT_F64, c->fn_prev, z->contacts, 1);
    ITEM(t, "/contacts/impact_speed", NC_CKPT_F64, c->impact_speed, z->contacts, 1);
    ITEM(t, "/contacts/overlap", NC_CKPT_F64, c->overlap, z->contacts, 1);
    ITEM(t, "/contacts/normal", NC_CKPT_F64, c->normal, z->contacts, 3);
    ITEM(t, "/contacts/first", NC_CKPT_I32, s->contact.first, n + 1, 1);
    /* the Verlet list, its reference positions and rebuild state */
    ITEM(t, "/neighbors/first", NC_CKPT_I32, s->nlist.first, n + 1, 1);
    ITEM(t, "/neighbors/list", NC_CKPT_I32, s->nlist.nbr, z->pairs, 1);
    ITEM(t, "/neighbors/position_at_build", NC_CKPT_F64, s->nlist.pos_at_build, n, 3);
    ITEM(t, "/neighbors/max_displacement2", NC_CKPT_F64, &s->nlist.max_disp2, 1, 1);
    ITEM(t, "/neighbors/rebuild", NC_CKPT_INT, &s->nlist.rebuild, 1, 1);
    ITEM(t, "/neighbors/builds", NC_CKPT_LONG, &s->nlist.n_builds, 1, 1);
    /* the thread ranges the list was built for */
    if (threads) {
        ITEM(t, "/threads/range_first", NC_CKPT_SIZE, s->work.range_first, (size_t)s->work.n_buffers + 1, 1);
        ITEM(t, "/threads/shared_sphere", NC_CKPT_U8, s->work.shared_sphere, n, 1);
    }
    /* output counters (the rows of dem.h5 at the checkpoint) */
    ITEM(t, "/output/steps", NC_CKPT_LONG, &o->n_out, 1, 1);
    ITEM(t, "/output/net_rows", NC_CKPT_LONG, &o->net_rows, 1, 1);
    ITEM(t, "/output/net_written", NC_CKPT_INT, &o->net_written, 1, 1);
}

/* The sizes, stored so that a loader can size the variable parts first. */
static void size_entries(nc_ckpt_table *t, sizes *z)
{
    ITEM(t, "/sizes/contacts", NC_CKPT_SIZE, &z->contacts, 1, 1);
    ITEM(t, "/sizes/neighbor_pairs", NC_CKPT_SIZE, &z->pairs, 1, 1);
    ITEM(t, "/sizes/threads", NC_CKPT_INT, &z->buffers, 1, 1);
}

/* ---- saving ---------------------------------------------------------------------------------- */

int dem_checkpoint_save(const char *path, const char *name, dem_sim *s, dem_output *o,
                        const nc_ckpt_table *extra, long step, double time_s, nc_error *err)
{
    (void)name;
    identity id;
    identity_of(s, &id);
    sizes z = {s->contact.list.n, s->nlist.first ? (size_t)s->nlist.first[s->model.sph.n] : 0,
               s->work.n_buffers};
    int format = DEM_CK_FORMAT;
    nc_ckpt_table t = {0};
    run_entries(&t, &format, &step, &time_s);
    identity_entries(&t, s, &id);
    size_entries(&t, &z);
    state_entries(&t, s, o, &z, 1);
    nc_ckpt_add_table(&t, extra);
    int rc = nc_ckpt_save(&t, path, err);
    nc_ckpt_table_free(&t);
    return rc;
}

/* ---- loading --------------------------------------------------------------------------------- */

/* Compares the identity stored in the file with this model's; names the first difference. */
static int check_identity(const char *path, dem_sim *s, const identity *mine, nc_error *err)
{
    identity there;
    memset(&there, 0, sizeof there);
    nc_ckpt_table t = {0};
    identity_count_entries(&t, &there);
    int rc = nc_ckpt_load(&t, path, err);
    nc_ckpt_table_free(&t);
    if (rc) return -1;
    for (size_t k = 0; k < N_ID_COUNTS; k++) {
        size_t a = *(const size_t *)((const char *)&there + ID_COUNTS[k].offset);
        size_t b = *(const size_t *)((const char *)mine + ID_COUNTS[k].offset);
        if (a != b)
            return nc_error_set(err, 1, "%s: is a checkpoint of another model: %s %zu in the "
                                "checkpoint, %zu in this model", path, ID_COUNTS[k].label, a, b);
    }
    if (memcmp(&there.dt_s, &mine->dt_s, sizeof there.dt_s) != 0)
        return nc_error_set(err, 1, "%s: is a checkpoint of another model: DEM step dt_s (s) "
                            "%.17g in the checkpoint, %.17g in this model", path, there.dt_s,
                            mine->dt_s);
    /* the arrays, now that the counts that size them agree */
    id_array a[N_ID_ARRAYS];
    size_t n = identity_arrays(s, mine, a);
    for (size_t k = 0; k < n && rc == 0; k++) {
        size_t vs = nc_ckpt_type_size(a[k].type), nv = a[k].rows * a[k].width;
        char *stored = malloc(nv * vs + 1);
        if (!stored) return nc_error_set(err, 1, "%s: out of memory", path);
        nc_ckpt_table one = {0};
        ITEM(&one, a[k].name, a[k].type, stored, a[k].rows, a[k].width);
        rc = nc_ckpt_load(&one, path, err);
        nc_ckpt_table_free(&one);
        size_t x = 0;
        while (rc == 0 && x < nv && memcmp(stored + x * vs, (const char *)a[k].data + x * vs, vs) == 0) x++;
        if (rc == 0 && x < nv) {
            char here[40], then[40];
            if (a[k].type == NC_CKPT_F64) {
                snprintf(then, sizeof then, "%.17g", ((const double *)(const void *)stored)[x]);
                snprintf(here, sizeof here, "%.17g", ((const double *)a[k].data)[x]);
            } else {
                snprintf(then, sizeof then, "%d", (int)((const int32_t *)(const void *)stored)[x]);
                snprintf(here, sizeof here, "%d", (int)((const int32_t *)a[k].data)[x]);
            }
            rc = nc_error_set(err, 1, "%s: is a checkpoint of another model: %s differ (entry "
                              "%zu: %s in the checkpoint, %s in this model)", path, a[k].label,
                              x / a[k].width, then, here);
        }
        free(stored);
    }
    return rc ? -1 : 0;
}

/* Room for the variable parts (contact records, Verlet pairs) of the state to be loaded; the
 * state itself is not changed. */
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

int dem_checkpoint_load(const char *path, dem_sim *s, dem_output *o, const nc_ckpt_table *extra,
                        long step, double time_s, nc_error *err)
{
    int format = 0;
    long saved_step = -1;
    double saved_time = 0.0;
    nc_ckpt_table t = {0};
    run_entries(&t, &format, &saved_step, &saved_time);
    int rc = nc_ckpt_load(&t, path, err);
    nc_ckpt_clear(&t);
    if (rc) goto done;
    rc = -1;
    if (format != DEM_CK_FORMAT) {
        nc_error_set(err, 1, "%s: checkpoint format %d, this dem_solver reads %d", path, format,
                     DEM_CK_FORMAT);
        goto done;
    }
    identity id;
    identity_of(s, &id);
    if (check_identity(path, s, &id, err)) goto done;
    if (saved_step != step || !(fabs(saved_time - time_s) <= 1e-9)) {
        nc_error_set(err, 1, "%s: is the checkpoint of step %ld at t = %.9g s, RESUME asks for "
                     "step %ld at t = %.9g s", path, saved_step, saved_time, step, time_s);
        goto done;
    }
    sizes z;
    memset(&z, 0, sizeof z);
    size_entries(&t, &z);
    if (nc_ckpt_load(&t, path, err)) goto done;
    nc_ckpt_clear(&t);
    if (z.pairs > (size_t)INT32_MAX || z.contacts > (size_t)INT32_MAX) {
        nc_error_set(err, 1, "%s: implausible sizes in /sizes", path);
        goto done;
    }
    if (reserve_state(s, &z, err)) goto done;
    /* all or nothing (nc_ckpt_load): a failure from here on leaves the state untouched */
    int same_threads = z.buffers == s->work.n_buffers;
    state_entries(&t, s, o, &z, same_threads);
    nc_ckpt_add_table(&t, extra);
    if (nc_ckpt_load(&t, path, err)) goto done;
    s->contact.list.n = z.contacts;
    /* thread ranges of another thread count cannot be used: rebuild the list at the next step */
    if (!same_threads) s->nlist.rebuild = 1;
    s->snap.valid = 0;
    rc = 0;
done:
    nc_ckpt_table_free(&t);
    return rc;
}
