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

/* Binary STL: 80-byte header, u32 facet count, then 50 bytes per facet (normal, 3 vertices
 * as little-endian float32, u16 attribute). The caller has checked the size: 84 + 50 n. */
static int read_binary(FILE *f, size_t n, double **out, const char *path, nc_error *err)
{
    double *xyz = malloc(9 * (n ? n : 1) * sizeof *xyz);
    if (!xyz) return nc_error_set(err, 1, "%s: out of memory for %zu facets", path, n);
    if (fseek(f, 84, SEEK_SET) != 0) {
        free(xyz);
        return nc_error_set(err, 1, "%s: cannot read: %s", path, strerror(errno));
    }
    unsigned char rec[50];
    for (size_t t = 0; t < n; t++) {
        if (fread(rec, 1, 50, f) != 50) {
            free(xyz);
            return nc_error_set(err, 1, "%s: binary STL: facet %zu of %zu cannot be read "
                                        "(file changed while read?)", path, t + 1, n);
        }
        for (int k = 0; k < 9; k++) {
            float v;
            uint32_t bits = (uint32_t)rec[12 + 4 * k] | ((uint32_t)rec[13 + 4 * k] << 8) |
                            ((uint32_t)rec[14 + 4 * k] << 16) | ((uint32_t)rec[15 + 4 * k] << 24);
            memcpy(&v, &bits, sizeof v);
            if (!isfinite(v)) {
                free(xyz);
                return nc_error_set(err, 1, "%s: binary STL: facet %zu of %zu: vertex %d, "
                                            "coordinate %c is not finite", path, t + 1, n,
                                    k / 3 + 1, "xyz"[k % 3]);
            }
            xyz[9 * t + (size_t)k] = (double)v;
        }
    }
    *out = xyz;
    return 0;
}

/* ASCII STL, read word by word against its grammar:
 *   solid name / { facet normal n n n / outer loop / 3 x (vertex x y z) / endloop / endfacet }
 *   / endsolid name     (several solids may follow one another)
 * so that every facet is either read whole or refused, and a file that stops early is
 * refused as truncated. */
typedef struct lexer {
    const char *p, *end;
    int line;
    size_t facet; /* 1-based number of the facet being read, 0 before the first */
    const char *path;
} lexer;

static size_t next_word(lexer *x, const char **word)
{
    while (x->p < x->end && (*x->p == ' ' || *x->p == '\t' || *x->p == '\r' || *x->p == '\n')) {
        if (*x->p == '\n') x->line++;
        x->p++;
    }
    *word = x->p;
    while (x->p < x->end && *x->p != ' ' && *x->p != '\t' && *x->p != '\r' && *x->p != '\n')
        x->p++;
    return (size_t)(x->p - *word);
}

static void skip_line(lexer *x)
{
    while (x->p < x->end && *x->p != '\n') x->p++;
}

static int is_word(const char *w, size_t len, const char *want)
{
    return len == strlen(want) && strncmp(w, want, len) == 0;
}

static int ascii_error(lexer *x, nc_error *err, const char *what, const char *w, size_t len)
{
    char at[64] = "";
    if (x->facet) snprintf(at, sizeof at, " facet %zu:", x->facet);
    if (len == 0)
        return nc_error_set(err, 1, "%s:%d:%s the file ends where %s was expected (truncated "
                                    "after %zu complete facets?)", x->path, x->line, at, what,
                            x->facet ? x->facet - 1 : 0);
    return nc_error_set(err, 1, "%s:%d:%s expected %s, got '%.*s'", x->path, x->line, at, what,
                        (int)(len > 40 ? 40 : len), w);
}

static int expect_word(lexer *x, const char *want, nc_error *err)
{
    const char *w;
    size_t len = next_word(x, &w);
    if (is_word(w, len, want)) return 0;
    char what[32];
    snprintf(what, sizeof what, "'%s'", want);
    return ascii_error(x, err, what, w, len);
}

