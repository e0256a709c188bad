/* cpl_interface — the coupling interface Γ: its mesh (from the FEM participant) and the
 * interface state vectors the coupler exchanges.
 *
 * All nodal vectors are row-major n × 3 arrays (node i, component c at [3 i + c]) in the
 * node order of the FEM's interface node list, SI units. The mesh arrays follow the protocol
 * (node_ids i32 [n], coordinates f64 [n,3], elements i32 [m,2] indexing the node list).
 */
#ifndef CPL_INTERFACE_H
#define CPL_INTERFACE_H

#include <stddef.h>
#include <stdint.h>
#include "nc_error.h"

typedef struct cpl_mesh {
    size_t n_nodes;
    size_t n_elements;
    int32_t *node_ids;     /* [n] the FEM's own node indices */
    double *coordinates;   /* [n × 3] positions at the start of the run, m */
    int32_t *elements;     /* [m × 2] 0-based indices into the interface node list */
} cpl_mesh;

/* Copies the arrays into a new mesh and checks them (element indices in range, finite
 * coordinates); `source` names the sender in error messages. */
int cpl_mesh_init(cpl_mesh *mesh, size_t n_nodes, const int32_t *node_ids,
                  const double *coordinates, size_t n_elements, const int32_t *elements,
                  const char *source, nc_error *err);
void cpl_mesh_free(cpl_mesh *mesh);

/* 0 when every entry of the node list (count entries, per_row to a row) indexes one of the
 * interface's n_nodes nodes and, with `once`, none is listed twice; else -1 with err naming
 * `what` (the array), the row and the node. A participant's reply (jacobian_nodes,
 * compliance_nodes) or a checkpoint's lists are checked so before anything is indexed by
 * them. */
int cpl_node_list_check(const int32_t *nodes, size_t count, size_t per_row, size_t n_nodes,
                        int once, const char *what, nc_error *err);

/* Interface state at one instant: displacement (m), velocity (m/s) of the nodes and the
 * contact force on them (N). */
typedef struct cpl_state {
    size_t n_nodes;
    double *displacement;  /* [n × 3] */
    double *velocity;      /* [n × 3] */
    double *force;         /* [n × 3] */
} cpl_state;

int cpl_state_init(cpl_state *s, size_t n_nodes, nc_error *err);   /* zeroed vectors */
void cpl_state_free(cpl_state *s);
void cpl_state_copy(cpl_state *dst, const cpl_state *src);          /* same n_nodes */

/* Sum of the nodal forces: the total force the particles exert on the interface. */
void cpl_total_force(const double *force, size_t n_nodes, double total[3]);
/* Largest |component| of a vector of length n (0 for n = 0). */
double cpl_max_abs(const double *x, size_t n);

#endif
