/* dem_config — dem.json parser with validated fields and named errors. */
#include "nc_plausible.h"
#include "dem_config.h"

#include <cjson/cJSON.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "dem_contact_law.h"
#include "dem_neighbor_grid.h"
#include "dem_stl.h"
#include "nc_file.h"
#include "nc_json.h"
#include "nc_time.h"

/* Wide engineering ranges: a value outside is a warning (likely a unit mistake), not an error. */
#define PLAUSIBLE_RADIUS_MIN_M 1e-3
#define PLAUSIBLE_RADIUS_MAX_M 20.0
#define PLAUSIBLE_SPEED_MAX_M_S 100.0


static void warn_radius(FILE *sink, const char *where, const char *key, double r)
{
    if (r < PLAUSIBLE_RADIUS_MIN_M || r > PLAUSIBLE_RADIUS_MAX_M)
        nc_warn(sink, "%s.%s: %s%g m%s outside the plausible range 1e-3..20 m for a rock", where,
             key, strcmp(key, "radius") ? "gives a radius of " : "", r,
             strcmp(key, "radius") ? "," : " is");
}

static void warn_modulus(FILE *sink, const char *where, double e)
{
    if (e < NC_PLAUSIBLE_MODULUS_MIN_PA || e > NC_PLAUSIBLE_MODULUS_MAX_PA)
        nc_warn(sink, "%s.youngs_modulus_pa: %g Pa is outside the plausible range 1e5..1e12 Pa "
                   "(rock about 1e10..1e11, steel 2.1e11)", where, e);
}

static void warn_speed(FILE *sink, const char *where, const char *key, const double v[3])
{
    double sp = sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
    if (sp > PLAUSIBLE_SPEED_MAX_M_S)
        nc_warn(sink, "%s.%s: gives a speed of %g m/s, above the plausible 100 m/s for a rockfall",
             where, key, sp);
}

static double norm3(const double v[3])
{
    return sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
}

/* The initial velocity of a body of mass `mass_kg` (<= 0: not known here, impact_energy_j is
 * refused) from exactly one of velocity, drop_height_m (free fall from rest under `gravity`
 * through that height: v = sqrt(2 |g| h) along g) or impact_energy_j (v = sqrt(2 E / m) along
 * impact_direction, default along g). Missing all three: at rest. */
static int parse_initial_velocity(const cJSON *o, const char *where, const double gravity[3],
                                  double mass_kg, FILE *sink, double vel[3], nc_error *err)
{
    static const double zero[3] = {0, 0, 0};
    const char *given[3] = {"velocity", "drop_height_m", "impact_energy_j"};
    int n = 0, which = 0;
    for (int k = 0; k < 3; k++)
        if (cJSON_GetObjectItemCaseSensitive(o, given[k])) {
            n++;
            which = k;
        }
    if (n > 1)
        return nc_error_set(err, 1, "%s: give only one of velocity, drop_height_m and "
                                    "impact_energy_j", where);
    int has_dir = cJSON_GetObjectItemCaseSensitive(o, "impact_direction") != NULL;
    if (has_dir && !(n == 1 && which == 2))
        return nc_error_set(err, 1, "%s.impact_direction: only used with impact_energy_j", where);
    double g = norm3(gravity);
    if (n == 0 || which == 0) {
        if (nc_json_vec3_opt(o, where, "velocity", zero, vel, err)) return -1;
        if (n) warn_speed(sink, where, "velocity", vel);
        return 0;
    }
    double dir[3], speed;
    if (which == 1) {
        double h;
        if (nc_json_number_range(o, where, "drop_height_m", 0.0, INFINITY, &h, err)) return -1;
        if (!(g > 0.0))
            return nc_error_set(err, 1, "%s.drop_height_m: needs a non-zero gravity", where);
        for (int k = 0; k < 3; k++) dir[k] = gravity[k] / g;
        speed = sqrt(2.0 * g * h);
    } else {
        double e;
        if (nc_json_number_range(o, where, "impact_energy_j", 0.0, INFINITY, &e, err)) return -1;
        if (!(mass_kg > 0.0))
            return nc_error_set(err, 1, "%s.impact_energy_j: not available here (the mass is "
                                        "not known)", where);
        if (has_dir) {
            if (nc_json_vec3(o, where, "impact_direction", dir, err)) return -1;
            double d = norm3(dir);
            if (!(d > 0.0))
                return nc_error_set(err, 1, "%s.impact_direction: expected a non-zero vector", where);
            for (int k = 0; k < 3; k++) dir[k] /= d;
        } else if (g > 0.0) {
            for (int k = 0; k < 3; k++) dir[k] = gravity[k] / g;
        } else {
            return nc_error_set(err, 1, "%s.impact_direction: missing (gravity is zero, so there "
                                        "is no default direction)", where);
        }
        speed = sqrt(2.0 * e / mass_kg);
    }
    for (int k = 0; k < 3; k++) vel[k] = speed * dir[k];
    warn_speed(sink, where, given[which], vel);
    return 0;
}

static double sphere_mass_kg(double r, double density)
{
    return 4.0 / 3.0 * M_PI * r * r * r * density;
}

