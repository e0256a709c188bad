/* fem_output — HDF5 results and the XDMF index ParaView opens (layout in fem_output.h). */
#include "fem_output.h"

#include "nc_file.h"
#include "nc_clock.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

int fem_output_open(fem_output *o, const fem_model *m, const char *dir, nc_error *err)
{
    memset(o, 0, sizeof *o);
    snprintf(o->dir, sizeof o->dir, "%s", dir);
    char path[700];
    snprintf(path, sizeof path, "%s/fem.h5", dir);
    o->buf = malloc(3 * (size_t)(m->n_nodes > m->n_elements ? m->n_nodes : m->n_elements) * sizeof(double) + 8);
    if (!o->buf) return nc_error_set(err, 1, "out of memory");
    if (nc_h5_create(&o->h5, path, err)) return -1;
    o->open = 1;
    hsize_t n = (hsize_t)m->n_nodes, e = (hsize_t)m->n_elements, p = (hsize_t)m->n_monitor;
    hsize_t dx[2] = {n, 3}, de[2] = {e, 2}, dm[1] = {p}, row_n3[2] = {n, 3}, row_e[1] = {e},
            row_p3[2] = {p, 3};
    if (nc_h5_write(&o->h5, "/mesh/coordinates", NC_H5_F64, 2, dx, m->X, err) ||
        nc_h5_write(&o->h5, "/mesh/elements", NC_H5_I32, 2, de, m->conn, err) ||
        nc_h5_write(&o->h5, "/mesh/element_set", NC_H5_I32, 1, &e, m->element_set, err) ||
        nc_h5_write(&o->h5, "/monitor/node_ids", NC_H5_I32, 1, dm, m->monitor_nodes, err) ||
        nc_h5_attr_string(&o->h5, "/", "program", "netcouple fem_solver", err) ||
        nc_h5_attr_string(&o->h5, "/", "units", "SI: m, s, N, kg", err) ||
        nc_h5_series_create(&o->h5, &o->time, "/output/time", NC_H5_F64, 1, NULL, err) ||
        nc_h5_series_create(&o->h5, &o->step, "/output/step", NC_H5_I32, 1, NULL, err) ||
        nc_h5_series_create(&o->h5, &o->disp, "/output/displacement", NC_H5_F64, 3, row_n3, err) ||
        nc_h5_series_create(&o->h5, &o->vel, "/output/velocity", NC_H5_F64, 3, row_n3, err) ||
        nc_h5_series_create(&o->h5, &o->pos, "/output/position", NC_H5_F64, 3, row_n3, err) ||
        nc_h5_series_create(&o->h5, &o->axial, "/output/axial_force", NC_H5_F64, 2, row_e, err) ||
        nc_h5_series_create(&o->h5, &o->mon_time, "/monitor/time", NC_H5_F64, 1, NULL, err) ||
        nc_h5_series_create(&o->h5, &o->mon_disp, "/monitor/displacement", NC_H5_F64, 3, row_p3, err) ||
        nc_h5_series_create(&o->h5, &o->mon_vel, "/monitor/velocity", NC_H5_F64, 3, row_p3, err) ||
        nc_h5_flush(&o->h5, err))
        return -1;
    return 0;
}

int fem_output_monitor(fem_output *o, const fem_analysis *s, double time_s, nc_error *err)
{
    const fem_model *m = s->m;
    double *b = o->buf;
    if (nc_h5_series_append(&o->mon_time, &time_s, err)) return -1;
    for (int i = 0; i < m->n_monitor; i++)
        for (int c = 0; c < 3; c++) b[3 * i + c] = s->cur.u[3 * m->monitor_nodes[i] + c];
    if (nc_h5_series_append(&o->mon_disp, b, err)) return -1;
    for (int i = 0; i < m->n_monitor; i++)
        for (int c = 0; c < 3; c++) b[3 * i + c] = s->cur.v[3 * m->monitor_nodes[i] + c];
    return nc_h5_series_append(&o->mon_vel, b, err);
}

