/* dem_stl — STL reader (ASCII and binary) and vertex/edge welding for rigid wall meshes. */
#include "dem_stl.h"

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "dem_neighbor_grid.h"

#define DEM_STL_MAX_TRIANGLES 50000000u

typedef struct { double x[3]; int32_t idx; } vertex_rec;

typedef struct { int32_t a, b, tri, slot; } edge_rec;

static int cmp_edge(const void *pa, const void *pb)
{
    const edge_rec *x = pa, *y = pb;
    if (x->a != y->a) return x->a < y->a ? -1 : 1;
    if (x->b != y->b) return x->b < y->b ? -1 : 1;
    if (x->tri != y->tri) return x->tri < y->tri ? -1 : 1;
    return x->slot - y->slot;
}

static int cmp_vertex(const void *pa, const void *pb)
{
    const vertex_rec *a = pa, *b = pb;
    for (int k = 0; k < 3; k++) {
        if (a->x[k] < b->x[k]) return -1;
        if (a->x[k] > b->x[k]) return 1;
    }
    return a->idx < b->idx ? -1 : (a->idx > b->idx);
}

void dem_mesh_free(dem_mesh *mesh)
{
    free(mesh->vertices);
    free(mesh->tri);
    free(mesh->tri_edges);
    free(mesh->edges);
    if (mesh->grid) {
        dem_item_grid_free(mesh->grid);
        free(mesh->grid);
    }
    mesh->vertices = NULL;
    mesh->tri = mesh->tri_edges = mesh->edges = NULL;
    mesh->grid = NULL;
    mesh->n_vertices = mesh->n_triangles = mesh->n_edges = 0;
}

int dem_mesh_from_triangles(dem_mesh *mesh, size_t n, const double *xyz, const char *what,
                            nc_error *err)
{
    if (n == 0) return nc_error_set(err, 1, "%s: the mesh has no triangles", what);
    for (size_t t = 0; t < n; t++) {
        const double *p = xyz + 9 * t;
        for (int k = 0; k < 9; k++)
            if (!isfinite(p[k]))
                return nc_error_set(err, 1, "%s: triangle %zu has a non-finite coordinate", what, t);
        double u[3], v[3], c[3];
        for (int k = 0; k < 3; k++) {
            u[k] = p[3 + k] - p[k];
            v[k] = p[6 + k] - p[k];
        }
        c[0] = u[1] * v[2] - u[2] * v[1];
        c[1] = u[2] * v[0] - u[0] * v[2];
        c[2] = u[0] * v[1] - u[1] * v[0];
        if (c[0] * c[0] + c[1] * c[1] + c[2] * c[2] == 0.0)
            return nc_error_set(err, 1, "%s: triangle %zu is degenerate (zero area)", what, t);
    }
    size_t nv = 3 * n;
    vertex_rec *order = malloc(nv * sizeof *order);
    int32_t *map = malloc(nv * sizeof *map);
    double *verts = malloc(3 * nv * sizeof *verts);
    int32_t *tri = malloc(3 * n * sizeof *tri);
    int32_t *tri_edges = malloc(3 * n * sizeof *tri_edges);
    edge_rec *recs = malloc(3 * n * sizeof *recs);
    int32_t *edges = malloc(6 * n * sizeof *edges);
    if (!order || !map || !verts || !tri || !tri_edges || !recs || !edges) {
        free(order); free(map); free(verts); free(tri); free(tri_edges); free(recs); free(edges);
        return nc_error_set(err, 1, "%s: out of memory for %zu triangles", what, n);
    }
    /* weld identical vertices */
    for (size_t i = 0; i < nv; i++) {
        memcpy(order[i].x, xyz + 3 * i, 3 * sizeof(double));
        order[i].idx = (int32_t)i;
    }
    qsort(order, nv, sizeof *order, cmp_vertex);
    size_t unique = 0;
    for (size_t s = 0; s < nv; s++) {
        if (s == 0 || order[s].x[0] != order[s - 1].x[0] || order[s].x[1] != order[s - 1].x[1] ||
            order[s].x[2] != order[s - 1].x[2]) {
            memcpy(verts + 3 * unique, order[s].x, 3 * sizeof(double));
            unique++;
        }
        map[order[s].idx] = (int32_t)(unique - 1);
    }
    for (size_t i = 0; i < nv; i++) tri[i] = map[i];
    /* one index per undirected edge */
    for (size_t t = 0; t < n; t++)
        for (int s = 0; s < 3; s++) {
            int32_t a = tri[3 * t + s], b = tri[3 * t + (s + 1) % 3];
            edge_rec *r = &recs[3 * t + (size_t)s];
            r->a = a < b ? a : b;
            r->b = a < b ? b : a;
            r->tri = (int32_t)t;
            r->slot = s;
        }
    qsort(recs, 3 * n, sizeof *recs, cmp_edge);
    size_t ne = 0;
    for (size_t r = 0; r < 3 * n; r++) {
        if (r == 0 || recs[r].a != recs[r - 1].a || recs[r].b != recs[r - 1].b) {
            edges[2 * ne] = recs[r].a;
            edges[2 * ne + 1] = recs[r].b;
            ne++;
        }
        tri_edges[3 * (size_t)recs[r].tri + (size_t)recs[r].slot] = (int32_t)(ne - 1);
    }
    free(order);
    free(map);
    free(recs);
    dem_mesh_free(mesh);
    mesh->vertices = verts;
    mesh->tri = tri;
    mesh->tri_edges = tri_edges;
    mesh->edges = edges;
    mesh->n_vertices = unique;
    mesh->n_triangles = n;
    mesh->n_edges = ne;
    return 0;
}

