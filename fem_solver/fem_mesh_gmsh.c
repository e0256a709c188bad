/* fem_mesh_gmsh — a small, strict reader of Gmsh ASCII meshes (2.2 and 4.1) that keeps
 * what a cable net needs: nodes, line elements, point elements and physical names. */
#include "fem_mesh_gmsh.h"

#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

typedef struct reader {
    FILE *f;
    const char *path;
    long line_no;
    char line[4096];
} reader;

static int next_line(reader *r)
{
    if (!fgets(r->line, sizeof r->line, r->f)) return -1;
    r->line_no++;
    return 0;
}

static int bad(reader *r, nc_error *err, const char *what)
{
    return nc_error_set(err, 1, "%s: line %ld: %s", r->path, r->line_no, what);
}

typedef struct tag_index { long tag; int index; } tag_index;

static int cmp_tag(const void *a, const void *b)
{
    long x = ((const tag_index *)a)->tag, y = ((const tag_index *)b)->tag;
    return x < y ? -1 : x > y;
}

static int lookup(const tag_index *map, int n, long tag)
{
    tag_index key = {tag, 0};
    const tag_index *hit = bsearch(&key, map, (size_t)n, sizeof key, cmp_tag);
    return hit ? hit->index : -1;
}

typedef struct entity_phys { int dim; long tag; int physical; } entity_phys;

static int grow(void **p, int *cap, int need, size_t size)
{
    if (need <= *cap) return 0;
    int c = *cap ? *cap * 2 : 64;
    while (c < need) c *= 2;
    void *q = realloc(*p, (size_t)c * size);
    if (!q) return -1;
    *p = q;
    *cap = c;
    return 0;
}

static int skip_section(reader *r, const char *name, nc_error *err)
{
    char end[80];
    snprintf(end, sizeof end, "$End%s", name + 1);
    while (!next_line(r))
        if (strncmp(r->line, end, strlen(end)) == 0) return 0;
    return bad(r, err, "unexpected end of file inside a section");
}

