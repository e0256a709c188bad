/* dem_output — HDF5 results and the XDMF index that lets ParaView show the particles. */
#include "dem_output.h"

#include "nc_file.h"

#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

int dem_output_open(dem_output *o, const dem_sim *s, const char *dir, nc_error *err)
{
    memset(o, 0, sizeof *o);
    o->h5.file = H5I_INVALID_HID;
    snprintf(o->dir, sizeof o->dir, "%s", dir);
    char path[1100];
    snprintf(path, sizeof path, "%s/dem.h5", dir);
    if (nc_h5_create(&o->h5, path, err)) return -1;
    hsize_t n = s->model.sph.n;
    if (n > 0) {
        int32_t *mat = malloc(n * sizeof *mat);
        if (!mat) return nc_error_set(err, 1, "dem: out of memory");
        for (size_t i = 0; i < n; i++) mat[i] = s->model.sph.material[i];
        int rc = nc_h5_write(&o->h5, "/particles/id", NC_H5_I32, 1, &n, s->model.sph.id, err) ||
                 nc_h5_write(&o->h5, "/particles/radius", NC_H5_F64, 1, &n, s->model.sph.radius, err) ||
                 nc_h5_write(&o->h5, "/particles/body", NC_H5_I32, 1, &n, s->model.sph.body, err) ||
                 nc_h5_write(&o->h5, "/particles/material", NC_H5_I32, 1, &n, mat, err);
        free(mat);
        if (rc) return -1;
    }
    hsize_t wall_dims[2] = {s->n_walls, 3};
    if (nc_h5_series_create(&o->h5, &o->time, "/time", NC_H5_F64, 1, NULL, err) ||
        nc_h5_series_create(&o->h5, &o->wall_force, "/walls/force", NC_H5_F64, 3, wall_dims, err) ||
        nc_h5_series_create(&o->h5, &o->kinetic, "/energy/kinetic", NC_H5_F64, 1, NULL, err))
        return -1;
    char names[4096] = "";
    for (size_t w = 0; w < s->n_walls; w++) {
        size_t used = strlen(names);
        if (w < s->model.n_planes) snprintf(names + used, sizeof names - used, "%splane%zu", w ? "," : "", w);
        else if (w < s->model.n_planes + s->model.n_meshes)
            snprintf(names + used, sizeof names - used, "%smesh%zu", w ? "," : "", w - s->model.n_planes);
        else snprintf(names + used, sizeof names - used, "%snet", w ? "," : "");
    }
    if (nc_h5_attr_string(&o->h5, "/walls/force", "walls", names, err) ||
        nc_h5_attr_string(&o->h5, "/", "program", "netcouple dem_solver", err))
        return -1;
    o->scratch = malloc((4 * s->model.bod.n + 4) * sizeof *o->scratch);
    if (!o->scratch) return nc_error_set(err, 1, "dem: out of memory");
    return nc_h5_flush(&o->h5, err);
}

/* Appends formatted text to a growing buffer (the XDMF grids of all output steps so far, so
 * that each step is formatted once and the file is rewritten with one fwrite). */
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

static int data_item(dem_text *t, nc_error *err, const char *dims, const char *type,
                     int precision, const char *path)
{
    return text_append(t, err, "          <DataItem Dimensions=\"%s\" NumberType=\"%s\" "
                               "Precision=\"%d\" Format=\"HDF\">dem.h5:%s</DataItem>\n",
                       dims, type, precision, path);
}