static int read_binary(FILE *f, size_t n, double **out, const char *path, nc_error *err)
{
    double *xyz = malloc(9 * n * sizeof *xyz);
    if (!xyz) return nc_error_set(err, 1, "%s: out of memory for %zu triangles", path, n);
    if (fseek(f, 84, SEEK_SET) != 0) {
        free(xyz);
        return nc_error_set(err, 1, "%s: cannot read", path);
    }
    unsigned char rec[50];
    for (size_t t = 0; t < n; t++) {
        if (fread(rec, 1, 50, f) != 50) {
            free(xyz);
            return nc_error_set(err, 1, "%s: binary STL truncated at triangle %zu", path, t);
        }
        for (int k = 0; k < 9; k++) {
            float v;
            uint32_t bits = (uint32_t)rec[12 + 4 * k] | ((uint32_t)rec[13 + 4 * k] << 8) |
                            ((uint32_t)rec[14 + 4 * k] << 16) | ((uint32_t)rec[15 + 4 * k] << 24);
            memcpy(&v, &bits, sizeof v);
            xyz[9 * t + (size_t)k] = (double)v;
        }
    }
    *out = xyz;
    return 0;
}

static int read_ascii(const char *text, double **out, size_t *n_out, const char *path,
                      nc_error *err)
{
    size_t cap = 64, count = 0; /* vertices */
    double *xyz = malloc(3 * cap * sizeof *xyz);
    if (!xyz) return nc_error_set(err, 1, "%s: out of memory", path);
    int line = 1;
    const char *p = text;
    while (*p) {
        while (*p == ' ' || *p == '\t' || *p == '\r' || *p == '\n') {
            if (*p == '\n') line++;
            p++;
        }
        if (!*p) break;
        const char *word = p;
        while (*p && *p != ' ' && *p != '\t' && *p != '\r' && *p != '\n') p++;
        size_t len = (size_t)(p - word);
        if (len == 6 && strncmp(word, "vertex", 6) == 0) {
            if (count == cap) {
                cap *= 2;
                double *g = realloc(xyz, 3 * cap * sizeof *xyz);
                if (!g) {
                    free(xyz);
                    return nc_error_set(err, 1, "%s: out of memory", path);
                }
                xyz = g;
            }
            for (int k = 0; k < 3; k++) {
                char *end;
                errno = 0;
                double v = strtod(p, &end);
                if (end == p || !isfinite(v)) {
                    free(xyz);
                    return nc_error_set(err, 1, "%s:%d: expected 3 finite numbers after 'vertex'",
                                        path, line);
                }
                xyz[3 * count + (size_t)k] = v;
                p = end;
            }
            count++;
        } else if (len == 5 && strncmp(word, "solid", 5) == 0) {
            while (*p && *p != '\n') p++; /* solid name */
        } else if (len == 8 && strncmp(word, "endsolid", 8) == 0) {
            while (*p && *p != '\n') p++;
        } else if (len == 5 && strncmp(word, "facet", 5) == 0) {
            while (*p && *p != '\n') p++; /* normal is recomputed, ignore */
        } else if (!((len == 5 && strncmp(word, "outer", 5) == 0) ||
                     (len == 4 && strncmp(word, "loop", 4) == 0) ||
                     (len == 7 && strncmp(word, "endloop", 7) == 0) ||
                     (len == 8 && strncmp(word, "endfacet", 8) == 0))) {
            free(xyz);
            return nc_error_set(err, 1, "%s:%d: unexpected word '%.*s' in ASCII STL", path, line,
                                (int)(len > 40 ? 40 : len), word);
        }
    }
    if (count % 3 != 0) {
        free(xyz);
        return nc_error_set(err, 1, "%s: %zu vertices is not a multiple of 3 (truncated facet?)",
                            path, count);
    }
    *out = xyz;
    *n_out = count / 3;
    return 0;
}