static int read_numbers(lexer *x, double v[3], int finite, const char *what, nc_error *err)
{
    for (int k = 0; k < 3; k++) {
        while (x->p < x->end && (*x->p == ' ' || *x->p == '\t')) x->p++;
        if (x->p == x->end) return ascii_error(x, err, "a number", x->p, 0);
        char *stop;
        v[k] = strtod(x->p, &stop);
        if (stop == x->p || stop > x->end ||
            (stop < x->end && *stop != ' ' && *stop != '\t' && *stop != '\r' && *stop != '\n'))
            return nc_error_set(err, 1, "%s:%d: facet %zu: expected 3 numbers after '%s'",
                                x->path, x->line, x->facet, what);
        if (finite && !isfinite(v[k]))
            return nc_error_set(err, 1, "%s:%d: facet %zu: %s coordinate %c is not finite",
                                x->path, x->line, x->facet, what, "xyz"[k]);
        x->p = stop;
    }
    return 0;
}

static int read_ascii(const char *text, size_t size, double **out, size_t *n_out,
                      const char *path, nc_error *err)
{
    size_t cap = 64, count = 0; /* facets */
    double *xyz = malloc(9 * cap * sizeof *xyz);
    if (!xyz) return nc_error_set(err, 1, "%s: out of memory", path);
    lexer x = {text, text + size, 1, 0, path};
    const char *w;
    size_t len = next_word(&x, &w);
    int in_solid = 0, rc = 0;
    if (!is_word(w, len, "solid")) {
        rc = ascii_error(&x, err, "'solid'", w, len);
        goto done;
    }
    in_solid = 1;
    skip_line(&x); /* the solid's name */
    for (;;) {
        len = next_word(&x, &w);
        if (len == 0) {
            if (in_solid) rc = ascii_error(&x, err, "'facet' or 'endsolid'", w, len);
            break;
        }
        if (!in_solid) {
            if (!is_word(w, len, "solid")) {
                rc = ascii_error(&x, err, "'solid' or the end of the file after 'endsolid'", w, len);
                break;
            }
            in_solid = 1;
            skip_line(&x);
            continue;
        }
        if (is_word(w, len, "endsolid")) {
            in_solid = 0;
            skip_line(&x);
            continue;
        }
        x.facet = count + 1;
        if (!is_word(w, len, "facet")) {
            rc = ascii_error(&x, err, "'facet' or 'endsolid'", w, len);
            break;
        }
        if (count == DEM_STL_MAX_TRIANGLES) {
            rc = nc_error_set(err, 1, "%s:%d: more than %u facets", path, x.line, DEM_STL_MAX_TRIANGLES);
            break;
        }
        if (count == cap) {
            cap *= 2;
            double *g = realloc(xyz, 9 * cap * sizeof *xyz);
            if (!g) {
                rc = nc_error_set(err, 1, "%s: out of memory at facet %zu", path, count + 1);
                break;
            }
            xyz = g;
        }
        double normal[3];
        if ((rc = expect_word(&x, "normal", err)) || (rc = read_numbers(&x, normal, 0, "normal", err)) ||
            (rc = expect_word(&x, "outer", err)) || (rc = expect_word(&x, "loop", err)))
            break;
        for (int v = 0; v < 3 && !rc; v++)
            if (!(rc = expect_word(&x, "vertex", err)))
                rc = read_numbers(&x, xyz + 9 * count + 3 * (size_t)v, 1, "vertex", err);
        if (rc || (rc = expect_word(&x, "endloop", err)) || (rc = expect_word(&x, "endfacet", err)))
            break;
        count++;
    }
done:
    *n_out = count; /* the complete facets, also on failure (to say where it stopped) */
    if (rc) {
        free(xyz);
        return -1;
    }
    *out = xyz;
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
        return nc_error_set(err, 1, "%s: cannot read STL file (not a regular file?)", path);
    }
    unsigned char head[84];
    size_t got = fread(head, 1, sizeof head, f);
    double *xyz = NULL;
    size_t n = 0;
    int rc;
    uint32_t nbin = got == 84 ? ((uint32_t)head[80] | ((uint32_t)head[81] << 8) |
                                 ((uint32_t)head[82] << 16) | ((uint32_t)head[83] << 24))
                              : 0;
    /* binary exactly when the size is that of the announced facets, even when the 80-byte
     * header happens to start with "solid" (many exporters write that) */
    long long binary_size = 84LL + 50LL * (long long)nbin;
    int ascii_start = got >= 5 && memcmp(head, "solid", 5) == 0;
    if (got == 84 && binary_size == (long long)size) {
        if (nbin > DEM_STL_MAX_TRIANGLES) {
            fclose(f);
            return nc_error_set(err, 1, "%s: binary STL with %u facets, more than the %u "
                                        "allowed", path, (unsigned)nbin, DEM_STL_MAX_TRIANGLES);
        }
        n = nbin;
        rc = read_binary(f, n, &xyz, path, err);
    } else if (ascii_start) {
        char *text = malloc((size_t)size + 1);
        if (!text) {
            fclose(f);
            return nc_error_set(err, 1, "%s: out of memory for %ld bytes", path, size);
        }
        if (fseek(f, 0, SEEK_SET) != 0 || fread(text, 1, (size_t)size, f) != (size_t)size) {
            free(text);
            fclose(f);
            return nc_error_set(err, 1, "%s: short read", path);
        }
        text[size] = '\0';
        const char *nul = memchr(text, '\0', (size_t)size);
        if (nul) {
            /* a NUL byte is not text: count the facets before it to say where it is */
            size_t before = 0;
            nc_error ignored;
            double *part = NULL;
            int line = 1;
            for (const char *c = text; c < nul; c++) line += *c == '\n';
            read_ascii(text, (size_t)(nul - text), &part, &before, path, &ignored);
            free(part);
            free(text);
            fclose(f);
            if (got == 84)
                return nc_error_set(err, 1, "%s:%d: byte %zu is a NUL byte, in facet %zu: an "
                                            "ASCII STL is text, and the file's %ld bytes are not "
                                            "the %lld of a binary STL with the %u facets its "
                                            "header announces", path, line,
                                    (size_t)(nul - text), before + 1, size, binary_size,
                                    (unsigned)nbin);
            return nc_error_set(err, 1, "%s:%d: byte %zu is a NUL byte: an ASCII STL is text",
                                path, line, (size_t)(nul - text));
        }
        rc = read_ascii(text, (size_t)size, &xyz, &n, path, err);
        free(text);
        /* a header whose count is near the size hints at a damaged binary file */
        if (rc && got == 84 && llabs(binary_size - (long long)size) < (long long)size) {
            char first[NC_ERROR_MESSAGE_MAX];
            snprintf(first, sizeof first, "%s", err ? err->message : "");
            nc_error_set(err, 1, "%s (read as ASCII: the file's %ld bytes are not the %lld of a "
                                 "binary STL with the %u facets its header announces)", first,
                         size, binary_size, (unsigned)nbin);
        }
    } else {
        fclose(f);
        if (got == 84)
            return nc_error_set(err, 1, "%s: not an STL file (binary header says %u facets, "
                                        "so %lld bytes were expected, the file has %ld; an ASCII "
                                        "STL starts with 'solid')",
                                path, (unsigned)nbin, binary_size, size);
        return nc_error_set(err, 1, "%s: not an STL file (too short)", path);
    }
    fclose(f);
    if (rc) return -1;
    rc = dem_mesh_from_triangles(mesh, n, xyz, path, err);
    free(xyz);
    if (rc == 0) snprintf(mesh->path, sizeof mesh->path, "%s", path);
    return rc;
}
