/* dem_detect_plane — contacts of a sphere with the one-sided infinite planes (a centre behind
 * a plane does not touch it); the reaction goes to the plane's wall force. */
#include "dem_detect.h"

#include <string.h>

static int present(const dem_sim *s)
{
    return s->model.n_planes > 0;
}

/* The contacts of sphere i with planes first .. n_planes-1 (the first one touches). */
static __attribute__((noinline)) int emit_from(const dem_sim *s, dem_emit_ctx *out, size_t i,
                                               double dt, size_t first)
{
    const double *p = s->model.sph.pos + 3 * i;
    double r = s->model.sph.radius[i];
    for (size_t w = first; w < s->model.n_planes; w++) {
        const dem_plane *pl = &s->model.planes[w];
        double d = (p[0] - pl->point[0]) * pl->normal[0] + (p[1] - pl->point[1]) * pl->normal[1] +
                   (p[2] - pl->point[2]) * pl->normal[2];
        if (fabs(d) >= r) continue; /* one-sided: centres behind the plane are ignored */
        dem_contact_in in;
        in.kind = DEM_CONTACT_PLANE;
        in.j = (int32_t)w;
        in.aux = 0;
        in.overlap = r - d;
        for (int k = 0; k < 3; k++) in.n[k] = -pl->normal[k];
        in.lever_i = r - 0.5 * in.overlap;
        in.lever_j = 0.0;
        memcpy(in.v_other, pl->velocity, sizeof in.v_other);
        in.weight = 0.0;
        dem_material_wall_pair(&s->contact, &s->model, i, pl->material, &in.pair);
        if (dem_emit_wall_contact(s, out, i, &in, dt)) return -1;
    }
    return 0;
}

/* Most spheres touch no plane: a lean scan, and the contacts (same test) out of line. */
static int detect(const dem_sim *s, dem_emit_ctx *out, size_t i, double dt, int *overflow)
{
    (void)overflow; /* no feature list */
    const double *p = s->model.sph.pos + 3 * i;
    double p0 = p[0], p1 = p[1], p2 = p[2], r = s->model.sph.radius[i];
    const dem_plane *planes = s->model.planes;
    for (size_t w = 0; w < s->model.n_planes; w++) {
        const dem_plane *pl = &planes[w];
        double d = (p0 - pl->point[0]) * pl->normal[0] + (p1 - pl->point[1]) * pl->normal[1] +
                   (p2 - pl->point[2]) * pl->normal[2];
        if (fabs(d) < r) return emit_from(s, out, i, dt, w);
    }
    return 0;
}

const dem_detector dem_detect_plane = {"plane", present, detect};
