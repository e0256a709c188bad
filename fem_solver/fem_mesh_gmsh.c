/* fem_mesh_gmsh — a small, strict reader of Gmsh ASCII meshes (2.2 and 4.1) that keeps
 * what a cable net needs: nodes, line elements, point elements and physical names. */
#include "fem_mesh_gmsh.h"

#include <errno.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* Bounds on what a file may announce. Storage grows with what is actually read, so a count
 * in a header never allocates more than the file holds. */
#define GMSH_MAX_NODES 50000000L
#define GMSH_MAX_ELEMENTS 100000000L
#define GMSH_MAX_BLOCKS 10000000L
#define GMSH_MAX_GROUPS 1000000L

typedef struct reader {
    FILE *f;
    const char *path;
    long line_no;
    int too_long;
    char line[4096];
} reader;

static int next_line(reader *r)
{
    if (!fgets(r->line, sizeof r->line, r->f)) return -1;
    r->line_no++;
    size_t n = strlen(r->line);
    if (n == sizeof r->line - 1 && r->line[n - 1] != '\n' && !feof(r->f)) {
        r->too_long = 1; /* a line cut in two would shift every count after it */
        return -1;
    }
    return 0;
}

static int bad(reader *r, nc_error *err, const char *fmt, ...) __attribute__((format(printf, 3, 4)));
static int bad(reader *r, nc_error *err, const char *fmt, ...)
{
    char what[400];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(what, sizeof what, fmt, ap);
    va_end(ap);
    return nc_error_set(err, 1, "%s: line %ld: %s", r->path, r->line_no, what);
}

/* The next line, or an error saying where the file ended (or that a line is too long). */
static int need_line(reader *r, nc_error *err, const char *inside)
{
    if (!next_line(r)) return 0;
    if (r->too_long) return bad(r, err, "%s: line longer than %zu characters", inside, sizeof r->line - 2);
    return bad(r, err, "%s: unexpected end of file", inside);
}

