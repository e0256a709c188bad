/* dem_stl — reading STL triangle meshes (ASCII and binary) into a welded dem_mesh.
 *
 * Vertices with identical coordinates are merged and each undirected edge gets one index, so
 * that contacts on shared edges and vertices can be counted once. Malformed files (truncated,
 * non-numeric, NaN, degenerate triangles, no triangles) are rejected with the file name and
 * what was wrong.
 */
#ifndef DEM_STL_H
#define DEM_STL_H

#include "dem_model.h"
#include "nc_error.h"

/* Fills the geometry of `mesh` (vertices, tri, tri_edges, edges) from the file. */
int dem_stl_load(dem_mesh *mesh, const char *path, nc_error *err);
/* Builds the welded mesh from n raw triangles (9 doubles each); `what` names the source. */
int dem_mesh_from_triangles(dem_mesh *mesh, size_t n, const double *xyz, const char *what,
                            nc_error *err);
void dem_mesh_free(dem_mesh *mesh);

#endif
