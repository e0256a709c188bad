/* dem_net_strands — the ropes through each net node (dem_net_strands.h). */
#include "dem_net_strands.h"

#include <math.h>
#include <stdlib.h>

typedef struct end_pair {
    double cosine;
    int32_t a, b; /* edge ends 2 e + s */
} end_pair;

static int by_cosine(const void *x, const void *y)
{
    const end_pair *p = x, *q = y;
    if (p->cosine != q->cosine) return p->cosine < q->cosine ? -1 : 1;
    if (p->a != q->a) return p->a < q->a ? -1 : 1; /* ties in a fixed order */
    return (p->b > q->b) - (p->b < q->b);
}

/* The unit direction from the node at edge end `end` along its edge; 0 for a zero length. */
static int direction(const double *coords, const int32_t *edges, int32_t end, double u[3])
{
    int32_t here = edges[end], there = edges[end ^ 1];
    double len = 0.0;
    for (int k = 0; k < 3; k++) {
        u[k] = coords[3 * (size_t)there + (size_t)k] - coords[3 * (size_t)here + (size_t)k];
        len += u[k] * u[k];
    }
    len = sqrt(len);
    if (!(len > 0.0)) return 0;
    for (int k = 0; k < 3; k++) u[k] /= len;
    return 1;
}

int dem_net_find_strands(size_t n_nodes, const double *coords, size_t n_edges,
                         const int32_t *edges, int32_t *strand, nc_error *err)
{
    size_t n_ends = 2 * n_edges;
    size_t *first = calloc(n_nodes + 1, sizeof *first);
    size_t *fill = malloc((n_nodes ? n_nodes : 1) * sizeof *fill);
    int32_t *ends = malloc((n_ends ? n_ends : 1) * sizeof *ends);
    char *paired = calloc(n_ends ? n_ends : 1, 1);
    end_pair *pairs = NULL;
    int rc = 0;
    if (!first || !fill || !ends || !paired) goto out_of_memory;
    for (size_t k = 0; k < n_ends; k++) {
        first[(size_t)edges[k] + 1]++;
        strand[k] = (int32_t)(k / 2);
    }
    size_t max_degree = 0;
    for (size_t v = 0; v < n_nodes; v++) {
        first[v + 1] += first[v];
        fill[v] = first[v];
        if (first[v + 1] - first[v] > max_degree) max_degree = first[v + 1] - first[v];
    }
    pairs = malloc((max_degree * max_degree / 2 + 1) * sizeof *pairs);
    if (!pairs) goto out_of_memory;
    for (size_t k = 0; k < n_ends; k++) ends[fill[edges[k]]++] = (int32_t)k;
    for (size_t v = 0; v < n_nodes; v++) {
        size_t np = 0, with_length = 0;
        for (size_t x = first[v]; x < first[v + 1]; x++) {
            double ux[3];
            if (!direction(coords, edges, ends[x], ux)) continue;
            with_length++;
            for (size_t y = x + 1; y < first[v + 1]; y++) {
                double uy[3];
                if (!direction(coords, edges, ends[y], uy)) continue;
                pairs[np].cosine = ux[0] * uy[0] + ux[1] * uy[1] + ux[2] * uy[2];
                pairs[np].a = ends[x];
                pairs[np].b = ends[y];
                np++;
            }
        }
        qsort(pairs, np, sizeof *pairs, by_cosine);
        for (size_t p = 0; p < np; p++) {
            int32_t a = pairs[p].a, b = pairs[p].b;
            if (paired[a] || paired[b] || a / 2 == b / 2) continue;
            paired[a] = paired[b] = 1;
            strand[a] = strand[b] = a / 2 < b / 2 ? a / 2 : b / 2;
        }
        for (size_t x = first[v]; x < first[v + 1]; x++) {
            double u[3];
            int has_length = direction(coords, edges, ends[x], u);
            /* one edge of length ending here is a free end; an edge of none touches nothing */
            if (!paired[ends[x]] && (with_length >= 2 || !has_length))
                strand[ends[x]] = DEM_NET_ATTACHED_END(ends[x] / 2);
        }
    }
    goto done;
out_of_memory:
    rc = nc_error_set(err, 1, "dem: out of memory for the net's strands (%zu edges)", n_edges);
done:
    free(first);
    free(fill);
    free(ends);
    free(paired);
    free(pairs);
    return rc;
}
