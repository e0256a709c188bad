/* dem_sim — the simulation object: init/free of all its parts, the model builders (materials,
 * free spheres, clusters, planes) and one explicit time step. */
#include "dem_sim.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "dem_integrate.h"

void dem_sim_init(dem_sim *s)
{
    memset(s, 0, sizeof *s);
    dem_model_init(&s->model);
}

void dem_sim_free(dem_sim *s)
{
    dem_model_free(&s->model);
    dem_contact_state_free(&s->contact);
    dem_thread_work_free(&s->work);
    dem_neighbor_list_free(&s->nlist);
    dem_snapshot_free(&s->snap);
    free(s->wall_force);
    memset(s, 0, sizeof *s);
}

/* ---- building ------------------------------------------------------------------------------- */

int dem_sim_add_material(dem_sim *s, const dem_material *m, nc_error *err)
{
    dem_material *p = realloc(s->model.materials, (s->model.n_materials + 1) * sizeof *p);
    if (!p) return nc_error_set(err, 1, "dem: out of memory");
    s->model.materials = p;
    p[s->model.n_materials] = *m;
    return (int)s->model.n_materials++;
}

static int check_material(const dem_sim *s, int material, nc_error *err)
{
    if (material < 0 || (size_t)material >= s->model.n_materials)
        return nc_error_set(err, 1, "dem: material index %d out of range (%zu materials)",
                            material, s->model.n_materials);
    return 0;
}

int dem_sim_add_sphere(dem_sim *s, const double pos[3], double radius, int material,
                       const double vel[3], const double omega[3], nc_error *err)
{
    static const double zero[3] = {0, 0, 0};
    if (!(radius > 0.0) || !isfinite(radius))
        return nc_error_set(err, 1, "dem: sphere radius must be > 0, got %g", radius);
    if (check_material(s, material, err)) return -1;
    if (dem_model_reserve_spheres(&s->model, s->model.sph.n + 1, err) ||
        dem_model_reserve_bodies(&s->model, s->model.bod.n + 1, err))
        return -1;
    size_t i = s->model.sph.n++, b = s->model.bod.n++;
    s->model.sph.id[i] = (int32_t)i;
    s->model.sph.body[i] = (int32_t)b;
    s->model.sph.material[i] = material;
    s->model.sph.radius[i] = radius;
    memcpy(s->model.sph.offset + 3 * i, zero, sizeof zero);
    memcpy(s->model.sph.pos + 3 * i, pos, 3 * sizeof *pos);
    memcpy(s->model.sph.vel + 3 * i, vel ? vel : zero, 3 * sizeof(double));
    s->model.bod.first_sphere[b] = (int32_t)i;
    s->model.bod.n_spheres[b] = 1;
    s->model.bod.is_cluster[b] = 0;
    memcpy(s->model.bod.pos + 3 * b, pos, 3 * sizeof *pos);
    memcpy(s->model.bod.vel + 3 * b, vel ? vel : zero, 3 * sizeof(double));
    memcpy(s->model.bod.omega + 3 * b, omega ? omega : zero, 3 * sizeof(double));
    double q[4] = {1, 0, 0, 0};
    memcpy(s->model.bod.quat + 4 * b, q, sizeof q);
    memset(s->model.bod.angmom + 3 * b, 0, 3 * sizeof(double));
    return 0;
}

int dem_sim_add_cluster(dem_sim *s, size_t n, const double *pos, const double *radius,
                        int material, const double vel[3], const double omega[3],
                        nc_error *err)
{
    static const double zero[3] = {0, 0, 0};
    if (n == 0) return nc_error_set(err, 1, "dem: a cluster needs at least one sphere");
    if (check_material(s, material, err)) return -1;
    for (size_t k = 0; k < n; k++)
        if (!(radius[k] > 0.0) || !isfinite(radius[k]))
            return nc_error_set(err, 1, "dem: cluster sphere %zu: radius must be > 0, got %g", k,
                                radius[k]);
    if (dem_model_reserve_spheres(&s->model, s->model.sph.n + n, err) ||
        dem_model_reserve_bodies(&s->model, s->model.bod.n + 1, err))
        return -1;
    size_t b = s->model.bod.n++, first = s->model.sph.n;
    s->model.bod.first_sphere[b] = (int32_t)first;
    s->model.bod.n_spheres[b] = (int32_t)n;
    s->model.bod.is_cluster[b] = 1;
    for (size_t k = 0; k < n; k++) {
        size_t i = s->model.sph.n++;
        s->model.sph.id[i] = (int32_t)i;
        s->model.sph.body[i] = (int32_t)b;
        s->model.sph.material[i] = material;
        s->model.sph.radius[i] = radius[k];
        memcpy(s->model.sph.pos + 3 * i, pos + 3 * k, 3 * sizeof(double));
    }
    memcpy(s->model.bod.vel + 3 * b, vel ? vel : zero, 3 * sizeof(double));
    memcpy(s->model.bod.omega + 3 * b, omega ? omega : zero, 3 * sizeof(double));
    double q[4] = {1, 0, 0, 0};
    memcpy(s->model.bod.quat + 4 * b, q, sizeof q);
    return 0; /* mass, centre, inertia and offsets are derived in dem_sim_prepare */
}

