/* dem_output — HDF5 results and the XDMF index that lets ParaView show the particles. */
#include "dem_output.h"

#include <errno.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

int dem_output_open(dem_output *o, const dem_sim *s, const char *dir, nc_error *err)
{
    memset(o, 0, sizeof *o);
    o->h5.file = H5I_INVALID_HID;
    snprintf(o->dir, sizeof o->dir, "%s", dir);
    /* the files come later (create_files, dem_output_resume): an unwritable folder is
     * reported now */
    if (access(dir, W_OK) != 0)
        return nc_error_set(err, 1, "%s: cannot write results there: %s", dir, strerror(errno));
    size_t scratch = 4 * s->model.bod.n + 3 * s->model.sph.n + 4;
    o->scratch = malloc(scratch * sizeof *o->scratch);
    if (!o->scratch) return nc_error_set(err, 1, "%s: out of memory", dir);
    for (size_t b = 0; b < s->model.bod.n; b++) o->n_clusters += s->model.bod.is_cluster[b] != 0;
    return 0;
}

/* Creates dem.h5 with its fixed datasets and empty series (the first output step). */
static int create_files(dem_output *o, const dem_sim *s, nc_error *err)
{
    const char *dir = o->dir;
    char path[1100];
    snprintf(path, sizeof path, "%s/dem.h5", dir);
    if (nc_h5_create(&o->h5, path, err)) return -1;
    nc_h5_set_buffered(&o->h5);
    o->created = 1;
    /* index files of an earlier run in this folder would show stale or missing data */
    static const char *const stale[] = {"dem.xdmf", "particles.xdmf", "dem_net.xdmf"};
    for (size_t i = 0; i < sizeof stale / sizeof *stale; i++) {
        char old[1100];
        snprintf(old, sizeof old, "%s/%s", dir, stale[i]);
        remove(old);
    }
    nc_h5_file *h = &o->h5;
    hsize_t n = s->model.sph.n;
    if (n > 0) {
        int32_t *mat = malloc(n * sizeof *mat);
        if (!mat) return nc_error_set(err, 1, "%s: out of memory", path);
        for (size_t i = 0; i < n; i++) mat[i] = s->model.sph.material[i];
        hsize_t row[2] = {n, 3};
        int rc = nc_h5_write_units(h, "/particles/id", NC_H5_I32, 1, &n, s->model.sph.id, "1", err) ||
                 nc_h5_write_units(h, "/particles/radius", NC_H5_F64, 1, &n, s->model.sph.radius, "m", err) ||
                 nc_h5_write_units(h, "/particles/body", NC_H5_I32, 1, &n, s->model.sph.body, "1", err) ||
                 nc_h5_write_units(h, "/particles/material", NC_H5_I32, 1, &n, mat, "1", err) ||
                 nc_h5_series_create_units(h, &o->pos, "/particles/position", NC_H5_F64, 3, row, "m", err) ||
                 nc_h5_series_create_units(h, &o->vel, "/particles/velocity", NC_H5_F64, 3, row, "m/s", err) ||
                 nc_h5_series_create_units(h, &o->omega, "/particles/angular_velocity", NC_H5_F64, 3, row, "rad/s", err);
        /* one vertex cell per sphere, so ParaView shows the centres without a filter */
        for (size_t i = 0; i < n; i++) mat[i] = (int32_t)i;
        rc = rc || nc_h5_write_units(h, "/particles/vertex", NC_H5_I32, 1, &n, mat, "1", err);
        free(mat);
        if (rc) return -1;
    }
    if (o->n_clusters > 0) {
        hsize_t r3[2] = {o->n_clusters, 3}, r4[2] = {o->n_clusters, 4};
        if (nc_h5_series_create_units(h, &o->cl_pos, "/clusters/position", NC_H5_F64, 3, r3, "m", err) ||
            nc_h5_series_create_units(h, &o->cl_quat, "/clusters/orientation", NC_H5_F64, 3, r4, "1", err))
            return -1;
    }
    hsize_t wall_dims[2] = {s->n_walls, 3};
    if (nc_h5_series_create_units(h, &o->time, "/time", NC_H5_F64, 1, NULL, "s", err) ||
        nc_h5_series_create_units(h, &o->wall_force, "/walls/force", NC_H5_F64, 3, wall_dims, "N", err) ||
        nc_h5_series_create_units(h, &o->kinetic, "/energy/kinetic", NC_H5_F64, 1, NULL, "J", err))
        return -1;
    char names[4096] = "";
    for (size_t w = 0; w < s->n_walls; w++) {
        size_t used = strlen(names);
        if (w < s->model.n_planes) snprintf(names + used, sizeof names - used, "%splane%zu", w ? "," : "", w);
        else if (w < s->model.n_planes + s->model.n_meshes)
            snprintf(names + used, sizeof names - used, "%smesh%zu", w ? "," : "", w - s->model.n_planes);
        else snprintf(names + used, sizeof names - used, "%snet", w ? "," : "");
    }
    if (nc_h5_attr_string(h, "/walls/force", "walls", names, err) ||
        nc_h5_attr_string(h, "/", "program", "netcouple dem_solver", err) ||
        nc_h5_attr_string(h, "/", "units", "SI: m, s, N, kg", err))
        return -1;
    return nc_h5_flush(h, err);
}