static int find_material(const dem_sim *s, const cJSON *obj, const char *where, int *index,
                         nc_error *err)
{
    const char *name;
    if (nc_json_string_opt(obj, where, "material", NULL, &name, err)) return -1;
    if (!name) {
        *index = 0;
        return 0;
    }
    for (size_t k = 0; k < s->model.n_materials; k++)
        if (strcmp(s->model.materials[k].name, name) == 0) {
            *index = (int)k;
            return 0;
        }
    return nc_error_set(err, 1, "%s.material: unknown material \"%s\" (define it in materials)",
                        where, name);
}

static int parse_materials(dem_sim *s, const cJSON *root, const char *file, FILE *sink,
                           nc_error *err)
{
    static const char *const keys[] = {"name", "youngs_modulus_pa", "poisson_ratio",
                                       "density_kg_m3", "restitution", "friction", NULL};
    const cJSON *arr;
    int count;
    if (nc_json_array(root, file, "materials", &arr, &count, err)) return -1;
    if (count == 0) return nc_error_set(err, 1, "%s.materials: expected at least one material", file);
    int k = 0;
    for (const cJSON *m = count ? arr->child : NULL; m; m = m->next, k++) {
        char where[600];
        nc_json_path_index(where, sizeof where, file, "materials", k);
        if (!cJSON_IsObject(m)) return nc_error_set(err, 1, "%s: expected an object", where);
        if (nc_json_check_keys(m, where, keys, err)) return -1;
        dem_material mat;
        memset(&mat, 0, sizeof mat);
        const char *name;
        if (nc_json_string(m, where, "name", &name, err) ||
            nc_json_positive(m, where, "youngs_modulus_pa", &mat.youngs_modulus_pa, err) ||
            nc_json_number_range(m, where, "poisson_ratio", -0.999, 0.5, &mat.poisson_ratio, err) ||
            nc_json_positive(m, where, "density_kg_m3", &mat.density_kg_m3, err) ||
            nc_json_number_range(m, where, "restitution", 0.0, 1.0, &mat.restitution, err) ||
            nc_json_number_range(m, where, "friction", 0.0, INFINITY, &mat.friction, err))
            return -1;
        if (strlen(name) == 0 || strlen(name) >= sizeof mat.name)
            return nc_error_set(err, 1, "%s.name: expected 1 to %zu characters", where,
                                sizeof mat.name - 1);
        for (size_t q = 0; q < s->model.n_materials; q++)
            if (strcmp(s->model.materials[q].name, name) == 0)
                return nc_error_set(err, 1, "%s.name: material \"%s\" defined twice", where, name);
        snprintf(mat.name, sizeof mat.name, "%s", name);
        warn_modulus(sink, where, mat.youngs_modulus_pa);
        if (mat.density_kg_m3 < NC_PLAUSIBLE_DENSITY_MIN || mat.density_kg_m3 > NC_PLAUSIBLE_DENSITY_MAX)
            nc_warn(sink, "%s.density_kg_m3: %g kg/m³ is outside the plausible range 100..25000 "
                       "kg/m³ (rock 1000..5000)", where, mat.density_kg_m3);
        if (dem_sim_add_material(s, &mat, err) < 0) return -1;
    }
    return 0;
}

static int parse_particles(dem_sim *s, const cJSON *root, const char *file, FILE *sink,
                           nc_error *err)
{
    static const char *const keys[] = {"position", "radius", "mass_kg", "velocity",
                                       "drop_height_m", "impact_energy_j", "impact_direction",
                                       "angular_velocity", "material", NULL};
    static const double zero[3] = {0, 0, 0};
    const cJSON *arr;
    int count;
    if (nc_json_array_opt(root, file, "particles", &arr, &count, err)) return -1;
    int k = 0;
    for (const cJSON *p = count ? arr->child : NULL; p; p = p->next, k++) {
        char where[600];
        nc_json_path_index(where, sizeof where, file, "particles", k);
        if (!cJSON_IsObject(p)) return nc_error_set(err, 1, "%s: expected an object", where);
        if (nc_json_check_keys(p, where, keys, err)) return -1;
        double pos[3], vel[3], omega[3], r = 0.0, mass = 0.0;
        int mat;
        int has_r = cJSON_GetObjectItemCaseSensitive(p, "radius") != NULL;
        int has_m = cJSON_GetObjectItemCaseSensitive(p, "mass_kg") != NULL;
        if (nc_json_vec3(p, where, "position", pos, err) ||
            (has_r && nc_json_positive(p, where, "radius", &r, err)) ||
            (has_m && nc_json_positive(p, where, "mass_kg", &mass, err)) ||
            nc_json_vec3_opt(p, where, "angular_velocity", zero, omega, err) ||
            find_material(s, p, where, &mat, err))
            return -1;
        if (!has_r && !has_m)
            return nc_error_set(err, 1, "%s.radius: missing (give radius or mass_kg)", where);
        double rho = s->model.materials[mat].density_kg_m3;
        if (has_m) {
            /* the sphere of that mass in the particle's material: m = 4/3 π r³ ρ */
            double rm = cbrt(3.0 * mass / (4.0 * M_PI * rho));
            if (has_r && !(fabs(rm - r) <= 1e-9 * r))
                return nc_error_set(err, 1, "%s: radius %.10g m and mass_kg %.10g kg disagree "
                                            "(a sphere of %.10g kg of material \"%s\", %g kg/m³, "
                                            "has radius %.10g m); give one of them", where, r,
                                    mass, mass, s->model.materials[mat].name, rho, rm);
            if (!has_r) r = rm;
        }
        warn_radius(sink, where, has_r ? "radius" : "mass_kg", r);
        if (parse_initial_velocity(p, where, s->model.prm.gravity, sphere_mass_kg(r, rho), sink,
                                   vel, err))
            return -1;
        if (dem_sim_add_sphere(s, pos, r, mat, vel, omega, err)) return nc_error_prefix(err, "%s", where);
    }
    return 0;
}

