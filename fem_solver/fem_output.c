/* fem_output — HDF5 results and the XDMF index ParaView opens (layout in fem_output.h). */
#include "fem_output.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static void free_peaks(fem_output *o)
{
    free(o->peak_n);
    free(o->peak_time_s);
    free(o->peak_element);
    free(o->exceeded_s);
    o->peak_n = o->peak_time_s = o->exceeded_s = NULL;
    o->peak_element = NULL;
}

/* Buffers and the support list of model m; support_dofs [3 n_nodes] into *dofs (caller frees). */
static int prepare(fem_output *o, const fem_model *m, const char *dir, const char *path,
                   int **dofs, nc_error *err)
{
    snprintf(o->dir, sizeof o->dir, "%s", dir);
    size_t big = (size_t)(m->n_nodes > m->n_elements ? m->n_nodes : m->n_elements);
    o->buf = malloc(3 * big * sizeof(double) + 8);
    o->force = malloc(3 * big * sizeof(double) + 8);
    o->support_nodes = malloc((size_t)m->n_nodes * sizeof(int) + 8);
    int *support_dofs = malloc(3 * (size_t)m->n_nodes * sizeof(int) + 8);
    if (!o->buf || !o->force || !o->support_nodes || !support_dofs) {
        free(support_dofs);
        return nc_error_set(err, 1, "%s: out of memory", path);
    }
    o->n_support = 0;
    for (int i = 0; i < m->n_nodes; i++) {
        const unsigned char *fx = m->fixed + 3 * i;
        if (!(fx[0] || fx[1] || fx[2])) continue;
        for (int c = 0; c < 3; c++) support_dofs[3 * o->n_support + c] = fx[c] != 0;
        o->support_nodes[o->n_support++] = i;
    }
    *dofs = support_dofs;
    return fem_output_reserve_peaks(o, m, err);
}

int fem_output_reserve_peaks(fem_output *o, const fem_model *m, nc_error *err)
{
    if (o->peak_n) return 0;
    size_t k = (size_t)m->n_sets, e = (size_t)m->n_elements;
    o->peak_n = calloc(k + 1, sizeof *o->peak_n);
    o->peak_time_s = calloc(k + 1, sizeof *o->peak_time_s);
    o->peak_element = malloc((k + 1) * sizeof *o->peak_element);
    o->exceeded_s = malloc((e + 1) * sizeof *o->exceeded_s);
    if (!o->peak_n || !o->peak_time_s || !o->peak_element || !o->exceeded_s) {
        free_peaks(o);
        return nc_error_set(err, 1, "out of memory for the peak forces of %zu element sets", k);
    }
    for (size_t i = 0; i < k; i++) o->peak_element[i] = -1;
    for (size_t i = 0; i < e; i++) o->exceeded_s[i] = -1.0;
    return 0;
}

