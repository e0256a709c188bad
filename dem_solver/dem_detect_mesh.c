/* dem_detect_mesh — contacts of a sphere with rigid STL meshes (eq. (15) for rigid triangles):
 * the closest feature (face, edge or vertex) of every nearby triangle, each shared feature once
 * and none that lies on the same surface as a touched face or edge (that would count the same
 * contact twice); the reaction goes to the mesh's wall force. */
#include "dem_detect.h"

#include <string.h>

#include "dem_contact_geometry.h"

static int present(const dem_sim *s)
{
    return s->model.n_meshes > 0;
}

static int detect(const dem_sim *s, dem_emit_ctx *out, size_t i, double dt, int *overflow)
{
    const double *pw = s->model.sph.pos + 3 * i;
    double r = s->model.sph.radius[i];
    dem_feature f[DEM_MAX_FEATURES];
    for (size_t m = 0; m < s->model.n_meshes; m++) {
        const dem_mesh *mesh = &s->model.meshes[m];
        double p[3] = {pw[0] - mesh->offset[0], pw[1] - mesh->offset[1], pw[2] - mesh->offset[2]};
        const int32_t *items;
        size_t count = dem_item_grid_query(mesh->grid, p, &items);
        int nf = 0;
        for (size_t c = 0; c < count; c++) {
            int32_t t = items[c];
            const int32_t *v = mesh->tri + 3 * (size_t)t;
            dem_feature x;
            dem_tri_feature which;
            x.d2 = dem_closest_on_triangle(p, mesh->vertices + 3 * (size_t)v[0],
                                           mesh->vertices + 3 * (size_t)v[1],
                                           mesh->vertices + 3 * (size_t)v[2], x.q, &which);
            if (x.d2 >= r * r || x.d2 == 0.0) continue; /* eq. (15) for rigid triangles */
            x.owner = t;
            x.t = 0.0;
            if (which == DEM_TRI_FACE) {
                x.type = 0;
                x.id = t;
            } else if (which <= DEM_TRI_EDGE2) {
                x.type = 1;
                x.id = mesh->tri_edges[3 * (size_t)t + (size_t)(which - DEM_TRI_EDGE0)];
            } else {
                x.type = 2;
                x.id = v[which - DEM_TRI_VERT0];
            }
            dem_add_feature(f, &nf, &x, overflow);
        }
        for (int a = 0; a < nf; a++) {
            /* An edge next to a touched face, or a vertex of a touched face or edge, lies on
             * the same surface as that contact: counting it again would double the force. */
            int drop = 0;
            for (int b = 0; b < nf && !drop; b++) {
                if (b == a) continue;
                if (f[b].type == 0 && f[a].type == 1) {
                    const int32_t *e = mesh->tri_edges + 3 * (size_t)f[b].id;
                    drop = e[0] == f[a].id || e[1] == f[a].id || e[2] == f[a].id;
                } else if (f[b].type == 0 && f[a].type == 2) {
                    const int32_t *v = mesh->tri + 3 * (size_t)f[b].id;
                    drop = v[0] == f[a].id || v[1] == f[a].id || v[2] == f[a].id;
                } else if (f[b].type == 1 && f[a].type == 2) {
                    const int32_t *e = mesh->edges + 2 * (size_t)f[b].id;
                    drop = e[0] == f[a].id || e[1] == f[a].id;
                }
            }
            if (drop) continue;
            double dist = sqrt(f[a].d2);
            dem_contact_in in;
            in.kind = DEM_CONTACT_MESH;
            in.aux = (int32_t)m;
            in.j = f[a].type == 0 ? f[a].id
                   : f[a].type == 1 ? (int32_t)mesh->n_triangles + f[a].id
                                    : (int32_t)(mesh->n_triangles + mesh->n_edges) + f[a].id;
            in.overlap = r - dist;
            for (int k = 0; k < 3; k++) in.n[k] = (f[a].q[k] - p[k]) / dist;
            in.lever_i = r - 0.5 * in.overlap;
            in.lever_j = 0.0;
            memcpy(in.v_other, mesh->velocity, sizeof in.v_other);
            in.weight = 0.0;
            dem_material_wall_pair(&s->contact, &s->model, i, mesh->material, &in.pair);
            if (dem_emit_wall_contact(s, out, i, &in, dt)) return -1;
        }
    }
    return 0;
}

const dem_detector dem_detect_mesh = {"mesh", present, detect};