int dem_sim_set_cluster_mass(dem_sim *s, size_t body, double mass_kg, const double com[3],
                             const double inertia[9], nc_error *err)
{
    if (body >= s->model.bod.n || !s->model.bod.is_cluster[body])
        return nc_error_set(err, 1, "dem: body %zu is not a cluster (a free sphere's mass is its "
                                    "radius and density)", body);
    if (!(mass_kg > 0.0) || !isfinite(mass_kg))
        return nc_error_set(err, 1, "dem: cluster mass must be a finite number > 0, got %g", mass_kg);
    if ((com == NULL) != (inertia == NULL))
        return nc_error_set(err, 1, "dem: give the centre of mass and the inertia together");
    if (com) {
        for (int k = 0; k < 3; k++)
            if (!isfinite(com[k]))
                return nc_error_set(err, 1, "dem: centre of mass must be finite");
        if (dem_inertia_check(inertia, NULL, err)) return -1;
    }
    dem_mass_override *o = NULL;
    for (size_t k = 0; k < s->model.n_mass_overrides && !o; k++)
        if (s->model.mass_overrides[k].body == (int32_t)body) o = &s->model.mass_overrides[k];
    if (!o) {
        dem_mass_override *p = realloc(s->model.mass_overrides,
                                       (s->model.n_mass_overrides + 1) * sizeof *p);
        if (!p) return nc_error_set(err, 1, "dem: out of memory");
        s->model.mass_overrides = p;
        o = &p[s->model.n_mass_overrides++];
    }
    memset(o, 0, sizeof *o);
    o->body = (int32_t)body;
    o->mass_kg = mass_kg;
    o->full = com != NULL;
    if (com) {
        memcpy(o->com, com, sizeof o->com);
        /* the symmetric part (the check allowed asymmetry of 1e-9 of the largest entry) */
        for (int a = 0; a < 3; a++)
            for (int c = 0; c < 3; c++) o->inertia[3 * a + c] = 0.5 * (inertia[3 * a + c] + inertia[3 * c + a]);
    }
    return 0;
}

int dem_sim_add_plane(dem_sim *s, const double point[3], const double normal[3],
                      const double velocity[3], int material, nc_error *err)
{
    static const double zero[3] = {0, 0, 0};
    if (check_material(s, material, err)) return -1;
    double len = sqrt(normal[0] * normal[0] + normal[1] * normal[1] + normal[2] * normal[2]);
    if (!(len > 0.0) || !isfinite(len))
        return nc_error_set(err, 1, "dem: plane normal must be a non-zero finite vector");
    dem_plane *p = realloc(s->model.planes, (s->model.n_planes + 1) * sizeof *p);
    if (!p) return nc_error_set(err, 1, "dem: out of memory");
    s->model.planes = p;
    dem_plane *pl = &p[s->model.n_planes++];
    for (int k = 0; k < 3; k++) {
        pl->point0[k] = pl->point[k] = point[k];
        pl->normal[k] = normal[k] / len;
        pl->velocity[k] = velocity ? velocity[k] : zero[k];
    }
    pl->material = material;
    return 0;
}

/* ---- stepping ------------------------------------------------------------------------------- */

int dem_sim_step_forces(dem_sim *s, double dt, nc_error *err)
{
    for (size_t w = 0; w < s->model.n_planes; w++)
        for (int k = 0; k < 3; k++)
            s->model.planes[w].point[k] =
                s->model.planes[w].point0[k] + s->model.planes[w].velocity[k] * s->time_s;
    for (size_t m = 0; m < s->model.n_meshes; m++)
        for (int k = 0; k < 3; k++)
            s->model.meshes[m].offset[k] = s->model.meshes[m].velocity[k] * s->time_s;
    return dem_contact_pass(s, dt, err);
}

void dem_sim_step_advance(dem_sim *s, double dt)
{
    dem_integrate_bodies(s, dt);
    s->time_s += dt;
    s->step++;
}

int dem_sim_step(dem_sim *s, double dt, nc_error *err)
{
    if (dem_sim_step_forces(s, dt, err)) return -1;
    dem_sim_step_advance(s, dt);
    return 0;
}