int fem_output_open(fem_output *o, const fem_model *m, const char *dir, nc_error *err)
{
    memset(o, 0, sizeof *o);
    o->max_u_node = -1;
    char path[700];
    snprintf(path, sizeof path, "%s/fem.h5", dir);
    int *support_dofs = NULL;
    if (prepare(o, m, dir, path, &support_dofs, err)) return -1;
    if (nc_h5_create(&o->h5, path, err)) {
        free(support_dofs);
        return -1;
    }
    nc_h5_set_buffered(&o->h5);
    o->open = 1;
    hsize_t n = (hsize_t)m->n_nodes, e = (hsize_t)m->n_elements, p = (hsize_t)m->n_monitor,
            r = (hsize_t)o->n_support;
    hsize_t dx[2] = {n, 3}, de[2] = {e, 2}, dm[1] = {p}, dr[2] = {r, 3}, row_n3[2] = {n, 3},
            row_e[1] = {e}, row_p3[2] = {p, 3}, row_r3[2] = {r, 3};
    nc_h5_file *h = &o->h5;
    int rc = nc_h5_write_units(h, "/mesh/coordinates", NC_H5_F64, 2, dx, m->X, "m", err) ||
             nc_h5_write_units(h, "/mesh/elements", NC_H5_I32, 2, de, m->conn, "1", err) ||
             nc_h5_write_units(h, "/mesh/element_set", NC_H5_I32, 1, &e, m->element_set, "1", err) ||
             nc_h5_write_units(h, "/mesh/reference_length", NC_H5_F64, 1, &e, m->L0, "m", err) ||
             nc_h5_write_units(h, "/mesh/support_nodes", NC_H5_I32, 1, &r, o->support_nodes, "1", err) ||
             nc_h5_write_units(h, "/mesh/support_dofs", NC_H5_I32, 2, dr, support_dofs, "1", err) ||
             nc_h5_write_units(h, "/monitor/node_ids", NC_H5_I32, 1, dm, m->monitor_nodes, "1", err) ||
             nc_h5_attr_string(h, "/", "program", "netcouple fem_solver", err) ||
             nc_h5_attr_string(h, "/", "units", "SI: m, s, N, kg", err) ||
             nc_h5_series_create_units(h, &o->time, "/output/time", NC_H5_F64, 1, NULL,
                                       m->settings.type == FEM_STATIC ? "1" : "s", err) ||
             nc_h5_series_create_units(h, &o->step, "/output/step", NC_H5_I32, 1, NULL, "1", err) ||
             nc_h5_series_create_units(h, &o->load, "/output/load_factor", NC_H5_F64, 1, NULL, "1", err) ||
             nc_h5_series_create_units(h, &o->disp, "/output/displacement", NC_H5_F64, 3, row_n3, "m", err) ||
             nc_h5_series_create_units(h, &o->vel, "/output/velocity", NC_H5_F64, 3, row_n3, "m/s", err) ||
             nc_h5_series_create_units(h, &o->pos, "/output/position", NC_H5_F64, 3, row_n3, "m", err) ||
             nc_h5_series_create_units(h, &o->axial, "/output/axial_force", NC_H5_F64, 2, row_e, "N", err) ||
             nc_h5_series_create_units(h, &o->strain, "/output/strain", NC_H5_F64, 2, row_e, "1", err) ||
             nc_h5_series_create_units(h, &o->reaction, "/output/reaction", NC_H5_F64, 3, row_r3, "N", err) ||
             nc_h5_series_create_units(h, &o->mon_time, "/monitor/time", NC_H5_F64, 1, NULL,
                                       m->settings.type == FEM_STATIC ? "1" : "s", err) ||
             nc_h5_series_create_units(h, &o->mon_disp, "/monitor/displacement", NC_H5_F64, 3, row_p3, "m", err) ||
             nc_h5_series_create_units(h, &o->mon_vel, "/monitor/velocity", NC_H5_F64, 3, row_p3, "m/s", err) ||
             (m->history_count > 0 &&
              (nc_h5_series_create_units(h, &o->stroke, "/output/element_stroke", NC_H5_F64, 2, row_e, "m", err) ||
               nc_h5_series_create_units(h, &o->dissipated, "/output/element_dissipated_energy", NC_H5_F64, 2, row_e, "J", err))) ||
             nc_h5_flush(h, err);
    o->has_history = !rc && m->history_count > 0;
    free(support_dofs);
    return rc ? -1 : 0;
}

int fem_output_reserve_times(fem_output *o, int count, nc_error *err)
{
    if (count <= o->cap) return 0;
    double *t = realloc(o->times, (size_t)count * sizeof *t);
    if (!t) return nc_error_set(err, 1, "out of memory for %d output times", count);
    o->times = t;
    o->cap = count;
    return 0;
}

static int write_xdmf(fem_output *o, const fem_model *m, nc_error *err);

/* The XDMF grids of the output steps fem.h5 holds since its last write and fem.xdmf does not
 * list yet. */
static int write_new_grids(fem_output *o, nc_error *err)
{
    return o->model && o->n_xdmf < o->n_out ? write_xdmf(o, o->model, err) : 0;
}

int fem_output_write_due(fem_output *o, nc_error *err)
{
    int written = nc_h5_flush_due(&o->h5, err);
    if (written < 0) return -1;
    return written ? write_new_grids(o, err) : 0;
}

static void close_series(fem_output *o)
{
    nc_h5_series *all[] = {&o->time, &o->step, &o->load, &o->disp, &o->vel, &o->pos, &o->axial,
                           &o->strain, &o->reaction, &o->mon_time, &o->mon_disp, &o->mon_vel};
    for (size_t i = 0; i < sizeof all / sizeof *all; i++) nc_h5_series_close(all[i]);
    nc_h5_series_close(&o->stroke);       /* no-ops when the model has no element history */
    nc_h5_series_close(&o->dissipated);
}