/* Formats the grids of output step k (particles, and the net when written). */
static int format_step(dem_output *o, const dem_sim *s, long k, nc_error *err)
{
    size_t n = s->model.sph.n;
    char nd[64], n3[64], group[64], p[128];
    snprintf(nd, sizeof nd, "%zu", n);
    snprintf(n3, sizeof n3, "%zu 3", n);
    snprintf(group, sizeof group, "/steps/%06ld", k);
    dem_text *t = &o->xdmf_particles;
    if (n > 0) {
        static const char *const vec[] = {"velocity", "angular_velocity"};
        if (text_append(t, err, "      <Grid Name=\"step_%06ld\" GridType=\"Uniform\">\n"
                                "        <Time Value=\"%.17g\"/>\n"
                                "        <Topology TopologyType=\"Polyvertex\" NumberOfElements=\"%zu\"/>\n"
                                "        <Geometry GeometryType=\"XYZ\">\n",
                        k, o->times[k], n))
            return -1;
        snprintf(p, sizeof p, "%s/position", group);
        if (data_item(t, err, n3, "Float", 8, p) ||
            text_append(t, err, "        </Geometry>\n"
                                "        <Attribute Name=\"radius\" AttributeType=\"Scalar\" Center=\"Node\">\n") ||
            data_item(t, err, nd, "Float", 8, "/particles/radius") ||
            text_append(t, err, "        </Attribute>\n"
                                "        <Attribute Name=\"id\" AttributeType=\"Scalar\" Center=\"Node\">\n") ||
            data_item(t, err, nd, "Int", 4, "/particles/id") ||
            text_append(t, err, "        </Attribute>\n"))
            return -1;
        for (int v = 0; v < 2; v++) {
            snprintf(p, sizeof p, "%s/%s", group, vec[v]);
            if (text_append(t, err, "        <Attribute Name=\"%s\" AttributeType=\"Vector\" Center=\"Node\">\n", vec[v]) ||
                data_item(t, err, n3, "Float", 8, p) ||
                text_append(t, err, "        </Attribute>\n"))
                return -1;
        }
        if (text_append(t, err, "      </Grid>\n")) return -1;
    }
    if (o->has_net[k]) {
        char ne[64], nn3[64];
        snprintf(ne, sizeof ne, "%zu 2", o->net_edges);
        snprintf(nn3, sizeof nn3, "%zu 3", o->net_nodes);
        t = &o->xdmf_net;
        if (text_append(t, err, "      <Grid Name=\"net_%06ld\" GridType=\"Uniform\">\n"
                                "        <Time Value=\"%.17g\"/>\n"
                                "        <Topology TopologyType=\"Polyline\" NodesPerElement=\"2\" "
                                "NumberOfElements=\"%zu\">\n",
                        k, o->times[k], o->net_edges) ||
            data_item(t, err, ne, "Int", 4, "/net/edges") ||
            text_append(t, err, "        </Topology>\n        <Geometry GeometryType=\"XYZ\">\n"))
            return -1;
        snprintf(p, sizeof p, "%s/net_position", group);
        if (data_item(t, err, nn3, "Float", 8, p) ||
            text_append(t, err, "        </Geometry>\n"
                                "        <Attribute Name=\"contact_force\" AttributeType=\"Vector\" Center=\"Node\">\n"))
            return -1;
        snprintf(p, sizeof p, "%s/net_force", group);
        if (data_item(t, err, nn3, "Float", 8, p) ||
            text_append(t, err, "        </Attribute>\n      </Grid>\n"))
            return -1;
    }
    return 0;
}

static int write_xdmf(const dem_output *o, nc_error *err)
{
    char path[1100], tmp[1120];
    snprintf(path, sizeof path, "%s/dem.xdmf", o->dir);
    FILE *f = nc_file_replace_open(path, tmp, sizeof tmp, err);
    if (!f) return -1;
    fputs("<?xml version=\"1.0\" ?>\n<Xdmf Version=\"2.0\">\n  <Domain>\n"
          "    <Grid Name=\"particles\" GridType=\"Collection\" CollectionType=\"Temporal\">\n", f);
    if (o->xdmf_particles.len) fwrite(o->xdmf_particles.data, 1, o->xdmf_particles.len, f);
    fputs("    </Grid>\n", f);
    if (o->xdmf_net.len) {
        fputs("    <Grid Name=\"net\" GridType=\"Collection\" CollectionType=\"Temporal\">\n", f);
        fwrite(o->xdmf_net.data, 1, o->xdmf_net.len, f);
        fputs("    </Grid>\n", f);
    }
    fputs("  </Domain>\n</Xdmf>\n", f);
    return nc_file_replace_commit(f, tmp, path, err);
}