/* Whole numbers of a line (at most max); -1 when something else than numbers follows. */
static int parse_longs(const char *line, long *v, int max, int *n)
{
    const char *p = line;
    char *end;
    *n = 0;
    for (;;) {
        while (*p == ' ' || *p == '\t' || *p == '\r' || *p == '\n') p++;
        if (!*p) return 0;
        if (*n == max) return 0; /* more numbers than kept: the caller decides */
        errno = 0;
        long x = strtol(p, &end, 10);
        if (end == p || errno == ERANGE) return -1;
        v[(*n)++] = x;
        p = end;
    }
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

static int grow(void **p, int *cap, long need, size_t size)
{
    if (need <= *cap) return 0;
    if (need > 0x3fffffffL) return -1;
    long c = *cap ? *cap : 64;
    while (c < need) c *= 2;
    void *q = realloc(*p, (size_t)c * size);
    if (!q) return -1;
    *p = q;
    *cap = (int)c;
    return 0;
}

static int skip_section(reader *r, const char *name, nc_error *err)
{
    char end[80];
    snprintf(end, sizeof end, "$End%s", name + 1);
    while (!next_line(r))
        if (strncmp(r->line, end, strlen(end)) == 0) return 0;
    if (r->too_long) return bad(r, err, "%s: line longer than %zu characters", name, sizeof r->line - 2);
    return bad(r, err, "unexpected end of file inside %s (no %s)", name, end);
}

static int out_of_memory(reader *r, nc_error *err, const char *what)
{
    return bad(r, err, "out of memory for %s", what);
}

static int read_physical_names(reader *r, fem_gmsh_mesh *g, nc_error *err)
{
    long n;
    if (need_line(r, err, "$PhysicalNames")) return -1;
    if (sscanf(r->line, "%ld", &n) != 1 || n < 0 || n > GMSH_MAX_GROUPS)
        return bad(r, err, "$PhysicalNames: count must be a whole number in [0, %ld]", GMSH_MAX_GROUPS);
    int cap = 0;
    for (long i = 0; i < n; i++) {
        if (need_line(r, err, "$PhysicalNames")) return -1;
        if (grow((void **)&g->groups, &cap, i + 1, sizeof *g->groups))
            return out_of_memory(r, err, "physical names");
        fem_gmsh_group *gr = &g->groups[i];
        char *q1, *q2;
        if (sscanf(r->line, "%d %d", &gr->dim, &gr->tag) != 2 || !(q1 = strchr(r->line, '"')) ||
            !(q2 = strchr(q1 + 1, '"')))
            return bad(r, err, "$PhysicalNames: physical name %ld: expected: dim tag \"name\"", i + 1);
        if (gr->dim < 0 || gr->dim > 3)
            return bad(r, err, "$PhysicalNames: physical name %ld: dimension %d is not 0..3", i + 1, gr->dim);
        *q2 = '\0';
        snprintf(gr->name, sizeof gr->name, "%s", q1 + 1);
        g->n_groups = (int)i + 1;
    }
    return skip_section(r, "$PhysicalNames", err);
}

/* $Entities (4.1): the physical tag of each point and curve (the first one when several). */
static int read_entities(reader *r, entity_phys **ents, int *n_ent, nc_error *err)
{
    long count[4];
    if (need_line(r, err, "$Entities")) return -1;
    if (sscanf(r->line, "%ld %ld %ld %ld", &count[0], &count[1], &count[2], &count[3]) != 4)
        return bad(r, err, "$Entities: expected: numPoints numCurves numSurfaces numVolumes");
    for (int d = 0; d < 4; d++)
        if (count[d] < 0 || count[d] > GMSH_MAX_BLOCKS)
            return bad(r, err, "$Entities: entity count %ld is not in [0, %ld]", count[d], GMSH_MAX_BLOCKS);
    int cap = 0;
    for (long i = 0; i < count[0] + count[1]; i++) {
        if (need_line(r, err, "$Entities")) return -1;
        int dim = i < count[0] ? 0 : 1;
        char *p = r->line, *endp;
        errno = 0;
        long tag = strtol(p, &endp, 10);
        int ok = endp != p;
        p = endp;
        for (int k = 0; ok && k < (dim == 0 ? 3 : 6); k++) {
            double x = strtod(p, &endp);
            ok = endp != p && isfinite(x);
            p = endp;
        }
        long nphys = ok ? strtol(p, &endp, 10) : 0;
        ok = ok && endp != p && errno != ERANGE;
        if (!ok) return bad(r, err, "$Entities: %s entity: expected: tag, %s, numPhysicalTags",
                            dim == 0 ? "point" : "curve", dim == 0 ? "x y z" : "min x y z, max x y z");
        if (nphys < 0) return bad(r, err, "$Entities: entity %ld: numPhysicalTags %ld is negative", tag, nphys);
        p = endp;
        long phys = 0;
        if (nphys > 0) {
            phys = strtol(p, &endp, 10);
            if (endp == p || errno == ERANGE || phys < -2147483647L || phys > 2147483647L)
                return bad(r, err, "$Entities: entity %ld: expected a physical tag", tag);
        }
        if (grow((void **)ents, &cap, *n_ent + 1, sizeof **ents)) return out_of_memory(r, err, "entities");
        (*ents)[*n_ent].dim = dim;
        (*ents)[*n_ent].tag = tag;
        (*ents)[(*n_ent)++].physical = (int)phys;
    }
    return skip_section(r, "$Entities", err);
}

static int read_xyz(reader *r, const char *fmt, long *tag, double *x, nc_error *err, long node)
{
    int want = tag ? 4 : 3;
    int got = tag ? sscanf(r->line, fmt, tag, x, x + 1, x + 2) : sscanf(r->line, fmt, x, x + 1, x + 2);
    if (got != want) return bad(r, err, "$Nodes: node %ld: expected %s", node, tag ? "tag x y z" : "x y z");
    for (int c = 0; c < 3; c++)
        if (!isfinite(x[c])) return bad(r, err, "$Nodes: node %ld: coordinate %c is not finite", node, "xyz"[c]);
    return 0;
}

static int read_nodes(reader *r, int version, fem_gmsh_mesh *g, tag_index **map, nc_error *err)
{
    long nblocks = 1, nnodes;
    if (need_line(r, err, "$Nodes")) return -1;
    if (version == 2 ? sscanf(r->line, "%ld", &nnodes) != 1
                     : sscanf(r->line, "%ld %ld", &nblocks, &nnodes) != 2)
        return bad(r, err, "$Nodes: expected %s", version == 2 ? "the number of nodes" : "numEntityBlocks numNodes");
    if (nnodes < 1 || nnodes > GMSH_MAX_NODES)
        return bad(r, err, "$Nodes: number of nodes %ld is not in [1, %ld]", nnodes, GMSH_MAX_NODES);
    if (nblocks < 1 || nblocks > GMSH_MAX_BLOCKS)
        return bad(r, err, "$Nodes: numEntityBlocks %ld is not in [1, %ld]", nblocks, GMSH_MAX_BLOCKS);
    int xcap = 0, mcap = 0;
    long k = 0;
    for (long b = 0; b < nblocks; b++) {
        long count = nnodes;
        int parametric = 0;
        if (version == 4) {
            int edim;
            long etag;
            if (need_line(r, err, "$Nodes")) return -1;
            if (sscanf(r->line, "%d %ld %d %ld", &edim, &etag, &parametric, &count) != 4)
                return bad(r, err, "$Nodes: node block %ld: expected: entityDim entityTag parametric numNodesInBlock", b + 1);
            if (parametric) return bad(r, err, "$Nodes: node block %ld: parametric nodes are not supported", b + 1);
            if (count < 0 || count > nnodes - k)
                return bad(r, err, "$Nodes: node block %ld: numNodesInBlock %ld is not in [0, %ld] "
                                   "(the nodes left of the %ld announced)", b + 1, count, nnodes - k, nnodes);
        }
        for (long i = 0; i < count; i++) {
            if (grow((void **)&g->X, &xcap, 3 * (k + i + 1), sizeof *g->X) ||
                grow((void **)map, &mcap, k + i + 1, sizeof **map))
                return out_of_memory(r, err, "nodes");
            tag_index *t = *map + k + i;
            double *x = g->X + 3 * (k + i);
            t->index = (int)(k + i);
            if (need_line(r, err, "$Nodes")) return -1;
            if (version == 4) {
                if (sscanf(r->line, "%ld", &t->tag) != 1)
                    return bad(r, err, "$Nodes: node block %ld: expected a node tag", b + 1);
            } else if (read_xyz(r, "%ld %lf %lf %lf", &t->tag, x, err, k + i + 1)) {
                return -1;
            }
        }
        if (version == 4)
            for (long i = 0; i < count; i++) {
                if (need_line(r, err, "$Nodes") ||
                    read_xyz(r, "%lf %lf %lf", NULL, g->X + 3 * (k + i), err, k + i + 1))
                    return -1;
            }
        k += count;
    }
    if (k != nnodes) return bad(r, err, "$Nodes: %ld nodes in the blocks, %ld announced", k, nnodes);
    g->n_nodes = (int)k;
    qsort(*map, (size_t)k, sizeof **map, cmp_tag);
    for (long i = 1; i < k; i++)
        if ((*map)[i].tag == (*map)[i - 1].tag)
            return bad(r, err, "$Nodes: node tag %ld appears twice", (*map)[i].tag);
    return skip_section(r, "$Nodes", err);
}

static int read_elements(reader *r, int version, fem_gmsh_mesh *g, const tag_index *map,
                         const entity_phys *ents, int n_ent, nc_error *err)
{
    long nblocks = 1, nelem;
    if (need_line(r, err, "$Elements")) return -1;
    if (version == 2 ? sscanf(r->line, "%ld", &nelem) != 1
                     : sscanf(r->line, "%ld %ld", &nblocks, &nelem) != 2)
        return bad(r, err, "$Elements: expected %s", version == 2 ? "the number of elements" : "numEntityBlocks numElements");
    if (nelem < 0 || nelem > GMSH_MAX_ELEMENTS)
        return bad(r, err, "$Elements: number of elements %ld is not in [0, %ld]", nelem, GMSH_MAX_ELEMENTS);
    if (nblocks < 0 || nblocks > GMSH_MAX_BLOCKS)
        return bad(r, err, "$Elements: numEntityBlocks %ld is not in [0, %ld]", nblocks, GMSH_MAX_BLOCKS);
    int line_cap = 0, phys_cap = 0, point_cap = 0, ppoint_cap = 0;
    long done = 0;
    for (long b = 0; b < nblocks; b++) {
        long count = nelem;
        int type = 0, phys = 0, edim = 0;
        long etag = 0;
        if (version == 4) {
            if (need_line(r, err, "$Elements")) return -1;
            if (sscanf(r->line, "%d %ld %d %ld", &edim, &etag, &type, &count) != 4)
                return bad(r, err, "$Elements: element block %ld: expected: entityDim entityTag elementType numElementsInBlock", b + 1);
            if (count < 0 || count > nelem - done)
                return bad(r, err, "$Elements: element block %ld: numElementsInBlock %ld is not in [0, %ld] "
                                   "(the elements left of the %ld announced)", b + 1, count, nelem - done, nelem);
            for (int i = 0; i < n_ent; i++)
                if (ents[i].dim == edim && ents[i].tag == etag) phys = ents[i].physical;
        }
        for (long i = 0; i < count; i++) {
            long id = done + i + 1;
            if (need_line(r, err, "$Elements")) return -1;
            long v[64];
            int nv;
            if (parse_longs(r->line, v, 64, &nv))
                return bad(r, err, "$Elements: element %ld: expected whole numbers", id);
            const long *nodes;
            int t;
            if (version == 2) {
                /* elm-number elm-type number-of-tags <tags> node-number-list */
                if (nv < 3) return bad(r, err, "$Elements: element %ld: expected: number type number-of-tags tags... nodes...", id);
                if (v[2] < 0 || v[2] > nv - 3)
                    return bad(r, err, "$Elements: element %ld: number-of-tags %ld is not in [0, %d] (the numbers on the line)", id, v[2], nv - 3);
                if (v[1] < 0 || v[1] > 1000) return bad(r, err, "$Elements: element %ld: element type %ld is not a Gmsh type", id, v[1]);
                t = (int)v[1];
                if (v[2] > 0 && (v[3] < -2147483647L || v[3] > 2147483647L))
                    return bad(r, err, "$Elements: element %ld: physical tag %ld is out of range", id, v[3]);
                phys = v[2] > 0 ? (int)v[3] : 0;
                nodes = v + 3 + v[2];
                nv -= 3 + (int)v[2];
            } else {
                if (nv < 1) return bad(r, err, "$Elements: element %ld: expected: tag nodes...", id);
                t = type;
                nodes = v + 1;
                nv -= 1;
            }
            if ((t == 1 && nv != 2) || (t == 15 && nv != 1))
                return bad(r, err, "$Elements: element %ld: a %s has %d node%s, this line gives %d",
                           id, t == 1 ? "line (type 1)" : "point (type 15)", t == 1 ? 2 : 1, t == 1 ? "s" : "", nv);
            if (t == 1) {
                int a = lookup(map, g->n_nodes, nodes[0]), c = lookup(map, g->n_nodes, nodes[1]);
                if (a < 0 || c < 0)
                    return bad(r, err, "$Elements: element %ld: unknown node tag %ld", id, a < 0 ? nodes[0] : nodes[1]);
                if (grow((void **)&g->lines, &line_cap, 2L * g->n_lines + 2, sizeof(int)) ||
                    grow((void **)&g->line_physical, &phys_cap, g->n_lines + 1L, sizeof(int)))
                    return out_of_memory(r, err, "line elements");
                g->lines[2 * g->n_lines] = a;
                g->lines[2 * g->n_lines + 1] = c;
                g->line_physical[g->n_lines++] = phys;
            } else if (t == 15) {
                int a = lookup(map, g->n_nodes, nodes[0]);
                if (a < 0) return bad(r, err, "$Elements: element %ld: unknown node tag %ld", id, nodes[0]);
                if (grow((void **)&g->points, &point_cap, g->n_points + 1L, sizeof(int)) ||
                    grow((void **)&g->point_physical, &ppoint_cap, g->n_points + 1L, sizeof(int)))
                    return out_of_memory(r, err, "point elements");
                g->points[g->n_points] = a;
                g->point_physical[g->n_points++] = phys;
            }
        }
        done += count;
    }
    if (done != nelem) return bad(r, err, "$Elements: %ld elements in the blocks, %ld announced", done, nelem);
    return skip_section(r, "$Elements", err);
}

int fem_gmsh_read(const char *path, fem_gmsh_mesh *g, nc_error *err)
{
    memset(g, 0, sizeof *g);
    reader r = {fopen(path, "r"), path, 0, 0, {0}};
    if (!r.f) return nc_error_set(err, 1, "%s: cannot open: %s", path, strerror(errno));
    int rc = -1, version = 0, n_ent = 0;
    int have_format = 0, have_names = 0, have_entities = 0, have_nodes = 0, have_elements = 0;
    tag_index *map = NULL;
    entity_phys *ents = NULL;
    while (!next_line(&r)) {
        char sec[64];
        if (sscanf(r.line, "%63s", sec) != 1) continue;
        int *seen = strcmp(sec, "$MeshFormat") == 0      ? &have_format
                    : strcmp(sec, "$PhysicalNames") == 0 ? &have_names
                    : strcmp(sec, "$Entities") == 0      ? &have_entities
                    : strcmp(sec, "$Nodes") == 0         ? &have_nodes
                    : strcmp(sec, "$Elements") == 0      ? &have_elements
                                                         : NULL;
        if (seen && *seen) { bad(&r, err, "a second %s section", sec); goto out; }
        if (seen && seen != &have_format && !version) { bad(&r, err, "%s before $MeshFormat", sec); goto out; }
        if (seen) *seen = 1;
        if (seen == &have_format) {
            double v;
            int file_type;
            if (need_line(&r, err, "$MeshFormat")) goto out;
            if (sscanf(r.line, "%lf %d", &v, &file_type) != 2) { bad(&r, err, "$MeshFormat: expected: version file-type data-size"); goto out; }
            if (file_type != 0) { bad(&r, err, "$MeshFormat: binary .msh files are not supported (save as ASCII)"); goto out; }
            if (v >= 2.0 && v < 3.0) version = 2;
            else if (v >= 4.1 && v < 5.0) version = 4;
            else { bad(&r, err, "$MeshFormat: format version %g not supported (expected 2.2 or 4.1 ASCII)", v); goto out; }
            if (skip_section(&r, "$MeshFormat", err)) goto out;
        } else if (seen == &have_names) {
            if (read_physical_names(&r, g, err)) goto out;
        } else if (seen == &have_entities && version == 4) {
            if (read_entities(&r, &ents, &n_ent, err)) goto out;
        } else if (seen == &have_nodes) {
            if (read_nodes(&r, version, g, &map, err)) goto out;
        } else if (seen == &have_elements) {
            if (!g->n_nodes) { bad(&r, err, "$Elements before $Nodes"); goto out; }
            if (read_elements(&r, version, g, map, ents, n_ent, err)) goto out;
        } else if (sec[0] == '$') {
            if (skip_section(&r, sec, err)) goto out;
        }
    }
    if (r.too_long) { bad(&r, err, "line longer than %zu characters", sizeof r.line - 2); goto out; }
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