/* Closes without writing anything more (a reopen that failed). */
static void discard(fem_output *o)
{
    close_series(o);
    nc_h5_close(&o->h5);
    nc_xdmf_close(&o->xdmf);
    free(o->times);
    free(o->buf);
    free(o->force);
    free(o->support_nodes);
    free_peaks(o);
    memset(o, 0, sizeof *o);
    o->max_u_node = -1;
}

/* Rows of dataset `path` of an open file, -1 when it is missing. */
static long rows_of(const nc_h5_file *h, const char *path)
{
    if (H5Lexists(h->file, path, H5P_DEFAULT) <= 0) return -1;
    hid_t d = H5Dopen2(h->file, path, H5P_DEFAULT);
    if (d < 0) return -1;
    hid_t space = H5Dget_space(d);
    hsize_t dims[3] = {0, 0, 0};
    long rows = -1;
    if (space >= 0 && H5Sget_simple_extent_ndims(space) >= 1 && H5Sget_simple_extent_ndims(space) <= 3 &&
        H5Sget_simple_extent_dims(space, dims, NULL) >= 0)
        rows = (long)dims[0];
    if (space >= 0) H5Sclose(space);
    H5Dclose(d);
    return rows;
}

int fem_output_reopen(fem_output *o, const fem_model *m, const char *dir, nc_error *err)
{
    char path[700];
    snprintf(path, sizeof path, "%s/fem.h5", dir);
    int *support_dofs = NULL;
    if (o->n_out < 0 || o->n_out > o->cap || o->n_mon < 0)
        return nc_error_set(err, 1, "%s: %d output rows and %ld monitor rows cannot be resumed",
                            path, o->n_out, o->n_mon);
    if (prepare(o, m, dir, path, &support_dofs, err)) return -1;
    free(support_dofs);
    if (nc_h5_open(&o->h5, path, err)) {
        discard(o);
        return -1;
    }
    nc_h5_set_buffered(&o->h5);
    /* every series holds at least the checkpoint's rows before any is cut (a file older than
     * the checkpoint is left as it is) */
    static const char *const out_series[] = {"/output/time", "/output/step", "/output/load_factor",
        "/output/displacement", "/output/velocity", "/output/position", "/output/axial_force",
        "/output/strain", "/output/reaction"};
    static const char *const mon_series[] = {"/monitor/time", "/monitor/displacement",
                                             "/monitor/velocity"};
    static const char *const history_series[] = {"/output/element_stroke",
                                                 "/output/element_dissipated_energy"};
    for (int pass = 0; pass < 3; pass++)
        for (int i = 0; i < (pass == 2 ? (m->history_count > 0 ? 2 : 0) : pass ? 3 : 9); i++) {
            const char *name = pass == 2 ? history_series[i] : pass ? mon_series[i] : out_series[i];
            long have = rows_of(&o->h5, name), need = pass == 1 ? o->n_mon : o->n_out;
            if (have < need) {
                if (have < 0) nc_error_set(err, 1, "%s: has no dataset %s to append to", path, name);
                else nc_error_set(err, 1, "%s: dataset %s has %ld rows, the checkpoint needs %ld "
                                  "(the file is older than the checkpoint)", path, name, have, need);
                discard(o);
                return -1;
            }
        }
    o->open = 1;
    hsize_t n = (hsize_t)m->n_nodes, e = (hsize_t)m->n_elements, p = (hsize_t)m->n_monitor,
            r = (hsize_t)o->n_support, k = (hsize_t)o->n_out, s = (hsize_t)o->n_mon;
    hsize_t row_n3[2] = {n, 3}, row_e[1] = {e}, row_p3[2] = {p, 3}, row_r3[2] = {r, 3};
    nc_h5_file *h = &o->h5;
    /* rows written after the checkpoint are cut off; later output is appended */
    int rc = nc_h5_series_open(h, &o->time, "/output/time", NC_H5_F64, 1, NULL, k, err) ||
             nc_h5_series_open(h, &o->step, "/output/step", NC_H5_I32, 1, NULL, k, err) ||
             nc_h5_series_open(h, &o->load, "/output/load_factor", NC_H5_F64, 1, NULL, k, err) ||
             nc_h5_series_open(h, &o->disp, "/output/displacement", NC_H5_F64, 3, row_n3, k, err) ||
             nc_h5_series_open(h, &o->vel, "/output/velocity", NC_H5_F64, 3, row_n3, k, err) ||
             nc_h5_series_open(h, &o->pos, "/output/position", NC_H5_F64, 3, row_n3, k, err) ||
             nc_h5_series_open(h, &o->axial, "/output/axial_force", NC_H5_F64, 2, row_e, k, err) ||
             nc_h5_series_open(h, &o->strain, "/output/strain", NC_H5_F64, 2, row_e, k, err) ||
             nc_h5_series_open(h, &o->reaction, "/output/reaction", NC_H5_F64, 3, row_r3, k, err) ||
             nc_h5_series_open(h, &o->mon_time, "/monitor/time", NC_H5_F64, 1, NULL, s, err) ||
             nc_h5_series_open(h, &o->mon_disp, "/monitor/displacement", NC_H5_F64, 3, row_p3, s, err) ||
             nc_h5_series_open(h, &o->mon_vel, "/monitor/velocity", NC_H5_F64, 3, row_p3, s, err) ||
             (m->history_count > 0 &&
              (nc_h5_series_open(h, &o->stroke, "/output/element_stroke", NC_H5_F64, 2, row_e, k, err) ||
               nc_h5_series_open(h, &o->dissipated, "/output/element_dissipated_energy", NC_H5_F64, 2, row_e, k, err))) ||
             nc_h5_flush(h, err);
    o->has_history = !rc && m->history_count > 0;
    if (rc) {
        discard(o);
        return -1;
    }
    /* the XDMF index lists exactly the rows kept */
    o->model = m;
    nc_xdmf_close(&o->xdmf);
    return write_xdmf(o, m, err);
}