/* Appends formatted text to a growing buffer (the XDMF grids of the steps being added). */
static int text_append(dem_text *t, nc_error *err, const char *format, ...)
    __attribute__((format(printf, 3, 4)));
static int text_append(dem_text *t, nc_error *err, const char *format, ...)
{
    for (;;) {
        size_t room = t->cap - t->len;
        va_list args;
        va_start(args, format);
        int n = t->data ? vsnprintf(t->data + t->len, room, format, args) : -1;
        va_end(args);
        if (n >= 0 && (size_t)n < room) {
            t->len += (size_t)n;
            return 0;
        }
        size_t cap = t->cap ? 2 * t->cap : 16384;
        while (n >= 0 && cap - t->len <= (size_t)n) cap *= 2;
        char *d = realloc(t->data, cap);
        if (!d) return nc_error_set(err, 1, "dem: out of memory for the XDMF text");
        t->data = d;
        t->cap = cap;
    }
}

/* One DataItem line: row k of a series (row_rank further dims) or, k < 0, a fixed dataset. */
static int data_item(dem_text *t, nc_error *err, const char *dataset, long k, int row_rank,
                     hsize_t d0, hsize_t d1, nc_h5_type type)
{
    char item[700];
    hsize_t dims[2] = {d0, d1};
    if (k >= 0) nc_xdmf_row_item(item, sizeof item, "dem.h5", dataset, k, row_rank, dims, type);
    else if (row_rank == 1)
        snprintf(item, sizeof item, "<DataItem Dimensions=\"%llu\" NumberType=\"%s\" Precision=\"%d\" "
                 "Format=\"HDF\">dem.h5:%s</DataItem>", (unsigned long long)d0,
                 type == NC_H5_F64 ? "Float" : "Int", type == NC_H5_F64 ? 8 : 4, dataset);
    else
        snprintf(item, sizeof item, "<DataItem Dimensions=\"%llu %llu\" NumberType=\"%s\" Precision=\"%d\" "
                 "Format=\"HDF\">dem.h5:%s</DataItem>", (unsigned long long)d0, (unsigned long long)d1,
                 type == NC_H5_F64 ? "Float" : "Int", type == NC_H5_F64 ? 8 : 4, dataset);
    return text_append(t, err, "          %s\n", item);
}

