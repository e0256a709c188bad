/* cpl_interface — interface mesh and state vectors (allocation, checks, small reductions). */
#include "cpl_interface.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

int cpl_mesh_init(cpl_mesh *mesh, size_t n_nodes, const int32_t *node_ids,
                  const double *coordinates, size_t n_elements, const int32_t *elements,
                  const char *source, nc_error *err)
{
    memset(mesh, 0, sizeof *mesh);
    if (n_nodes == 0) return nc_error_set(err, 1, "%s: interface has no nodes", source);
    for (size_t i = 0; i < 3 * n_nodes; i++)
        if (!isfinite(coordinates[i]))
            return nc_error_set(err, 1, "%s: interface coordinates[%zu][%zu] is not finite",
                                source, i / 3, i % 3);
    for (size_t e = 0; e < 2 * n_elements; e++)
        if (elements[e] < 0 || (size_t)elements[e] >= n_nodes)
            return nc_error_set(err, 1,
                                "%s: interface elements[%zu][%zu] = %d is not a node index in "
                                "0..%zu", source, e / 2, e % 2, (int)elements[e], n_nodes - 1);
    mesh->node_ids = malloc(n_nodes * sizeof *mesh->node_ids);
    mesh->coordinates = malloc(3 * n_nodes * sizeof *mesh->coordinates);
    mesh->elements = malloc((2 * n_elements + 1) * sizeof *mesh->elements);
    if (!mesh->node_ids || !mesh->coordinates || !mesh->elements) {
        cpl_mesh_free(mesh);
        return nc_error_set(err, 1, "%s: out of memory for an interface of %zu nodes", source,
                            n_nodes);
    }
    mesh->n_nodes = n_nodes;
    mesh->n_elements = n_elements;
    memcpy(mesh->node_ids, node_ids, n_nodes * sizeof *node_ids);
    memcpy(mesh->coordinates, coordinates, 3 * n_nodes * sizeof *coordinates);
    if (n_elements) memcpy(mesh->elements, elements, 2 * n_elements * sizeof *elements);
    return 0;
}

void cpl_mesh_free(cpl_mesh *mesh)
{
    if (!mesh) return;
    free(mesh->node_ids);
    free(mesh->coordinates);
    free(mesh->elements);
    memset(mesh, 0, sizeof *mesh);
}

int cpl_state_init(cpl_state *s, size_t n_nodes, nc_error *err)
{
    memset(s, 0, sizeof *s);
    s->displacement = calloc(3 * n_nodes + 1, sizeof(double));
    s->velocity = calloc(3 * n_nodes + 1, sizeof(double));
    s->force = calloc(3 * n_nodes + 1, sizeof(double));
    if (!s->displacement || !s->velocity || !s->force) {
        cpl_state_free(s);
        return nc_error_set(err, 1, "out of memory for interface state of %zu nodes", n_nodes);
    }
    s->n_nodes = n_nodes;
    return 0;
}

void cpl_state_free(cpl_state *s)
{
    if (!s) return;
    free(s->displacement);
    free(s->velocity);
    free(s->force);
    memset(s, 0, sizeof *s);
}

void cpl_state_copy(cpl_state *dst, const cpl_state *src)
{
    size_t bytes = 3 * src->n_nodes * sizeof(double);
    memcpy(dst->displacement, src->displacement, bytes);
    memcpy(dst->velocity, src->velocity, bytes);
    memcpy(dst->force, src->force, bytes);
}

void cpl_total_force(const double *force, size_t n_nodes, double total[3])
{
    total[0] = total[1] = total[2] = 0.0;
    for (size_t i = 0; i < n_nodes; i++)
        for (int c = 0; c < 3; c++) total[c] += force[3 * i + c];
}

double cpl_max_abs(const double *x, size_t n)
{
    double m = 0.0;
    for (size_t i = 0; i < n; i++) {
        double a = fabs(x[i]);
        if (a > m) m = a;
    }
    return m;
}

int cpl_node_list_check(const int32_t *nodes, size_t count, size_t per_row, size_t n_nodes,
                        int once, const char *what, nc_error *err)
{
    for (size_t q = 0; q < count; q++) {
        if (nodes[q] < 0 || (size_t)nodes[q] >= n_nodes)
            return nc_error_set(err, 1, "%s row %zu: node %d is not an interface node (0..%zu)",
                                what, q / per_row, (int)nodes[q], n_nodes ? n_nodes - 1 : 0);
        for (size_t p = 0; once && p < q; p++)
            if (nodes[p] == nodes[q])
                return nc_error_set(err, 1, "%s row %zu: node %d is listed twice", what,
                                    q / per_row, (int)nodes[q]);
    }
    return 0;
}