/* xorshift64* — a small reproducible generator whose state lives in the caller. */
static double rng_uniform(uint64_t *state)
{
    uint64_t x = *state;
    x ^= x >> 12;
    x ^= x << 25;
    x ^= x >> 27;
    *state = x;
    return (double)((x * 2685821657736338717ULL) >> 11) * (1.0 / 9007199254740992.0);
}

static int generate_lattice(dem_sim *s, const cJSON *g, const char *where, const double lo[3],
                            const double hi[3], double r, int mat, const double vel[3],
                            nc_error *err)
{
    double spacing;
    if (nc_json_number_range_opt(g, where, "spacing", 2.0 * r, 2.0 * r, INFINITY, &spacing, err))
        return -1;
    long n[3];
    for (int k = 0; k < 3; k++) {
        double room = hi[k] - lo[k] - 2.0 * r;
        n[k] = (long)floor(room / spacing + 1e-9) + 1;
    }
    if ((double)n[0] * (double)n[1] * (double)n[2] > 5e7)
        return nc_error_set(err, 1, "%s: lattice would hold more than 5e7 spheres", where);
    for (long z = 0; z < n[2]; z++)
        for (long y = 0; y < n[1]; y++)
            for (long x = 0; x < n[0]; x++) {
                double p[3] = {lo[0] + r + (double)x * spacing, lo[1] + r + (double)y * spacing,
                               lo[2] + r + (double)z * spacing};
                if (dem_sim_add_sphere(s, p, r, mat, vel, NULL, err)) return -1;
            }
    return 0;
}

static int generate_random(dem_sim *s, const cJSON *g, const char *where, const double lo[3],
                           const double hi[3], double r, int mat, const double vel[3],
                           nc_error *err)
{
    long count, seed, attempts;
    double rmax;
    if (nc_json_int(g, where, "count", 1, 50000000, &count, err) ||
        nc_json_int_opt(g, where, "seed", 1, 0, 0x7fffffffL, &seed, err) ||
        nc_json_int_opt(g, where, "max_attempts", 1000, 1, 1000000000L, &attempts, err) ||
        nc_json_number_range_opt(g, where, "radius_max", r, r, INFINITY, &rmax, err))
        return -1;
    for (int k = 0; k < 3; k++)
        if (hi[k] - lo[k] <= 2.0 * rmax)
            return nc_error_set(err, 1, "%s: the box is smaller than one sphere diameter", where);
    /* placed spheres in a hash grid of cells >= 2 rmax: a candidate checks 27 cells */
    double cell = 2.0 * rmax;
    long dims[3];
    double total = 1.0;
    for (int k = 0; k < 3; k++) {
        dims[k] = (long)floor((hi[k] - lo[k]) / cell) + 1;
        total *= (double)dims[k];
    }
    while (total > 4.0 * (double)count + 1e6) {
        cell *= 1.5;
        total = 1.0;
        for (int k = 0; k < 3; k++) {
            dims[k] = (long)floor((hi[k] - lo[k]) / cell) + 1;
            total *= (double)dims[k];
        }
    }
    size_t ncell = (size_t)total;
    int32_t *head = malloc(ncell * sizeof *head);
    int32_t *next = malloc((size_t)count * sizeof *next);
    double *xyz = malloc(3 * (size_t)count * sizeof *xyz);
    double *rad = malloc((size_t)count * sizeof *rad);
    if (!head || !next || !xyz || !rad) {
        free(head); free(next); free(xyz); free(rad);
        return nc_error_set(err, 1, "%s: out of memory for %ld spheres", where, count);
    }
    for (size_t c = 0; c < ncell; c++) head[c] = -1;
    uint64_t state = 0x9E3779B97F4A7C15ULL ^ (uint64_t)seed;
    long placed = 0, tries = 0, max_tries = attempts * count;
    while (placed < count && tries < max_tries) {
        tries++;
        double rr = r + (rmax - r) * rng_uniform(&state);
        double p[3];
        long c[3];
        for (int k = 0; k < 3; k++) {
            p[k] = lo[k] + rr + (hi[k] - lo[k] - 2.0 * rr) * rng_uniform(&state);
            c[k] = (long)((p[k] - lo[k]) / cell);
            if (c[k] >= dims[k]) c[k] = dims[k] - 1;
        }
        int ok = 1;
        for (long dz = -1; dz <= 1 && ok; dz++)
            for (long dy = -1; dy <= 1 && ok; dy++)
                for (long dx = -1; dx <= 1 && ok; dx++) {
                    long x = c[0] + dx, y = c[1] + dy, z = c[2] + dz;
                    if (x < 0 || y < 0 || z < 0 || x >= dims[0] || y >= dims[1] || z >= dims[2]) continue;
                    for (int32_t q = head[(z * dims[1] + y) * dims[0] + x]; q >= 0 && ok; q = next[q]) {
                        double d2 = 0.0;
                        for (int k = 0; k < 3; k++) {
                            double d = xyz[3 * q + k] - p[k];
                            d2 += d * d;
                        }
                        double rs = rr + rad[q];
                        if (d2 < rs * rs) ok = 0;
                    }
                }
        if (!ok) continue;
        memcpy(xyz + 3 * placed, p, sizeof p);
        rad[placed] = rr;
        size_t id = (size_t)((c[2] * dims[1] + c[1]) * dims[0] + c[0]);
        next[placed] = head[id];
        head[id] = (int32_t)placed;
        placed++;
    }
    int rc = 0;
    if (placed < count)
        rc = nc_error_set(err, 1, "%s: placed only %ld of %ld non-overlapping spheres after %ld "
                                  "attempts (box too small for count?)", where, placed, count, tries);
    for (long k = 0; k < placed && rc == 0; k++)
        rc = dem_sim_add_sphere(s, xyz + 3 * k, rad[k], mat, vel, NULL, err);
    free(head); free(next); free(xyz); free(rad);
    return rc;
}