/* Formats the grids of output step k (particles, and the net when written: its row j). */
static int format_step(dem_output *o, const dem_sim *s, long k, double time_s, long net_row,
                       nc_error *err)
{
    size_t n = s->model.sph.n;
    dem_text *t = &o->xdmf_particles;
    if (n > 0) {
        static const char *const vec[] = {"velocity", "angular_velocity"};
        static const char *const path[] = {"/particles/velocity", "/particles/angular_velocity"};
        if (text_append(t, err, "      <Grid Name=\"step_%06ld\" GridType=\"Uniform\">\n"
                                "        <Time Value=\"%.17g\"/>\n"
                                "        <Topology TopologyType=\"Polyvertex\" NumberOfElements=\"%zu\" NodesPerElement=\"1\">\n",
                        k, time_s, n) ||
            data_item(t, err, "/particles/vertex", -1, 1, n, 0, NC_H5_I32) ||
            text_append(t, err, "        </Topology>\n        <Geometry GeometryType=\"XYZ\">\n") ||
            data_item(t, err, "/particles/position", k, 2, n, 3, NC_H5_F64) ||
            text_append(t, err, "        </Geometry>\n"
                                "        <Attribute Name=\"radius\" AttributeType=\"Scalar\" Center=\"Node\">\n") ||
            data_item(t, err, "/particles/radius", -1, 1, n, 0, NC_H5_F64) ||
            text_append(t, err, "        </Attribute>\n"
                                "        <Attribute Name=\"id\" AttributeType=\"Scalar\" Center=\"Node\">\n") ||
            data_item(t, err, "/particles/id", -1, 1, n, 0, NC_H5_I32) ||
            text_append(t, err, "        </Attribute>\n"))
            return -1;
        for (int v = 0; v < 2; v++)
            if (text_append(t, err, "        <Attribute Name=\"%s\" AttributeType=\"Vector\" Center=\"Node\">\n", vec[v]) ||
                data_item(t, err, path[v], k, 2, n, 3, NC_H5_F64) ||
                text_append(t, err, "        </Attribute>\n"))
                return -1;
        if (text_append(t, err, "      </Grid>\n")) return -1;
    }
    if (net_row >= 0) {
        t = &o->xdmf_net;
        if (text_append(t, err, "      <Grid Name=\"net_%06ld\" GridType=\"Uniform\">\n"
                                "        <Time Value=\"%.17g\"/>\n"
                                "        <Topology TopologyType=\"Polyline\" NodesPerElement=\"2\" "
                                "NumberOfElements=\"%zu\">\n",
                        k, time_s, o->net_edges) ||
            data_item(t, err, "/net/edges", -1, 2, o->net_edges, 2, NC_H5_I32) ||
            text_append(t, err, "        </Topology>\n        <Geometry GeometryType=\"XYZ\">\n") ||
            data_item(t, err, "/net/position", net_row, 2, o->net_nodes, 3, NC_H5_F64) ||
            text_append(t, err, "        </Geometry>\n"
                                "        <Attribute Name=\"contact_force\" AttributeType=\"Vector\" Center=\"Node\">\n") ||
            data_item(t, err, "/net/force", net_row, 2, o->net_nodes, 3, NC_H5_F64) ||
            text_append(t, err, "        </Attribute>\n      </Grid>\n"))
            return -1;
    }
    return 0;
}

static const char XDMF_TAIL[] = "    </Grid>\n  </Domain>\n</Xdmf>\n";

/* Adds the grids formatted in text to name (created with them when x holds no file yet) and
 * empties text. */
static int add_xdmf(dem_output *o, nc_xdmf_file *x, const char *name, const char *grid,
                    dem_text *text, nc_error *err)
{
    char path[1100], head[300];
    snprintf(path, sizeof path, "%s/%s", o->dir, name);
    snprintf(head, sizeof head, "<?xml version=\"1.0\" ?>\n<Xdmf Version=\"3.0\">\n  <Domain>\n"
             "    <Grid Name=\"%s\" GridType=\"Collection\" CollectionType=\"Temporal\">\n", grid);
    int rc = x->open ? nc_xdmf_append(x, text->data, text->len, err)
                     : nc_xdmf_create(x, path, head, text->data, text->len, XDMF_TAIL, err);
    if (rc == 0) text->len = 0;
    return rc;
}

/* The XDMF grids of the steps whose rows the last flush wrote (an XDMF file names only rows
 * that are on the disk). */
static int add_pending_xdmf(dem_output *o, nc_error *err)
{
    if (o->xdmf_particles.len > 0 &&
        add_xdmf(o, &o->particles_xdmf, "particles.xdmf", "particles", &o->xdmf_particles, err))
        return -1;
    if (o->xdmf_net.len > 0 && add_xdmf(o, &o->net_xdmf, "dem_net.xdmf", "net", &o->xdmf_net, err))
        return -1;
    return 0;
}

int dem_output_flush(dem_output *o, nc_error *err)
{
    if (!o->created) return 0;
    if (nc_h5_flush(&o->h5, err)) return -1;
    return add_pending_xdmf(o, err);
}