static int write_xdmf(fem_output *o, const fem_model *m, nc_error *err)
{
    char path[700], tmp[710];
    snprintf(path, sizeof path, "%s/fem.xdmf", o->dir);
    FILE *f = nc_file_replace_open(path, tmp, sizeof tmp, err);
    if (!f) return -1;
    int n = m->n_nodes, e = m->n_elements, k = o->n_out;
    fprintf(f, "<?xml version=\"1.0\" ?>\n<!DOCTYPE Xdmf SYSTEM \"Xdmf.dtd\" []>\n"
               "<Xdmf Version=\"2.0\">\n <Domain>\n"
               "  <Grid Name=\"net\" GridType=\"Collection\" CollectionType=\"Temporal\">\n");
    for (int i = 0; i < k; i++) {
        fprintf(f, "   <Grid Name=\"step%d\" GridType=\"Uniform\">\n    <Time Value=\"%.17g\"/>\n", i, o->times[i]);
        fprintf(f, "    <Topology TopologyType=\"Polyline\" NodesPerElement=\"2\" NumberOfElements=\"%d\">\n"
                   "     <DataItem Dimensions=\"%d 2\" NumberType=\"Int\" Format=\"HDF\">fem.h5:/mesh/elements</DataItem>\n"
                   "    </Topology>\n", e, e);
        /* current coordinates, so the net deforms without a Warp filter */
        const char *fields[3][3] = {{"Geometry", "", "/output/position"},
                                    {"Attribute", "displacement", "/output/displacement"},
                                    {"Attribute", "velocity", "/output/velocity"}};
        for (int a = 0; a < 3; a++) {
            if (a == 0) fprintf(f, "    <Geometry GeometryType=\"XYZ\">\n");
            else fprintf(f, "    <Attribute Name=\"%s\" AttributeType=\"Vector\" Center=\"Node\">\n", fields[a][1]);
            fprintf(f, "     <DataItem ItemType=\"HyperSlab\" Dimensions=\"%d 3\" Type=\"HyperSlab\">\n"
                       "      <DataItem Dimensions=\"3 3\" Format=\"XML\">%d 0 0 1 1 1 1 %d 3</DataItem>\n"
                       "      <DataItem Dimensions=\"%d %d 3\" NumberType=\"Float\" Precision=\"8\" Format=\"HDF\">fem.h5:%s</DataItem>\n"
                       "     </DataItem>\n", n, i, n, k, n, fields[a][2]);
            fprintf(f, a == 0 ? "    </Geometry>\n" : "    </Attribute>\n");
        }
        fprintf(f, "    <Attribute Name=\"axial_force\" AttributeType=\"Scalar\" Center=\"Cell\">\n"
                   "     <DataItem ItemType=\"HyperSlab\" Dimensions=\"%d\" Type=\"HyperSlab\">\n"
                   "      <DataItem Dimensions=\"3 2\" Format=\"XML\">%d 0 1 1 1 %d</DataItem>\n"
                   "      <DataItem Dimensions=\"%d %d\" NumberType=\"Float\" Precision=\"8\" Format=\"HDF\">fem.h5:/output/axial_force</DataItem>\n"
                   "     </DataItem>\n    </Attribute>\n   </Grid>\n", e, i, e, k, e);
    }
    fprintf(f, "  </Grid>\n </Domain>\n</Xdmf>\n");
    return nc_file_replace_commit(f, tmp, path, err);
}

int fem_output_step(fem_output *o, const fem_analysis *s, double time_s, nc_error *err)
{
    const fem_model *m = s->m;
    int step = (int)s->cur.step;
    for (int i = 0; i < 3 * m->n_nodes; i++) o->buf[i] = m->X[i] + s->cur.u[i];
    if (nc_h5_series_append(&o->time, &time_s, err) || nc_h5_series_append(&o->step, &step, err) ||
        nc_h5_series_append(&o->disp, s->cur.u, err) || nc_h5_series_append(&o->vel, s->cur.v, err) ||
        nc_h5_series_append(&o->pos, o->buf, err) || nc_h5_series_append(&o->axial, s->axial, err))
        return -1;
    if (o->n_out == o->cap) {
        int cap = o->cap ? 2 * o->cap : 64;
        double *t = realloc(o->times, (size_t)cap * sizeof *t);
        if (!t) return nc_error_set(err, 1, "out of memory");
        o->times = t;
        o->cap = cap;
    }
    o->times[o->n_out++] = time_s;
    if (nc_h5_flush(&o->h5, err)) return -1;
    /* The XDMF file grows with the number of output steps; rewriting it after each of
     * thousands of steps would cost O(k^2) bytes, so beyond 200 steps it is rewritten at
     * most every 2 s of wall time (and always on close). */
    double now = nc_clock_now_s();
    if (o->n_out <= 200 || now - o->last_xdmf_s > 2.0) {
        o->last_xdmf_s = now;
        o->xdmf_current = 1;
        return write_xdmf(o, m, err);
    }
    o->xdmf_current = 0;
    o->model = m;
    return 0;
}

void fem_output_close(fem_output *o)
{
    if (!o) return;
    nc_h5_series *all[] = {&o->time, &o->step, &o->disp, &o->vel, &o->pos, &o->axial,
                           &o->mon_time, &o->mon_disp, &o->mon_vel};
    if (o->open) {
        nc_error ignored;
        if (!o->xdmf_current && o->model) write_xdmf(o, o->model, &ignored);
        for (size_t i = 0; i < sizeof all / sizeof *all; i++) nc_h5_series_close(all[i]);
        nc_h5_flush(&o->h5, &ignored);
        nc_h5_close(&o->h5);
    }
    free(o->times);
    free(o->buf);
    memset(o, 0, sizeof *o);
}