static int parse_generators(dem_sim *s, const cJSON *root, const char *file, FILE *sink,
                            nc_error *err)
{
    static const char *const keys[] = {"type", "min", "max", "radius", "radius_max", "material",
                                       "velocity", "drop_height_m", "spacing", "count", "seed",
                                       "max_attempts", NULL};
    static const char *const types[] = {"lattice", "random", NULL};
    const cJSON *arr;
    int count;
    if (nc_json_array_opt(root, file, "generators", &arr, &count, err)) return -1;
    int k = 0;
    for (const cJSON *g = count ? arr->child : NULL; g; g = g->next, k++) {
        char where[600];
        nc_json_path_index(where, sizeof where, file, "generators", k);
        if (!cJSON_IsObject(g)) return nc_error_set(err, 1, "%s: expected an object", where);
        if (nc_json_check_keys(g, where, keys, err)) return -1;
        int type, mat;
        double lo[3], hi[3], vel[3], r;
        if (!cJSON_GetObjectItemCaseSensitive(g, "type"))
            return nc_error_set(err, 1, "%s.type: missing (expected \"lattice\" or \"random\")", where);
        if (nc_json_choice_opt(g, where, "type", types, 0, &type, err) ||
            nc_json_vec3(g, where, "min", lo, err) || nc_json_vec3(g, where, "max", hi, err) ||
            nc_json_positive(g, where, "radius", &r, err) ||
            parse_initial_velocity(g, where, s->model.prm.gravity, 0.0, sink, vel, err) ||
            find_material(s, g, where, &mat, err))
            return -1;
        warn_radius(sink, where, "radius", r);
        for (int d = 0; d < 3; d++)
            if (hi[d] - lo[d] < 2.0 * r)
                return nc_error_set(err, 1, "%s: max - min must be at least one diameter (%g m) "
                                            "in every direction", where, 2.0 * r);
        if (type == 1 && !cJSON_GetObjectItemCaseSensitive(g, "count"))
            return nc_error_set(err, 1, "%s.count: missing (expected an integer >= 1)", where);
        int rc = type == 0 ? generate_lattice(s, g, where, lo, hi, r, mat, vel, err)
                           : generate_random(s, g, where, lo, hi, r, mat, vel, err);
        if (rc) return -1;
    }
    return 0;
}

/* A 3×3 matrix [[a, b, c], [d, e, f], [g, h, i]] of finite numbers, row-major into m. */
static int parse_matrix3(const cJSON *o, const char *where, const char *key, double m[9],
                         nc_error *err)
{
    const cJSON *rows = cJSON_GetObjectItemCaseSensitive(o, key);
    int ok = cJSON_IsArray(rows) && cJSON_GetArraySize(rows) == 3;
    int r = 0;
    for (const cJSON *row = ok ? rows->child : NULL; row && ok; row = row->next, r++) {
        ok = cJSON_IsArray(row) && cJSON_GetArraySize(row) == 3;
        int c = 0;
        for (const cJSON *v = ok ? row->child : NULL; v && ok; v = v->next, c++) {
            if (!cJSON_IsNumber(v) || !isfinite(v->valuedouble))
                return nc_error_set(err, 1, "%s.%s[%d][%d]: expected a finite number", where, key,
                                    r, c);
            m[3 * r + c] = v->valuedouble;
        }
    }
    if (!ok)
        return nc_error_set(err, 1, "%s.%s: expected a 3x3 array [[Ixx, Ixy, Ixz], [Iyx, Iyy, "
                                    "Iyz], [Izx, Izy, Izz]] (kg m²)", where, key);
    return 0;
}

/* The optional true mass properties of cluster `where` (spheres at pos, rad): mass_kg alone, or
 * mass_kg, center_of_mass and inertia_kg_m2 together. *given = 0 when none is given. The
 * centre must lie within the spheres' bounding box; a mass far from the spheres' or a moment
 * beyond m R² (R the spheres' extent from the centre) is warned about as a likely unit slip. */