int dem_stl_load(dem_mesh *mesh, const char *path, nc_error *err)
{
    FILE *f = fopen(path, "rb");
    if (!f) return nc_error_set(err, 1, "%s: cannot open STL file: %s", path, strerror(errno));
    long size = -1;
    if (fseek(f, 0, SEEK_END) == 0) size = ftell(f);
    if (size < 0 || fseek(f, 0, SEEK_SET) != 0) {
        fclose(f);
        return nc_error_set(err, 1, "%s: cannot read STL file", path);
    }
    unsigned char head[84];
    size_t got = fread(head, 1, sizeof head, f);
    double *xyz = NULL;
    size_t n = 0;
    int rc;
    uint32_t nbin = got == 84 ? ((uint32_t)head[80] | ((uint32_t)head[81] << 8) |
                                 ((uint32_t)head[82] << 16) | ((uint32_t)head[83] << 24))
                              : 0;
    if (got == 84 && nbin <= DEM_STL_MAX_TRIANGLES && (long)(84 + 50 * (long)nbin) == size) {
        n = nbin;
        rc = read_binary(f, n, &xyz, path, err);
    } else if (got >= 5 && memcmp(head, "solid", 5) == 0) {
        char *text = malloc((size_t)size + 1);
        if (!text) {
            fclose(f);
            return nc_error_set(err, 1, "%s: out of memory", path);
        }
        rc = fseek(f, 0, SEEK_SET) != 0 || fread(text, 1, (size_t)size, f) != (size_t)size;
        if (rc) {
            free(text);
            fclose(f);
            return nc_error_set(err, 1, "%s: short read", path);
        }
        text[size] = '\0';
        rc = read_ascii(text, &xyz, &n, path, err);
        free(text);
    } else {
        fclose(f);
        if (got == 84)
            return nc_error_set(err, 1, "%s: not an STL file (binary header says %u triangles, "
                                        "so %ld bytes were expected, the file has %ld; an ASCII "
                                        "STL starts with 'solid')",
                                path, (unsigned)nbin, 84L + 50L * (long)nbin, size);
        return nc_error_set(err, 1, "%s: not an STL file (too short)", path);
    }
    fclose(f);
    if (rc) return -1;
    rc = dem_mesh_from_triangles(mesh, n, xyz, path, err);
    free(xyz);
    if (rc == 0) snprintf(mesh->path, sizeof mesh->path, "%s", path);
    return rc;
}