int fem_output_monitor(fem_output *o, const fem_analysis *s, double time_s, nc_error *err)
{
    const fem_model *m = s->m;
    double *b = o->buf;
    for (int i = 0; i < m->n_nodes; i++) {
        const double *u = s->cur.u + 3 * i;
        double mag = sqrt(u[0] * u[0] + u[1] * u[1] + u[2] * u[2]);
        if (o->max_u_node < 0 || mag > o->max_u_m) {
            o->max_u_m = mag;
            o->max_u_time_s = time_s;
            o->max_u_node = i;
        }
    }
    /* every step, not only output steps: a peak between two output steps counts */
    for (int e = 0; o->peak_n && e < m->n_elements; e++) {
        const int k = m->element_set[e];
        const double f = s->axial[e], limit = m->sets[k].breaking_load_n;
        if (o->peak_element[k] < 0 || f > o->peak_n[k]) {
            o->peak_n[k] = f;
            o->peak_time_s[k] = time_s;
            o->peak_element[k] = e;
        }
        if (limit > 0.0 && f > limit && o->exceeded_s[e] < 0.0) o->exceeded_s[e] = time_s;
    }
    if (nc_h5_series_append(&o->mon_time, &time_s, err)) return -1;
    o->n_mon++;
    for (int i = 0; i < m->n_monitor; i++)
        for (int c = 0; c < 3; c++) b[3 * i + c] = s->cur.u[3 * m->monitor_nodes[i] + c];
    if (nc_h5_series_append(&o->mon_disp, b, err)) return -1;
    for (int i = 0; i < m->n_monitor; i++)
        for (int c = 0; c < 3; c++) b[3 * i + c] = s->cur.v[3 * m->monitor_nodes[i] + c];
    return nc_h5_series_append(&o->mon_vel, b, err);
}

void fem_output_reactions(fem_output *o, const fem_analysis *s, double lambda, double *r)
{
    /* The support takes what the net's own balance leaves on a prescribed dof:
     * R = F_int(u) + M a + C v - lambda f_model - f_coupling, C = tau M + kappa K_T(u_n). */
    const fem_model *m = s->m;
    double *f = o->force;
    fem_analysis_node_balance(s, lambda, f);   /* every element type's forces */
    for (int i = 0; i < o->n_support; i++) {
        int node = o->support_nodes[i];
        for (int c = 0; c < 3; c++)
            r[3 * i + c] = m->fixed[3 * node + c] ? f[3 * node + c] : 0.0;
    }
}