static int parse_cluster_mass(const cJSON *c, const char *where, int ns, const double *pos,
                              const double *rad, double sphere_mass, FILE *sink, int *given,
                              double *mass, double com[3], double inertia[9], nc_error *err)
{
    int has_m = cJSON_GetObjectItemCaseSensitive(c, "mass_kg") != NULL;
    int has_c = cJSON_GetObjectItemCaseSensitive(c, "center_of_mass") != NULL;
    int has_i = cJSON_GetObjectItemCaseSensitive(c, "inertia_kg_m2") != NULL;
    *given = 0;
    if (!has_m && !has_c && !has_i) return 0;
    if (!has_m || has_c != has_i)
        return nc_error_set(err, 1, "%s.%s: give mass_kg alone or mass_kg, center_of_mass and "
                                    "inertia_kg_m2 together", where,
                            !has_m ? (has_c ? "center_of_mass" : "inertia_kg_m2")
                                   : (has_c ? "inertia_kg_m2" : "center_of_mass"));
    if (nc_json_positive(c, where, "mass_kg", mass, err)) return -1;
    if (!isfinite(*mass)) return nc_error_set(err, 1, "%s.mass_kg: expected a finite number", where);
    /* overlapping fillings sum to several times the body; a factor 50 is a unit slip */
    if (*mass > 50.0 * sphere_mass || *mass < sphere_mass / 50.0)
        nc_warn(sink, "%s.mass_kg: %g kg is %.3g times the spheres' %g kg (wrong unit or "
                      "material density?)", where, *mass, *mass / sphere_mass, sphere_mass);
    *given = 1;
    if (!has_c) return 0;
    *given = 2;
    if (nc_json_vec3(c, where, "center_of_mass", com, err) ||
        parse_matrix3(c, where, "inertia_kg_m2", inertia, err))
        return -1;
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    double extent = 0.0;
    for (int q = 0; q < ns; q++) {
        double d2 = 0.0;
        for (int k = 0; k < 3; k++) {
            lo[k] = fmin(lo[k], pos[3 * q + k] - rad[q]);
            hi[k] = fmax(hi[k], pos[3 * q + k] + rad[q]);
            d2 += (pos[3 * q + k] - com[k]) * (pos[3 * q + k] - com[k]);
        }
        extent = fmax(extent, sqrt(d2) + rad[q]);
    }
    for (int k = 0; k < 3; k++)
        if (!(com[k] >= lo[k] && com[k] <= hi[k]))
            return nc_error_set(err, 1, "%s.center_of_mass: [%g, %g, %g] m lies outside the "
                                        "spheres' bounding box [%g, %g, %g]..[%g, %g, %g] m", where,
                                com[0], com[1], com[2], lo[0], lo[1], lo[2], hi[0], hi[1], hi[2]);
    double principal[3];
    if (dem_inertia_check(inertia, principal, err))
        return nc_error_prefix(err, "%s.inertia_kg_m2", where);
    if (principal[2] > *mass * extent * extent)
        nc_warn(sink, "%s.inertia_kg_m2: principal moment %g kg m² exceeds m R² = %g kg m² "
                      "(R = %g m, the spheres' extent from the centre of mass): wrong unit?",
                where, principal[2], *mass * extent * extent, extent);
    return 0;
}

static int parse_clusters(dem_sim *s, const cJSON *root, const char *file, FILE *sink,
                          nc_error *err)
{
    static const char *const keys[] = {"spheres", "material", "velocity", "drop_height_m",
                                       "impact_energy_j", "impact_direction", "angular_velocity",
                                       "mass_kg", "center_of_mass", "inertia_kg_m2", NULL};
    static const char *const skeys[] = {"position", "radius", NULL};
    static const double zero[3] = {0, 0, 0};
    const cJSON *arr;
    int count;
    if (nc_json_array_opt(root, file, "clusters", &arr, &count, err)) return -1;
    int k = 0;
    for (const cJSON *c = count ? arr->child : NULL; c; c = c->next, k++) {
        char where[600];
        nc_json_path_index(where, sizeof where, file, "clusters", k);
        if (!cJSON_IsObject(c)) return nc_error_set(err, 1, "%s: expected an object", where);
        if (nc_json_check_keys(c, where, keys, err)) return -1;
        const cJSON *sp;
        int ns, mat;
        double vel[3], omega[3];
        if (nc_json_array(c, where, "spheres", &sp, &ns, err) ||
            nc_json_vec3_opt(c, where, "angular_velocity", zero, omega, err) ||
            find_material(s, c, where, &mat, err))
            return -1;
        if (ns == 0) return nc_error_set(err, 1, "%s.spheres: expected at least one sphere", where);
        double *pos = malloc(3 * (size_t)ns * sizeof *pos), *rad = malloc((size_t)ns * sizeof *rad);
        if (!pos || !rad) {
            free(pos); free(rad);
            return nc_error_set(err, 1, "%s: out of memory", where);
        }
        int rc = 0;
        int q = 0;
        for (const cJSON *o = sp->child; o && rc == 0; o = o->next, q++) {
            char sw[700];
            nc_json_path_index(sw, sizeof sw, where, "spheres", q);
            if (!cJSON_IsObject(o)) rc = nc_error_set(err, 1, "%s: expected an object", sw);
            else rc = nc_json_check_keys(o, sw, skeys, err) ||
                      nc_json_vec3(o, sw, "position", pos + 3 * q, err) ||
                      nc_json_positive(o, sw, "radius", rad + q, err) ? -1 : 0;
            if (rc == 0) warn_radius(sink, sw, "radius", rad[q]);
        }
        /* the body's mass as dem_sim_prepare sums it: the spheres' volumes times ρ */
        double mass = 0.0, com[3], inertia[9];
        int given = 0;
        for (int j = 0; j < ns && rc == 0; j++)
            mass += sphere_mass_kg(rad[j], s->model.materials[mat].density_kg_m3);
        /* ... or the given one, which impact_energy_j then uses too */
        if (rc == 0)
            rc = parse_cluster_mass(c, where, ns, pos, rad, mass, sink, &given, &mass, com,
                                    inertia, err);
        if (rc == 0) rc = parse_initial_velocity(c, where, s->model.prm.gravity, mass, sink, vel, err);
        if (rc == 0) rc = dem_sim_add_cluster(s, (size_t)ns, pos, rad, mat, vel, omega, err);
        if (rc == 0 && given)
            rc = dem_sim_set_cluster_mass(s, s->model.bod.n - 1, mass, given == 2 ? com : NULL,
                                          given == 2 ? inertia : NULL, err)
                     ? nc_error_prefix(err, "%s", where)
                     : 0;
        free(pos);
        free(rad);
        if (rc) return -1;
    }
    return 0;
}