int dem_output_write(dem_output *o, const dem_sim *s, const double *net_force, nc_error *err)
{
    if ((size_t)o->n_out >= o->times_cap) {
        size_t cap = o->times_cap ? 2 * o->times_cap : 64;
        double *t = realloc(o->times, cap * sizeof *t);
        int *h = realloc(o->has_net, cap * sizeof *h);
        if (t) o->times = t;
        if (h) o->has_net = h;
        if (!t || !h) return nc_error_set(err, 1, "dem: out of memory");
        o->times_cap = cap;
    }
    long k = o->n_out;
    char group[64], p[128];
    snprintf(group, sizeof group, "/steps/%06ld", k);
    size_t n = s->model.sph.n;
    if (n > 0) {
        hsize_t d[2] = {n, 3};
        snprintf(p, sizeof p, "%s/position", group);
        if (nc_h5_write(&o->h5, p, NC_H5_F64, 2, d, s->model.sph.pos, err)) return -1;
        snprintf(p, sizeof p, "%s/velocity", group);
        if (nc_h5_write(&o->h5, p, NC_H5_F64, 2, d, s->model.sph.vel, err)) return -1;
        /* angular velocity of each sphere = that of its body */
        double *w = malloc(3 * n * sizeof *w);
        if (!w) return nc_error_set(err, 1, "dem: out of memory");
        for (size_t i = 0; i < n; i++)
            memcpy(w + 3 * i, s->model.bod.omega + 3 * (size_t)s->model.sph.body[i], 3 * sizeof *w);
        snprintf(p, sizeof p, "%s/angular_velocity", group);
        int rc = nc_h5_write(&o->h5, p, NC_H5_F64, 2, d, w, err);
        free(w);
        if (rc) return -1;
    }
    size_t nc = 0;
    for (size_t b = 0; b < s->model.bod.n; b++) nc += s->model.bod.is_cluster[b] != 0;
    if (nc > 0) {
        size_t c = 0;
        for (size_t b = 0; b < s->model.bod.n; b++)
            if (s->model.bod.is_cluster[b]) memcpy(o->scratch + 4 * c++, s->model.bod.quat + 4 * b, 4 * sizeof(double));
        hsize_t d4[2] = {nc, 4}, d3[2] = {nc, 3};
        snprintf(p, sizeof p, "%s/cluster_orientation", group);
        if (nc_h5_write(&o->h5, p, NC_H5_F64, 2, d4, o->scratch, err)) return -1;
        c = 0;
        for (size_t b = 0; b < s->model.bod.n; b++)
            if (s->model.bod.is_cluster[b]) memcpy(o->scratch + 3 * c++, s->model.bod.pos + 3 * b, 3 * sizeof(double));
        snprintf(p, sizeof p, "%s/cluster_position", group);
        if (nc_h5_write(&o->h5, p, NC_H5_F64, 2, d3, o->scratch, err)) return -1;
    }
    o->has_net[k] = 0;
    if (s->model.net.active) {
        if (!o->net_written) {
            hsize_t de[2] = {s->model.net.n_edges, 2}, dn = s->model.net.n_nodes;
            if (nc_h5_write(&o->h5, "/net/edges", NC_H5_I32, 2, de, s->model.net.edges, err) ||
                nc_h5_write(&o->h5, "/net/node_ids", NC_H5_I32, 1, &dn, s->model.net.node_ids, err))
                return -1;
            o->net_written = 1;
            o->net_nodes = s->model.net.n_nodes;
            o->net_edges = s->model.net.n_edges;
        }
        hsize_t d[2] = {s->model.net.n_nodes, 3};
        snprintf(p, sizeof p, "%s/net_position", group);
        if (nc_h5_write(&o->h5, p, NC_H5_F64, 2, d, s->model.net.cur, err)) return -1;
        snprintf(p, sizeof p, "%s/net_force", group);
        if (nc_h5_write(&o->h5, p, NC_H5_F64, 2, d, net_force ? net_force : s->model.net.force, err))
            return -1;
        o->has_net[k] = 1;
    }
    double ke = dem_sim_kinetic_energy(s);
    if (nc_h5_series_append(&o->time, &s->time_s, err) ||
        nc_h5_series_append(&o->wall_force, s->wall_force, err) ||
        nc_h5_series_append(&o->kinetic, &ke, err))
        return -1;
    o->times[k] = s->time_s;
    o->n_out++;
    if (nc_h5_flush(&o->h5, err)) return -1;
    if (format_step(o, s, k, err)) return -1;
    return write_xdmf(o, err);
}

void dem_output_close(dem_output *o)
{
    nc_h5_series_close(&o->time);
    nc_h5_series_close(&o->wall_force);
    nc_h5_series_close(&o->kinetic);
    nc_h5_close(&o->h5);
    free(o->times);
    free(o->has_net);
    free(o->scratch);
    free(o->xdmf_particles.data);
    free(o->xdmf_net.data);
    memset(&o->xdmf_particles, 0, sizeof o->xdmf_particles);
    memset(&o->xdmf_net, 0, sizeof o->xdmf_net);
    o->times = NULL;
    o->has_net = NULL;
    o->scratch = NULL;
}
