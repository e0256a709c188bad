/* fem_mesh_gmsh — reader for Gmsh .msh files (format 2.2 and 4.1, ASCII): nodes, 2-node
 * line elements (type 1), 1-node point elements (type 15) and physical group names.
 * Other element types (surfaces, volumes, higher-order lines) are skipped; node tags are
 * renumbered to 0-based consecutive indices in file order.
 */
#ifndef FEM_MESH_GMSH_H
#define FEM_MESH_GMSH_H

#include "nc_error.h"

typedef struct fem_gmsh_group {
    int dim, tag;
    char name[64];
} fem_gmsh_group;

typedef struct fem_gmsh_mesh {
    int n_nodes;
    double *X;            /* [3 n_nodes] */
    int n_lines;
    int *lines;           /* [2 n_lines] 0-based node indices */
    int *line_physical;   /* [n_lines] physical tag (0 = none) */
    int n_points;
    int *points;          /* [n_points] node index */
    int *point_physical;  /* [n_points] */
    int n_groups;
    fem_gmsh_group *groups;
} fem_gmsh_mesh;

int fem_gmsh_read(const char *path, fem_gmsh_mesh *mesh, nc_error *err);
void fem_gmsh_free(fem_gmsh_mesh *mesh);

#endif