/* One attribute of a grid: row i of a series. */
static void attribute(FILE *f, const char *name, const char *kind, const char *center,
                      const char *dataset, long i, int row_rank, const hsize_t *row_dims)
{
    char item[600];
    nc_xdmf_row_item(item, sizeof item, "fem.h5", dataset, i, row_rank, row_dims, NC_H5_F64);
    fprintf(f, "    <Attribute Name=\"%s\" AttributeType=\"%s\" Center=\"%s\">\n     %s\n"
               "    </Attribute>\n", name, kind, center, item);
}

/* The grid of output step i (time t). */
static void format_grid(FILE *f, const fem_model *m, int i, double t)
{
    char item[600];
    int e = m->n_elements;
    hsize_t n3[2] = {(hsize_t)m->n_nodes, 3}, e1[1] = {(hsize_t)e};
    fprintf(f, "   <Grid Name=\"step%d\" GridType=\"Uniform\">\n    <Time Value=\"%.17g\"/>\n", i, t);
    fprintf(f, "    <Topology TopologyType=\"Polyline\" NodesPerElement=\"2\" NumberOfElements=\"%d\">\n"
               "     <DataItem Dimensions=\"%d 2\" NumberType=\"Int\" Precision=\"4\" Format=\"HDF\">fem.h5:/mesh/elements</DataItem>\n"
               "    </Topology>\n", e, e);
    /* current coordinates, so the net deforms without a Warp filter */
    nc_xdmf_row_item(item, sizeof item, "fem.h5", "/output/position", i, 2, n3, NC_H5_F64);
    fprintf(f, "    <Geometry GeometryType=\"XYZ\">\n     %s\n    </Geometry>\n", item);
    attribute(f, "displacement", "Vector", "Node", "/output/displacement", i, 2, n3);
    attribute(f, "velocity", "Vector", "Node", "/output/velocity", i, 2, n3);
    attribute(f, "axial_force", "Scalar", "Cell", "/output/axial_force", i, 1, e1);
    attribute(f, "strain", "Scalar", "Cell", "/output/strain", i, 1, e1);
    fprintf(f, "   </Grid>\n");
}

/* Adds the grids of the output steps fem.xdmf does not list yet (n_xdmf .. n_out-1, rows the
 * caller has just written to fem.h5) to it; written anew with all of them when it is not open
 * yet (the first output step, or a resumed run's kept rows). */
static int write_xdmf(fem_output *o, const fem_model *m, nc_error *err)
{
    static const char head[] = "<?xml version=\"1.0\" ?>\n<Xdmf Version=\"3.0\">\n <Domain>\n"
                               "  <Grid Name=\"net\" GridType=\"Collection\" CollectionType=\"Temporal\">\n";
    static const char tail[] = "  </Grid>\n </Domain>\n</Xdmf>\n";
    char path[700], *text = NULL;
    size_t len = 0;
    snprintf(path, sizeof path, "%s/fem.xdmf", o->dir);
    int first = o->xdmf.open ? o->n_xdmf : 0;
    FILE *f = open_memstream(&text, &len);
    if (!f) return nc_error_set(err, 1, "%s: out of memory", path);
    for (int i = first; i < o->n_out; i++) format_grid(f, m, i, o->times[i]);
    int bad = fclose(f) != 0 || !text;
    int rc = bad ? nc_error_set(err, 1, "%s: out of memory", path)
             : o->xdmf.open ? nc_xdmf_append(&o->xdmf, text, len, err)
                            : nc_xdmf_create(&o->xdmf, path, head, text, len, tail, err);
    free(text);
    if (rc == 0) o->n_xdmf = o->n_out;
    return rc;
}

/* fem.h5's rows (to the disk: sync), then the XDMF grids of the steps it now holds */
static int write_rows_and_grids(fem_output *o, int sync, nc_error *err)
{
    if (!o->open) return 0;
    if (sync ? nc_h5_sync(&o->h5, err) : nc_h5_flush(&o->h5, err)) return -1;
    return write_new_grids(o, err);
}

int fem_output_flush(fem_output *o, nc_error *err)
{
    return write_rows_and_grids(o, 0, err);
}

int fem_output_sync(fem_output *o, nc_error *err)
{
    return write_rows_and_grids(o, 1, err);
}