static int parse_planes(dem_sim *s, const cJSON *root, const char *file, nc_error *err)
{
    static const char *const keys[] = {"point", "normal", "velocity", "material", NULL};
    static const double zero[3] = {0, 0, 0};
    const cJSON *arr;
    int count;
    if (nc_json_array_opt(root, file, "planes", &arr, &count, err)) return -1;
    int k = 0;
    for (const cJSON *p = count ? arr->child : NULL; p; p = p->next, k++) {
        char where[600];
        nc_json_path_index(where, sizeof where, file, "planes", k);
        if (!cJSON_IsObject(p)) return nc_error_set(err, 1, "%s: expected an object", where);
        if (nc_json_check_keys(p, where, keys, err)) return -1;
        double point[3], normal[3], vel[3];
        int mat;
        if (nc_json_vec3(p, where, "point", point, err) ||
            nc_json_vec3(p, where, "normal", normal, err) ||
            nc_json_vec3_opt(p, where, "velocity", zero, vel, err) ||
            find_material(s, p, where, &mat, err))
            return -1;
        if (dem_sim_add_plane(s, point, normal, vel, mat, err)) return nc_error_prefix(err, "%s", where);
    }
    return 0;
}

/* STL files carry no unit and are read in metres: a terrain exported in millimetres spans a
 * thousand times its size. */
#define PLAUSIBLE_MESH_EXTENT_MAX_M 5000.0

static void warn_mesh_extent(FILE *sink, const char *where, const dem_mesh *mesh)
{
    double extent = 0.0;
    for (int k = 0; k < 3; k++) {
        double lo = INFINITY, hi = -INFINITY;
        for (size_t v = 0; v < mesh->n_vertices; v++) {
            lo = fmin(lo, mesh->vertices[3 * v + (size_t)k]);
            hi = fmax(hi, mesh->vertices[3 * v + (size_t)k]);
        }
        if (hi > lo) extent = fmax(extent, hi - lo);
    }
    if (extent > PLAUSIBLE_MESH_EXTENT_MAX_M)
        nc_warn(sink, "%s.file: %s spans %g m, above the plausible %g m for a slope; STL files "
                "carry no unit and are read in metres (a model exported in millimetres spans "
                "1000 times its size)", where, mesh->path, extent, PLAUSIBLE_MESH_EXTENT_MAX_M);
}

static int parse_meshes(dem_sim *s, const cJSON *root, const char *file, const char *base_dir,
                        FILE *sink, nc_error *err)
{
    static const char *const keys[] = {"file", "velocity", "material", NULL};
    static const double zero[3] = {0, 0, 0};
    const cJSON *arr;
    int count;
    if (nc_json_array_opt(root, file, "meshes", &arr, &count, err)) return -1;
    if (count == 0) return 0;
    s->model.meshes = calloc((size_t)count, sizeof *s->model.meshes);
    if (!s->model.meshes) return nc_error_set(err, 1, "dem: out of memory");
    int k = 0;
    for (const cJSON *m = count ? arr->child : NULL; m; m = m->next, k++) {
        char where[600];
        nc_json_path_index(where, sizeof where, file, "meshes", k);
        if (!cJSON_IsObject(m)) return nc_error_set(err, 1, "%s: expected an object", where);
        if (nc_json_check_keys(m, where, keys, err)) return -1;
        dem_mesh *mesh = &s->model.meshes[k];
        s->model.n_meshes = (size_t)k + 1;
        const char *path;
        int mat;
        if (nc_json_string(m, where, "file", &path, err) ||
            nc_json_vec3_opt(m, where, "velocity", zero, mesh->velocity, err) ||
            find_material(s, m, where, &mat, err))
            return -1;
        mesh->material = mat;
        char full[1024];
        nc_file_join(base_dir, path, full, sizeof full);
        if (dem_stl_load(mesh, full, err)) return nc_error_prefix(err, "%s.file", where);
        warn_mesh_extent(sink, where, mesh);
    }
    return 0;
}