int dem_output_write(dem_output *o, const dem_sim *s, const double *net_force, nc_error *err)
{
    if (!o->created && create_files(o, s, err)) return -1;
    long k = o->n_out;
    size_t n = s->model.sph.n;
    if (n > 0) {
        /* angular velocity of each sphere = that of its body */
        double *w = o->scratch;
        for (size_t i = 0; i < n; i++)
            memcpy(w + 3 * i, s->model.bod.omega + 3 * (size_t)s->model.sph.body[i], 3 * sizeof *w);
        if (nc_h5_series_append(&o->pos, s->model.sph.pos, err) ||
            nc_h5_series_append(&o->vel, s->model.sph.vel, err) ||
            nc_h5_series_append(&o->omega, w, err))
            return -1;
    }
    if (o->n_clusters > 0) {
        size_t c = 0;
        for (size_t b = 0; b < s->model.bod.n; b++)
            if (s->model.bod.is_cluster[b]) memcpy(o->scratch + 4 * c++, s->model.bod.quat + 4 * b, 4 * sizeof(double));
        if (nc_h5_series_append(&o->cl_quat, o->scratch, err)) return -1;
        c = 0;
        for (size_t b = 0; b < s->model.bod.n; b++)
            if (s->model.bod.is_cluster[b]) memcpy(o->scratch + 3 * c++, s->model.bod.pos + 3 * b, 3 * sizeof(double));
        if (nc_h5_series_append(&o->cl_pos, o->scratch, err)) return -1;
    }
    long net_row = -1;
    if (s->model.net.active) {
        if (!o->net_written) {
            hsize_t de[2] = {s->model.net.n_edges, 2}, dn = s->model.net.n_nodes;
            hsize_t row[2] = {s->model.net.n_nodes, 3};
            if (nc_h5_write_units(&o->h5, "/net/edges", NC_H5_I32, 2, de, s->model.net.edges, "1", err) ||
                nc_h5_write_units(&o->h5, "/net/node_ids", NC_H5_I32, 1, &dn, s->model.net.node_ids, "1", err) ||
                nc_h5_attr_double(&o->h5, "/net", "first_output_step", (double)k, err) ||
                nc_h5_series_create_units(&o->h5, &o->net_pos, "/net/position", NC_H5_F64, 3, row, "m", err) ||
                nc_h5_series_create_units(&o->h5, &o->net_force, "/net/force", NC_H5_F64, 3, row, "N", err))
                return -1;
            o->net_written = 1;
            o->net_nodes = s->model.net.n_nodes;
            o->net_edges = s->model.net.n_edges;
        }
        if (s->model.net.n_nodes != o->net_nodes)
            return nc_error_set(err, 1, "%s: the net wall changed from %zu to %zu nodes", o->h5.path,
                                o->net_nodes, s->model.net.n_nodes);
        if (nc_h5_series_append(&o->net_pos, s->model.net.cur, err) ||
            nc_h5_series_append(&o->net_force, net_force ? net_force : s->model.net.force, err))
            return -1;
        net_row = o->net_rows++;
    }
    double ke = dem_sim_kinetic_energy(s);
    if (nc_h5_series_append(&o->time, &s->time_s, err) ||
        nc_h5_series_append(&o->wall_force, s->wall_force, err) ||
        nc_h5_series_append(&o->kinetic, &ke, err))
        return -1;
    o->n_out++;
    /* a grid formatted only in part (out of memory) is not left in the text to be written */
    size_t particles_len = o->xdmf_particles.len, net_len = o->xdmf_net.len;
    if (format_step(o, s, k, s->time_s, net_row, err)) {
        o->xdmf_particles.len = particles_len;
        o->xdmf_net.len = net_len;
        return -1;
    }
    /* the rows wait in memory (nc_h5_set_buffered) and are written every fraction of a second;
     * the first output step at once, so that the XDMF files exist from the start */
    int written = o->n_out == 1 ? (nc_h5_flush(&o->h5, err) ? -1 : 1) : nc_h5_flush_due(&o->h5, err);
    if (written < 0) return -1;
    return written ? add_pending_xdmf(o, err) : 0;
}