int fem_output_step(fem_output *o, const fem_analysis *s, double time_s, nc_error *err)
{
    const fem_model *m = s->m;
    int step = (int)s->cur.step;
    double lambda = m->settings.type == FEM_STATIC ? time_s : fem_analysis_load_factor(s, time_s);
    for (int i = 0; i < 3 * m->n_nodes; i++) o->buf[i] = m->X[i] + s->cur.u[i];
    if (nc_h5_series_append(&o->time, &time_s, err) || nc_h5_series_append(&o->step, &step, err) ||
        nc_h5_series_append(&o->load, &lambda, err) ||
        nc_h5_series_append(&o->disp, s->cur.u, err) || nc_h5_series_append(&o->vel, s->cur.v, err) ||
        nc_h5_series_append(&o->pos, o->buf, err) || nc_h5_series_append(&o->axial, s->axial, err))
        return -1;
    for (int e = 0; e < m->n_elements; e++) {
        const int k = 3 * m->conn[2 * e], l = 3 * m->conn[2 * e + 1];
        double len2 = 0.0;
        for (int c = 0; c < 3; c++) {
            double d = o->buf[l + c] - o->buf[k + c];
            len2 += d * d;
        }
        o->force[e] = (sqrt(len2) - m->L0[e]) / m->L0[e];
    }
    if (nc_h5_series_append(&o->strain, o->force, err)) return -1;
    if (o->has_history) {
        fem_analysis_element_history_output(s, o->force, NULL);
        if (nc_h5_series_append(&o->stroke, o->force, err)) return -1;
        fem_analysis_element_history_output(s, NULL, o->force);
        if (nc_h5_series_append(&o->dissipated, o->force, err)) return -1;
    }
    fem_output_reactions(o, s, lambda, o->buf);
    if (nc_h5_series_append(&o->reaction, o->buf, err)) return -1;
    if (o->n_out == o->cap && fem_output_reserve_times(o, o->cap ? 2 * o->cap : 64, err)) return -1;
    o->times[o->n_out++] = time_s;
    o->model = m;
    /* the first output step at once, so that fem.xdmf exists from the start; the others
     * when due (fem_output_write_due, at the end of the step) */
    return o->xdmf.open ? 0 : fem_output_flush(o, err);
}

int fem_output_overload(const fem_output *o, const fem_model *m, fem_set_overload *per_set)
{
    int total = 0;
    for (int k = 0; per_set && k < m->n_sets; k++)
        per_set[k] = (fem_set_overload){m->sets[k].breaking_load_n, 0.0, -1.0, -1, 0, -1.0};
    if (!o->peak_n) return 0;
    for (int e = 0; e < m->n_elements; e++) {
        if (o->exceeded_s[e] < 0.0) continue;
        total++;
        if (!per_set) continue;
        fem_set_overload *r = per_set + m->element_set[e];
        if (r->exceeded++ == 0 || o->exceeded_s[e] < r->first_time_s) r->first_time_s = o->exceeded_s[e];
    }
    for (int k = 0; per_set && k < m->n_sets; k++) {
        per_set[k].peak_n = o->peak_n[k];
        per_set[k].peak_time_s = o->peak_time_s[k];
        per_set[k].peak_element = o->peak_element[k];
    }
    return total;
}

void fem_set_overload_text(const fem_model *m, int k, const fem_set_overload *r, char *out,
                           size_t size)
{
    const char *at = m->settings.type == FEM_STATIC ? "load factor" : "t =",
               *unit = m->settings.type == FEM_STATIC ? "" : " s";
    double ratio = r->peak_n / r->breaking_load_n;
    if (r->exceeded > 0)
        snprintf(out, size, "warning: set %s: %d element%s exceeded breaking_load_n %g N (first at "
                 "%s %g%s); largest %g N (%.3gx) in element %d at %s %g%s; the model has no rope "
                 "failure, forces beyond the breaking load are not physical", m->sets[k].name,
                 r->exceeded, r->exceeded == 1 ? "" : "s", r->breaking_load_n, at, r->first_time_s,
                 unit, r->peak_n, ratio, r->peak_element, at, r->peak_time_s, unit);
    else
        snprintf(out, size, "set %s: largest axial force %g N, %.3gx breaking_load_n %g N, in "
                 "element %d at %s %g%s", m->sets[k].name, r->peak_n, ratio, r->breaking_load_n,
                 r->peak_element, at, r->peak_time_s, unit);
}