static int parse_net_wall(dem_sim *s, const cJSON *root, const char *file, FILE *sink,
                          nc_error *err)
{
    static const char *const keys[] = {"youngs_modulus_pa", "poisson_ratio", "friction",
                                       "restitution", "cable_radius_m", "near_distance_m",
                                       "coupling_force", "wall_position", NULL};
    static const char *const force_kinds[] = {"average", "end_of_step", NULL};
    static const char *const wall_positions[] = {"end", "middle", NULL};
    const cJSON *w;
    if (nc_json_object_opt(root, file, "net_wall", &w, err)) return -1;
    if (!w) return 0;
    char where[600];
    nc_json_path(where, sizeof where, file, "net_wall");
    dem_net *n = &s->model.net;
    if (nc_json_check_keys(w, where, keys, err) ||
        nc_json_positive(w, where, "youngs_modulus_pa", &n->youngs_modulus_pa, err) ||
        nc_json_number_range(w, where, "poisson_ratio", -0.999, 0.5, &n->poisson_ratio, err) ||
        nc_json_number_range(w, where, "friction", 0.0, INFINITY, &n->friction, err) ||
        nc_json_number_range_opt(w, where, "restitution", -1.0, 0.0, 1.0, &n->restitution, err) ||
        nc_json_number_range_opt(w, where, "cable_radius_m", 0.0, 0.0, INFINITY, &n->cable_radius_m, err) ||
        nc_json_number_range_opt(w, where, "near_distance_m", -1.0, 0.0, INFINITY, &n->near_distance_m, err) ||
        nc_json_choice_opt(w, where, "coupling_force", force_kinds, 0, &n->force_at_end, err) ||
        nc_json_choice_opt(w, where, "wall_position", wall_positions, 0, &n->wall_at_middle, err))
        return -1;
    warn_modulus(sink, where, n->youngs_modulus_pa);
    return 0;
}

static int parse_root(dem_sim *s, const cJSON *root, const char *file, const char *base_dir,
                      FILE *sink, nc_error *err)
{
    static const char *const keys[] = {"description", "materials", "particles", "generators",
                                       "clusters", "planes", "meshes", "gravity", "dt_s",
                                       "dt_safety", "end_time_s", "output_interval_s",
                                       "contact_law", "damping", "linear", "net_wall", "threads",
                                       "neighbor_skin_m", "free_flight", NULL};
    const char *laws[8];
    size_t n_laws = 0;
    for (; dem_contact_laws[n_laws] && n_laws + 1 < sizeof laws / sizeof *laws; n_laws++)
        laws[n_laws] = dem_contact_laws[n_laws]->name;
    laws[n_laws] = NULL;
    static const char *const dampings[] = {"fit", "a7", "hunt_crossley", NULL};
    static const double g0[3] = {0, 0, -9.81};
    snprintf(s->model.source, sizeof s->model.source, "%s", file);
    if (nc_json_check_keys(root, file, keys, err)) return -1;
    dem_params *p = &s->model.prm;
    int law;
    if (nc_json_vec3_opt(root, file, "gravity", g0, p->gravity, err) ||
        nc_json_choice_opt(root, file, "contact_law", laws, 0, &law, err))
        return -1;
    p->law = (dem_law)law;
    const dem_contact_law *law_ops = dem_contact_law_of(p->law);
    int damping;
    if (nc_json_choice_opt(root, file, "damping", dampings, (int)law_ops->default_damping, &damping, err))
        return -1;
    p->damping = (dem_damping_formula)damping;
    if (p->damping == DEM_DAMPING_HUNT_CROSSLEY && p->law != DEM_LAW_HERTZ_MINDLIN)
        return nc_error_set(err, 1, "%s.damping: \"hunt_crossley\" is a dashpot of the Hertz law "
                                    "(contact_law \"hertz_mindlin\"), not of \"%s\"", file,
                            law_ops->name);
    const cJSON *dt = cJSON_GetObjectItemCaseSensitive(root, "dt_s");
    if (!dt || (cJSON_IsString(dt) && strcmp(dt->valuestring, "auto") == 0)) {
        p->dt_auto = 1;
    } else if (cJSON_IsNumber(dt) && dt->valuedouble > 0.0 && isfinite(dt->valuedouble)) {
        p->dt_auto = 0;
        p->dt_s = dt->valuedouble;
    } else {
        return nc_json_wrong(err, file, "dt_s", "a number > 0 or \"auto\"", dt);
    }
    long threads;
    if (nc_json_number_range_opt(root, file, "dt_safety", 0.1, 1e-6, 1.0, &p->dt_safety, err) ||
        nc_json_number_range_opt(root, file, "end_time_s", 1.0, 0.0, INFINITY, &p->end_time_s, err) ||
        nc_json_number_range_opt(root, file, "output_interval_s", p->end_time_s / 100.0, 0.0,
                                 INFINITY, &p->output_interval_s, err) ||
        nc_json_int_opt(root, file, "threads", 0, 0, DEM_MAX_BUFFERS, &threads, err) ||
        nc_json_number_range_opt(root, file, "neighbor_skin_m", 0.0, 0.0, INFINITY, &s->nlist.skin_m, err) ||
        nc_json_bool_opt(root, file, "free_flight", 0, &p->free_flight, err))
        return -1;
    p->threads = (int)threads;
    if (!p->dt_auto) {
        /* a standalone run of end_time_s / dt_s steps: refuse what cannot run or never ends */
        char what[600];
        long steps;
        nc_json_path(what, sizeof what, file, "dt_s");
        if (nc_time_check_step(p->dt_s, p->end_time_s, what, err) ||
            nc_time_step_count(p->end_time_s, p->dt_s, NC_TIME_MAX_STEPS, what, &steps, err))
            return -1;
    }
    const cJSON *lin;
    if (nc_json_object_opt(root, file, "linear", &lin, err)) return -1;
    if (lin) {
        static const char *const lkeys[] = {"normal_stiffness_n_per_m",
                                            "tangential_stiffness_ratio", NULL};
        char where[600];
        nc_json_path(where, sizeof where, file, "linear");
        if (nc_json_check_keys(lin, where, lkeys, err) ||
            nc_json_positive(lin, where, "normal_stiffness_n_per_m", &p->linear_kn_n_per_m, err) ||
            nc_json_number_range_opt(lin, where, "tangential_stiffness_ratio", 2.0 / 7.0, 0.0,
                                     INFINITY, &p->linear_kt_ratio, err))
            return -1;
    } else if (law_ops->section) {
        return nc_error_set(err, 1, "%s.%s: missing (the %s contact law needs %s)", file,
                            law_ops->section, law_ops->name, law_ops->section_example);
    }
    if (parse_materials(s, root, file, sink, err) || parse_particles(s, root, file, sink, err) ||
        parse_generators(s, root, file, sink, err) || parse_clusters(s, root, file, sink, err) ||
        parse_planes(s, root, file, err) || parse_meshes(s, root, file, base_dir, sink, err) ||
        parse_net_wall(s, root, file, sink, err))
        return -1;
    return 0;
}