static int reopen_files(dem_output *o, const dem_sim *s, nc_error *err)
{
    char path[1100];
    snprintf(path, sizeof path, "%s/dem.h5", o->dir);
    if (o->n_out == 0) { /* nothing was written yet: the first output step creates the files */
        o->net_rows = 0;
        o->net_written = 0;
        return 0;
    }
    if (o->net_rows < 0 || o->net_rows > o->n_out || (o->net_rows > 0 && !o->net_written))
        return nc_error_set(err, 1, "%s: the checkpoint's output counters do not fit (%ld steps, "
                            "%ld net rows)", path, o->n_out, o->net_rows);
    if (nc_h5_open(&o->h5, path, err)) return -1;
    nc_h5_set_buffered(&o->h5);
    o->created = 1;
    nc_h5_file *h = &o->h5;
    hsize_t keep = (hsize_t)o->n_out, n = s->model.sph.n;
    hsize_t row[2] = {n, 3}, wall_dims[2] = {s->n_walls, 3};
    hsize_t r3[2] = {o->n_clusters, 3}, r4[2] = {o->n_clusters, 4};
    if (n > 0 && (nc_h5_series_open(h, &o->pos, "/particles/position", NC_H5_F64, 3, row, keep, err) ||
                  nc_h5_series_open(h, &o->vel, "/particles/velocity", NC_H5_F64, 3, row, keep, err) ||
                  nc_h5_series_open(h, &o->omega, "/particles/angular_velocity", NC_H5_F64, 3, row, keep, err)))
        return -1;
    if (o->n_clusters > 0 &&
        (nc_h5_series_open(h, &o->cl_pos, "/clusters/position", NC_H5_F64, 3, r3, keep, err) ||
         nc_h5_series_open(h, &o->cl_quat, "/clusters/orientation", NC_H5_F64, 3, r4, keep, err)))
        return -1;
    if (nc_h5_series_open(h, &o->time, "/time", NC_H5_F64, 1, NULL, keep, err) ||
        nc_h5_series_open(h, &o->wall_force, "/walls/force", NC_H5_F64, 3, wall_dims, keep, err) ||
        nc_h5_series_open(h, &o->kinetic, "/energy/kinetic", NC_H5_F64, 1, NULL, keep, err))
        return -1;
    if (o->net_written) {
        hsize_t net_row[2] = {s->model.net.n_nodes, 3};
        if (nc_h5_series_open(h, &o->net_pos, "/net/position", NC_H5_F64, 3, net_row, (hsize_t)o->net_rows, err) ||
            nc_h5_series_open(h, &o->net_force, "/net/force", NC_H5_F64, 3, net_row, (hsize_t)o->net_rows, err))
            return -1;
        o->net_nodes = s->model.net.n_nodes;
        o->net_edges = s->model.net.n_edges;
    } else if (H5Lexists(h->file, "/net", H5P_DEFAULT) > 0 && H5Ldelete(h->file, "/net", H5P_DEFAULT) < 0) {
        return nc_error_set(err, 1, "%s: cannot remove /net, written after the checkpoint", path);
    }
    /* the XDMF text of the rows kept, formatted as the run formatted it */
    double *times = malloc(keep * sizeof *times);
    if (!times) return nc_error_set(err, 1, "%s: out of memory", path);
    if (H5Dread(o->time.dataset, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, times) < 0) {
        free(times);
        return nc_error_set(err, 1, "%s: cannot read /time", path);
    }
    o->xdmf_particles.len = 0;
    o->xdmf_net.len = 0;
    nc_xdmf_close(&o->particles_xdmf);   /* written anew below, with the kept steps */
    nc_xdmf_close(&o->net_xdmf);
    long first_net = o->n_out - o->net_rows;
    int rc = 0;
    for (long k = 0; k < o->n_out && rc == 0; k++)
        rc = format_step(o, s, k, times[k], o->net_written && k >= first_net ? k - first_net : -1, err);
    free(times);
    if (rc || nc_h5_flush(h, err) || add_pending_xdmf(o, err)) return -1;
    if (o->net_rows > 0) return 0;
    char old[1100]; /* a later run's net grids (the net was not written at the checkpoint) */
    snprintf(old, sizeof old, "%s/dem_net.xdmf", o->dir);
    remove(old);
    return 0;
}

static void close_files(dem_output *o)
{
    nc_h5_series *all[] = {&o->time, &o->wall_force, &o->kinetic, &o->pos, &o->vel, &o->omega,
                           &o->cl_pos, &o->cl_quat, &o->net_pos, &o->net_force};
    for (size_t i = 0; i < sizeof all / sizeof *all; i++) nc_h5_series_close(all[i]);
    nc_h5_close(&o->h5);
    nc_xdmf_close(&o->particles_xdmf);
    nc_xdmf_close(&o->net_xdmf);
}

int dem_output_resume(dem_output *o, const dem_sim *s, nc_error *err)
{
    if (reopen_files(o, s, err) == 0) return 0;
    close_files(o); /* a second RESUME may try again */
    o->created = 0;
    o->xdmf_particles.len = 0;   /* the grids of the rows it could not reopen */
    o->xdmf_net.len = 0;
    return -1;
}

int dem_output_sync(dem_output *o, nc_error *err)
{
    if (!o->created) return 0;
    /* the file first, then the XDMF grids of what it now holds */
    if (nc_h5_sync(&o->h5, err)) return -1;
    return add_pending_xdmf(o, err);
}

void dem_output_close(dem_output *o)
{
    nc_error ignored;   /* the runs flush with dem_output_flush first, and report its error */
    dem_output_flush(o, &ignored);
    close_files(o);
    free(o->scratch);
    free(o->xdmf_particles.data);
    free(o->xdmf_net.data);
    memset(&o->xdmf_particles, 0, sizeof o->xdmf_particles);
    memset(&o->xdmf_net, 0, sizeof o->xdmf_net);
    o->scratch = NULL;
}