/* /element_sets and the root's overload attributes (layout in fem_output.h). */
static int write_overload(fem_output *o, const fem_model *m, nc_error *err)
{
    int n = m->n_sets;
    fem_set_overload *r = malloc((size_t)n * sizeof *r);
    double *d = malloc(4 * (size_t)n * sizeof *d);
    int *i32 = malloc(2 * (size_t)n * sizeof *i32);
    char *text = malloc((size_t)n * 512 + 1);
    if (!r || !d || !i32 || !text) {
        free(r); free(d); free(i32); free(text);
        return nc_error_set(err, 1, "%s: out of memory for the set summary", o->h5.path);
    }
    int total = fem_output_overload(o, m, r), checked = 0;
    size_t len = 0;
    text[0] = '\0';
    for (int k = 0; k < n; k++) {
        d[k] = r[k].breaking_load_n;
        d[n + k] = r[k].peak_n;
        d[2 * n + k] = r[k].peak_time_s;
        d[3 * n + k] = r[k].first_time_s;
        i32[k] = r[k].peak_element;
        i32[n + k] = r[k].exceeded;
        checked |= r[k].breaking_load_n > 0.0;
        if (r[k].exceeded > 0) {
            if (len) text[len++] = '\n';
            fem_set_overload_text(m, k, r + k, text + len, 511);
            len += strlen(text + len);
        }
    }
    hsize_t k = (hsize_t)n, e = (hsize_t)m->n_elements;
    const char *ts = m->settings.type == FEM_STATIC ? "1" : "s";
    nc_h5_file *h = &o->h5;
    int rc = nc_h5_write_units(h, "/element_sets/breaking_load", NC_H5_F64, 1, &k, d, "N", err) ||
             nc_h5_write_units(h, "/element_sets/peak_axial_force", NC_H5_F64, 1, &k, d + n, "N", err) ||
             nc_h5_write_units(h, "/element_sets/peak_time", NC_H5_F64, 1, &k, d + 2 * n, ts, err) ||
             nc_h5_write_units(h, "/element_sets/peak_element", NC_H5_I32, 1, &k, i32, "1", err) ||
             nc_h5_write_units(h, "/element_sets/exceeded_elements", NC_H5_I32, 1, &k, i32 + n, "1", err) ||
             nc_h5_write_units(h, "/element_sets/first_exceedance_time", NC_H5_F64, 1, &k, d + 3 * n, ts, err) ||
             nc_h5_write_units(h, "/element_sets/element_exceedance_time", NC_H5_F64, 1, &e,
                               o->exceeded_s, ts, err) ||
             (checked && nc_h5_attr_double(h, "/", "overloaded_elements", total, err)) ||
             (total > 0 && nc_h5_attr_string(h, "/", "overload", text, err));
    /* a resumed run's file may hold the warnings of the run it continues beyond the checkpoint */
    if (!rc && total == 0 && !h->failed && H5Aexists_by_name(h->file, "/", "overload", H5P_DEFAULT) > 0)
        H5Adelete_by_name(h->file, "/", "overload", H5P_DEFAULT);
    free(r); free(d); free(i32); free(text);
    return rc ? -1 : 0;
}

int fem_output_finish(fem_output *o, nc_error *err)
{
    if (!o->open || o->finished) return 0;
    if (o->max_u_node >= 0 && o->disp.dataset > 0 &&
        (nc_h5_attr_double(&o->h5, "/output/displacement", "max_magnitude", o->max_u_m, err) ||
         nc_h5_attr_double(&o->h5, "/output/displacement", "max_time", o->max_u_time_s, err) ||
         nc_h5_attr_double(&o->h5, "/output/displacement", "max_node", o->max_u_node, err)))
        return -1;
    if (o->model && o->peak_n && write_overload(o, o->model, err)) return -1;
    if (fem_output_flush(o, err)) return -1;
    o->finished = 1;
    return 0;
}

void fem_output_close(fem_output *o)
{
    if (!o) return;
    if (o->open) {
        nc_error ignored;   /* a run finishes first (fem_output_finish) and reports its error */
        fem_output_finish(o, &ignored);
        close_series(o);
        nc_h5_flush(&o->h5, &ignored);
        nc_h5_close(&o->h5);
    }
    nc_xdmf_close(&o->xdmf);
    free(o->times);
    free(o->buf);
    free(o->force);
    free(o->support_nodes);
    free_peaks(o);
    memset(o, 0, sizeof *o);
}