/* Builds the item grids of the meshes (triangles, mesh frame). */
static int build_mesh_grids(dem_sim *s, nc_error *err)
{
    double rmax = 0.0;
    for (size_t i = 0; i < s->model.sph.n; i++) rmax = fmax(rmax, s->model.sph.radius[i]);
    for (size_t m = 0; m < s->model.n_meshes; m++) {
        dem_mesh *mesh = &s->model.meshes[m];
        size_t nt = mesh->n_triangles;
        double *lo = malloc(3 * nt * sizeof *lo), *hi = malloc(3 * nt * sizeof *hi);
        mesh->grid = calloc(1, sizeof *mesh->grid);
        if (!lo || !hi || !mesh->grid) {
            free(lo); free(hi);
            return nc_error_set(err, 1, "dem: out of memory for mesh %s", mesh->path);
        }
        for (size_t t = 0; t < nt; t++)
            for (int k = 0; k < 3; k++) {
                double a = mesh->vertices[3 * (size_t)mesh->tri[3 * t] + k];
                double b = mesh->vertices[3 * (size_t)mesh->tri[3 * t + 1] + k];
                double c = mesh->vertices[3 * (size_t)mesh->tri[3 * t + 2] + k];
                lo[3 * t + k] = fmin(a, fmin(b, c));
                hi[3 * t + k] = fmax(a, fmax(b, c));
            }
        int rc = dem_item_grid_build(mesh->grid, nt, lo, hi, rmax > 0 ? rmax : 1.0, err);
        free(lo);
        free(hi);
        if (rc) return -1;
    }
    return 0;
}

int dem_config_parse_string_opt(dem_sim *s, const char *json, const char *where,
                                const char *base_dir, const dem_config_options *opt,
                                nc_error *err)
{
    cJSON *root;
    if (nc_json_parse_text(where, json, strlen(json), &root, err)) return -1;
    int rc = parse_root(s, root, where, base_dir, opt ? opt->warnings : NULL, err);
    cJSON_Delete(root);
    if (rc == 0) rc = build_mesh_grids(s, err);
    return rc;
}

int dem_config_parse_string(dem_sim *s, const char *json, const char *where,
                            const char *base_dir, nc_error *err)
{
    return dem_config_parse_string_opt(s, json, where, base_dir, NULL, err);
}

int dem_config_load_opt(dem_sim *s, const char *path, const dem_config_options *opt,
                        nc_error *err)
{
    cJSON *root;
    if (nc_json_load_file(path, &root, err)) return -1;
    char dir[1024];
    nc_file_dir(path, dir, sizeof dir);
    int rc = parse_root(s, root, path, dir, opt ? opt->warnings : NULL, err);
    cJSON_Delete(root);
    if (rc == 0) rc = build_mesh_grids(s, err);
    return rc;
}

int dem_config_load(dem_sim *s, const char *path, nc_error *err)
{
    return dem_config_load_opt(s, path, NULL, err);
}