int fem_gmsh_read(const char *path, fem_gmsh_mesh *g, nc_error *err)
{
    memset(g, 0, sizeof *g);
    reader r = {fopen(path, "r"), path, 0, {0}};
    if (!r.f) return nc_error_set(err, 1, "%s: cannot open: %s", path, strerror(errno));
    int rc = -1, version = 0, node_cap = 0, line_cap = 0, phys_cap = 0, ent_cap = 0, n_ent = 0;
    tag_index *map = NULL;
    entity_phys *ents = NULL;
    long *line_tags_tmp = NULL;
    int have_nodes = 0;
    (void)line_tags_tmp;
    while (!next_line(&r)) {
        char sec[64];
        if (sscanf(r.line, "%63s", sec) != 1) continue;
        if (strcmp(sec, "$MeshFormat") == 0) {
            double v;
            int file_type;
            if (next_line(&r) || sscanf(r.line, "%lf %d", &v, &file_type) != 2) { bad(&r, err, "bad $MeshFormat"); goto out; }
            if (file_type != 0) { bad(&r, err, "binary .msh files are not supported (save as ASCII)"); goto out; }
            if (v >= 2.0 && v < 3.0) version = 2;
            else if (v >= 4.1 && v < 5.0) version = 4;
            else { nc_error_set(err, 1, "%s: format version %g not supported (expected 2.2 or 4.1 ASCII)", path, v); goto out; }
            if (skip_section(&r, "$MeshFormat", err)) goto out;
        } else if (strcmp(sec, "$PhysicalNames") == 0) {
            int n;
            if (next_line(&r) || sscanf(r.line, "%d", &n) != 1 || n < 0 || n > 1000000) { bad(&r, err, "bad $PhysicalNames count"); goto out; }
            g->groups = calloc((size_t)n + 1, sizeof *g->groups);
            if (!g->groups) { nc_error_set(err, 1, "%s: out of memory", path); goto out; }
            for (int i = 0; i < n; i++) {
                fem_gmsh_group *gr = &g->groups[i];
                char *q1, *q2;
                if (next_line(&r) || sscanf(r.line, "%d %d", &gr->dim, &gr->tag) != 2 ||
                    !(q1 = strchr(r.line, '"')) || !(q2 = strchr(q1 + 1, '"'))) {
                    bad(&r, err, "expected: dim tag \"name\""); goto out;
                }
                *q2 = '\0';
                snprintf(gr->name, sizeof gr->name, "%s", q1 + 1);
            }
            g->n_groups = n;
            if (skip_section(&r, "$PhysicalNames", err)) goto out;
        } else if (strcmp(sec, "$Entities") == 0 && version == 4) {
            long np, nc, ns, nv;
            if (next_line(&r) || sscanf(r.line, "%ld %ld %ld %ld", &np, &nc, &ns, &nv) != 4) { bad(&r, err, "bad $Entities header"); goto out; }
            for (long i = 0; i < np + nc; i++) {
                if (next_line(&r)) { bad(&r, err, "unexpected end of file in $Entities"); goto out; }
                int dim = i < np ? 0 : 1;
                char *p = r.line, *endp;
                long tag = strtol(p, &endp, 10);
                p = endp;
                for (int k = 0; k < (dim == 0 ? 3 : 6); k++) { strtod(p, &endp); p = endp; }
                long nphys = strtol(p, &endp, 10);
                if (endp == p) { bad(&r, err, "bad entity line"); goto out; }
                p = endp;
                long phys = nphys > 0 ? strtol(p, &endp, 10) : 0;
                if (grow((void **)&ents, &ent_cap, n_ent + 1, sizeof *ents)) { nc_error_set(err, 1, "out of memory"); goto out; }
                ents[n_ent].dim = dim;
                ents[n_ent].tag = tag;
                ents[n_ent++].physical = (int)phys;
            }
            if (skip_section(&r, "$Entities", err)) goto out;
        } else if (strcmp(sec, "$Nodes") == 0) {
            if (!version) { bad(&r, err, "$Nodes before $MeshFormat"); goto out; }
            long nblocks = 1, nnodes;
            if (next_line(&r)) { bad(&r, err, "bad $Nodes header"); goto out; }
            if (version == 2) {
                if (sscanf(r.line, "%ld", &nnodes) != 1) { bad(&r, err, "bad $Nodes count"); goto out; }
            } else if (sscanf(r.line, "%ld %ld", &nblocks, &nnodes) != 2) {
                bad(&r, err, "bad $Nodes header"); goto out;
            }
            if (nnodes < 1 || nnodes > 50000000L) { bad(&r, err, "bad number of nodes"); goto out; }
            g->X = malloc(3 * (size_t)nnodes * sizeof *g->X);
            map = malloc((size_t)nnodes * sizeof *map);
            if (!g->X || !map) { nc_error_set(err, 1, "%s: out of memory", path); goto out; }
            node_cap = (int)nnodes;
            int k = 0;
            for (long b = 0; b < nblocks; b++) {
                long count = nnodes;
                int parametric = 0;
                if (version == 4) {
                    int edim;
                    long etag;
                    if (next_line(&r) || sscanf(r.line, "%d %ld %d %ld", &edim, &etag, &parametric, &count) != 4) { bad(&r, err, "bad node block header"); goto out; }
                    if (parametric) { bad(&r, err, "parametric nodes are not supported"); goto out; }
                    if (k + count > nnodes) { bad(&r, err, "more nodes than announced"); goto out; }
                    for (long i = 0; i < count; i++) {
                        if (next_line(&r) || sscanf(r.line, "%ld", &map[k + i].tag) != 1) { bad(&r, err, "expected a node tag"); goto out; }
                        map[k + i].index = (int)(k + i);
                    }
                    for (long i = 0; i < count; i++) {
                        double *x = g->X + 3 * (k + i);
                        if (next_line(&r) || sscanf(r.line, "%lf %lf %lf", x, x + 1, x + 2) != 3) { bad(&r, err, "expected x y z"); goto out; }
                    }
                } else {
                    for (long i = 0; i < count; i++) {
                        double *x = g->X + 3 * (k + i);
                        if (next_line(&r) || sscanf(r.line, "%ld %lf %lf %lf", &map[k + i].tag, x, x + 1, x + 2) != 4) { bad(&r, err, "expected: tag x y z"); goto out; }
                        map[k + i].index = (int)(k + i);
                    }
                }
                k += (int)count;
            }
            if (k != nnodes) { bad(&r, err, "fewer nodes than announced"); goto out; }
            g->n_nodes = k;
            qsort(map, (size_t)k, sizeof *map, cmp_tag);
            for (int i = 1; i < k; i++)
                if (map[i].tag == map[i - 1].tag) { nc_error_set(err, 1, "%s: node tag %ld appears twice", path, map[i].tag); goto out; }
            have_nodes = 1;
            if (skip_section(&r, "$Nodes", err)) goto out;
        } else if (strcmp(sec, "$Elements") == 0) {
            if (!have_nodes) { bad(&r, err, "$Elements before $Nodes"); goto out; }
            long nblocks = 1, nelem;
            if (next_line(&r)) { bad(&r, err, "bad $Elements header"); goto out; }
            if (version == 2) {
                if (sscanf(r.line, "%ld", &nelem) != 1) { bad(&r, err, "bad $Elements count"); goto out; }
            } else if (sscanf(r.line, "%ld %ld", &nblocks, &nelem) != 2) {
                bad(&r, err, "bad $Elements header"); goto out;
            }
            for (long b = 0; b < nblocks; b++) {
                long count = nelem;
                int type = 0, phys = 0, edim = 0;
                long etag = 0;
                if (version == 4) {
                    if (next_line(&r) || sscanf(r.line, "%d %ld %d %ld", &edim, &etag, &type, &count) != 4) { bad(&r, err, "bad element block header"); goto out; }
                    for (int i = 0; i < n_ent; i++)
                        if (ents[i].dim == edim && ents[i].tag == etag) phys = ents[i].physical;
                }
                for (long i = 0; i < count; i++) {
                    if (next_line(&r)) { bad(&r, err, "unexpected end of file in $Elements"); goto out; }
                    long v[64];
                    int nv = 0;
                    char *p = r.line, *endp;
                    while (nv < 64) {
                        long x = strtol(p, &endp, 10);
                        if (endp == p) break;
                        v[nv++] = x;
                        p = endp;
                    }
                    const long *nodes;
                    int t;
                    if (version == 2) {
                        if (nv < 3 || nv < 3 + v[2]) { bad(&r, err, "bad element line"); goto out; }
                        t = (int)v[1];
                        phys = v[2] > 0 ? (int)v[3] : 0;
                        nodes = v + 3 + v[2];
                        nv -= 3 + (int)v[2];
                    } else {
                        t = type;
                        nodes = v + 1;
                        nv -= 1;
                    }
                    if ((t == 1 && nv < 2) || (t == 15 && nv < 1)) { bad(&r, err, "element with too few nodes"); goto out; }
                    if (t == 1) {
                        int a = lookup(map, g->n_nodes, nodes[0]), c = lookup(map, g->n_nodes, nodes[1]);
                        if (a < 0 || c < 0) { bad(&r, err, "element refers to an unknown node tag"); goto out; }
                        if (grow((void **)&g->lines, &line_cap, 2 * g->n_lines + 2, sizeof(int)) ||
                            grow((void **)&g->line_physical, &phys_cap, g->n_lines + 1, sizeof(int))) {
                            nc_error_set(err, 1, "out of memory"); goto out;
                        }
                        g->lines[2 * g->n_lines] = a;
                        g->lines[2 * g->n_lines + 1] = c;
                        g->line_physical[g->n_lines++] = phys;
                    } else if (t == 15) {
                        int a = lookup(map, g->n_nodes, nodes[0]);
                        if (a < 0) { bad(&r, err, "point element refers to an unknown node tag"); goto out; }
                        int *pp = realloc(g->points, (size_t)(g->n_points + 1) * sizeof(int));
                        int *pq = pp ? realloc(g->point_physical, (size_t)(g->n_points + 1) * sizeof(int)) : NULL;
                        if (pp) g->points = pp;
                        if (pq) g->point_physical = pq;
                        if (!pp || !pq) { nc_error_set(err, 1, "out of memory"); goto out; }
                        g->points[g->n_points] = a;
                        g->point_physical[g->n_points++] = phys;
                    }
                }
            }
            if (skip_section(&r, "$Elements", err)) goto out;
        } else if (sec[0] == '$') {
            if (skip_section(&r, sec, err)) goto out;
        }
    }
    (void)node_cap;
    if (!version) { nc_error_set(err, 1, "%s: not a Gmsh mesh (no $MeshFormat section)", path); goto out; }
    if (!have_nodes) { nc_error_set(err, 1, "%s: no $Nodes section", path); goto out; }
    rc = 0;
out:
    fclose(r.f);
    free(map);
    free(ents);
    if (rc) fem_gmsh_free(g);
    return rc;
}

void fem_gmsh_free(fem_gmsh_mesh *g)
{
    free(g->X); free(g->lines); free(g->line_physical); free(g->points);
    free(g->point_physical); free(g->groups);
    memset(g, 0, sizeof *g);
}
