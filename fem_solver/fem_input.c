/* fem_input — fem.json -> fem_model: mesh (explicit lists, regular-net generator or Gmsh
 * file), element sets, supports, loads, damping, interface, monitors, analysis settings. */
#include "nc_plausible.h"
#include "fem_input.h"
#include "fem_mesh_gmsh.h"
#include "nc_file.h"
#include "nc_json.h"
#include "nc_time.h"

#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define WHERE_MAX 600

/* Wide engineering ranges: a value outside is a warning (likely a unit mistake), not an
 * error. The messages state the same numbers. */
#define PLAUSIBLE_AREA_MIN_M2 1e-7
#define PLAUSIBLE_AREA_MAX_M2 1e-2
#define PLAUSIBLE_PRESTRESS_MAX_PA 2e9   /* above the yield strength of any rope steel */
#define PLAUSIBLE_STRENGTH_MIN_PA 1e7    /* breaking load / area */
#define PLAUSIBLE_STRENGTH_MAX_PA 3e9
/* Metallic area factor f = A / (π d² / 4) of a six-strand rope with a steel core
 * (6x19, 6x36 IWRC: 0.57–0.59 by the factors C = f π/4 of EN 12385-4); fibre-core ropes are
 * near 0.49, spiral strands 0.75–0.8. */
#define DEFAULT_METALLIC_AREA_FACTOR 0.58


/* Resolves a node reference: an index, a node-set name, or an array of those.
 * *out is malloc'ed (caller frees). */
static int parse_node_ref(const fem_model *m, const cJSON *item, const char *where, int **out,
                          int *count, nc_error *err)
{
    *out = NULL;
    *count = 0;
    if (!item) return nc_error_set(err, 1, "%s: missing (expected a node index, a node set name or an array of them)", where);
    /* the items: the children of an array, or the one value itself */
    const cJSON *first = cJSON_IsArray(item) ? item->child : item;
    const cJSON *stop = cJSON_IsArray(item) ? NULL : item->next;
    long cap = 0;
    for (const cJSON *it = first; it != stop; it = it->next) {
        if (cJSON_IsString(it)) {
            const fem_node_set *ns = fem_model_find_node_set(m, it->valuestring);
            if (!ns) {
                char names[300] = "";
                for (int k = 0; k < m->n_node_sets && strlen(names) < 200; k++) {
                    size_t len = strlen(names);
                    snprintf(names + len, sizeof names - len, "%s%s", k ? ", " : "",
                             m->node_sets[k].name);
                }
                free(*out);
                *out = NULL;
                return nc_error_set(err, 1, "%s: unknown node set \"%s\" (known: %s)", where,
                                    it->valuestring, names[0] ? names : "none");
            }
            cap += ns->count;
            if (cap > 100000000L)
                return nc_error_set(err, 1, "%s: more than 1e8 node references", where);
        } else if (cJSON_IsNumber(it)) {
            cap += 1;
        } else {
            return nc_error_set(err, 1, "%s: expected a node index, a node set name or an array of them", where);
        }
    }
    *out = malloc((size_t)(cap > 0 ? cap : 1) * sizeof **out);
    if (!*out) return nc_error_set(err, 1, "%s: out of memory", where);
    for (const cJSON *it = first; it != stop; it = it->next) {
        if (cJSON_IsString(it)) {
            const fem_node_set *ns = fem_model_find_node_set(m, it->valuestring);
            memcpy(*out + *count, ns->nodes, (size_t)ns->count * sizeof(int));
            *count += ns->count;
        } else {
            double v = it->valuedouble;
            if (v != floor(v) || v < 0 || v >= m->n_nodes) {
                free(*out);
                *out = NULL;
                return nc_error_set(err, 1, "%s: node index %g out of range (expected an integer 0..%d)",
                                    where, v, m->n_nodes - 1);
            }
            (*out)[(*count)++] = (int)v;
        }
    }
    return 0;
}

/* The section of a set: area_m2, or diameter_m with metallic_area_factor (A = f π d² / 4). */
static int parse_area(const cJSON *o, const char *w, FILE *sink, double *area, nc_error *err)
{
    int has_a = cJSON_GetObjectItemCaseSensitive(o, "area_m2") != NULL;
    int has_d = cJSON_GetObjectItemCaseSensitive(o, "diameter_m") != NULL;
    if (has_a && has_d)
        return nc_error_set(err, 1, "%s: give either area_m2 or diameter_m, not both", w);
    if (!has_d && cJSON_GetObjectItemCaseSensitive(o, "metallic_area_factor"))
        return nc_error_set(err, 1, "%s.metallic_area_factor: only used with diameter_m", w);
    if (!has_d) {
        if (nc_json_positive(o, w, "area_m2", area, err)) return -1;
        if (*area < PLAUSIBLE_AREA_MIN_M2 || *area > PLAUSIBLE_AREA_MAX_M2)
            nc_warn(sink, "%s.area_m2: %g m² is outside the plausible range 1e-7..1e-2 m² for a "
                       "cable (a 20 mm rope: 1.8e-4 m²)", w, *area);
        return 0;
    }
    double d, f;
    if (nc_json_positive(o, w, "diameter_m", &d, err) ||
        nc_json_number_range_opt(o, w, "metallic_area_factor", DEFAULT_METALLIC_AREA_FACTOR,
                                 1e-3, 1.0, &f, err))
        return -1;
    *area = f * M_PI * d * d / 4.0;
    if (*area < PLAUSIBLE_AREA_MIN_M2 || *area > PLAUSIBLE_AREA_MAX_M2)
        nc_warn(sink, "%s.diameter_m: %g m gives an area of %g m², outside the plausible range "
                   "1e-7..1e-2 m² for a cable (diameter in m: 20 mm is 0.02)", w, d, *area);
    if (f < 0.4 || f > 0.85)
        nc_warn(sink, "%s.metallic_area_factor: %g is outside 0.4..0.85 (wire ropes: fibre core "
                   "about 0.49, steel core 0.58, spiral strand 0.75..0.8)", w, f);
    return 0;
}

static int parse_sets(fem_model *m, const cJSON *root, const char *file, FILE *sink,
                      nc_error *err)
{
    const cJSON *arr;
    int n;
    if (nc_json_array(root, file, "element_sets", &arr, &n, err)) return -1;
    if (n < 1) return nc_error_set(err, 1, "%s: element_sets: expected at least one set", file);
    static const char *const base_keys[] = {"name", "youngs_modulus_pa", "area_m2", "diameter_m",
                                            "metallic_area_factor", "density_kg_m3", "prestress_pa",
                                            "pretension_n", "breaking_load_n", "behaviour", "type",
                                            NULL};
    static const char *const behaviours[] = {"cable", "truss", NULL};
    int i = 0;
    for (const cJSON *o = arr->child; o; o = o->next, i++) {
        char w[WHERE_MAX];
        snprintf(w, sizeof w, "%s: element_sets[%d]", file, i);
        if (!cJSON_IsObject(o)) return nc_error_set(err, 1, "%s: expected an object {...}", w);
        /* the type first: it brings keys of its own */
        const char *type_name;
        if (nc_json_string_opt(o, w, "type", "cable", &type_name, err)) return -1;
        fem_set_type st;
        memset(&st, 0, sizeof st);
        st.type = fem_element_find(type_name);
        if (st.type < 0) {
            char names[256];
            return nc_error_set(err, 1, "%s.type: unknown element type \"%s\" (expected one of %s)", w,
                                type_name, fem_element_names(names, sizeof names, ", "));
        }
        const fem_element_ops *ops = fem_element_type(st.type);
        const char *keys[64];
        int nk = 0;
        for (int k = 0; base_keys[k]; k++) keys[nk++] = base_keys[k];
        for (int k = 0; ops->keys && ops->keys[k] && nk < 63; k++) keys[nk++] = ops->keys[k];
        keys[nk] = NULL;
        if (nc_json_check_keys(o, w, keys, err)) return -1;
        if (ops->parse && ops->parse(o, w, sink, st.param, err)) return -1;
        fem_element_set set;
        memset(&set, 0, sizeof set);
        const char *name;
        int b;
        char defname[32];
        snprintf(defname, sizeof defname, "set%d", i);
        int has_n = cJSON_GetObjectItemCaseSensitive(o, "pretension_n") != NULL;
        if (has_n && cJSON_GetObjectItemCaseSensitive(o, "prestress_pa"))
            return nc_error_set(err, 1, "%s: give either prestress_pa or pretension_n, not both", w);
        double pretension = 0.0;
        if (nc_json_string_opt(o, w, "name", defname, &name, err) ||
            (ops->uses_section ? nc_json_positive(o, w, "youngs_modulus_pa", &set.youngs_modulus_pa, err)
                               : nc_json_number_range_opt(o, w, "youngs_modulus_pa", 0.0, 0.0, INFINITY,
                                                          &set.youngs_modulus_pa, err)) ||
            ((ops->uses_section || cJSON_GetObjectItemCaseSensitive(o, "area_m2") ||
              cJSON_GetObjectItemCaseSensitive(o, "diameter_m")) &&
             parse_area(o, w, sink, &set.area_m2, err)) ||
            nc_json_number_range_opt(o, w, "density_kg_m3", 0.0, 0.0, INFINITY, &set.density_kg_m3, err) ||
            nc_json_number_opt(o, w, "prestress_pa", 0.0, &set.prestress_pa, err) ||
            nc_json_number_opt(o, w, "pretension_n", 0.0, &pretension, err) ||
            nc_json_number_range_opt(o, w, "breaking_load_n", 0.0, 0.0, INFINITY, &set.breaking_load_n, err) ||
            nc_json_choice_opt(o, w, "behaviour", behaviours, 0, &b, err))
            return -1;
        if (cJSON_GetObjectItemCaseSensitive(o, "breaking_load_n") && !(set.breaking_load_n > 0.0))
            return nc_error_set(err, 1, "%s.breaking_load_n: expected a number > 0, got 0", w);
        /* the force N of the prestress in the reference configuration: S_pre = N / A */
        if (has_n && !(set.area_m2 > 0.0))
            return nc_error_set(err, 1, "%s.pretension_n: needs area_m2 or diameter_m", w);
        if (has_n) set.prestress_pa = pretension / set.area_m2;
        if (strlen(name) >= FEM_NAME_MAX)
            return nc_error_set(err, 1, "%s.name: longer than %d characters", w, FEM_NAME_MAX - 1);
        if (fem_model_find_set(m, name) >= 0)
            return nc_error_set(err, 1, "%s.name: \"%s\" is used by an earlier set", w, name);
        double e = set.youngs_modulus_pa, rho = set.density_kg_m3, a = set.area_m2;
        if (ops->uses_section && (e < NC_PLAUSIBLE_MODULUS_MIN_PA || e > NC_PLAUSIBLE_MODULUS_MAX_PA))
            nc_warn(sink, "%s.youngs_modulus_pa: %g Pa is outside the plausible range 1e5..1e12 Pa "
                       "(steel rope about 1e11..2.1e11)", w, e);
        if (rho > 0.0 && (rho < NC_PLAUSIBLE_DENSITY_MIN || rho > NC_PLAUSIBLE_DENSITY_MAX))
            nc_warn(sink, "%s.density_kg_m3: %g kg/m³ is outside the plausible range 100..25000 "
                       "kg/m³ (steel 7850)", w, rho);
        if (fabs(set.prestress_pa) > PLAUSIBLE_PRESTRESS_MAX_PA)
            nc_warn(sink, "%s.%s: a prestress of %g Pa is above 2e9 Pa, more than rope steel "
                       "yields at", w, has_n ? "pretension_n" : "prestress_pa", set.prestress_pa);
        if (set.breaking_load_n > 0.0 && a > 0.0) {
            double strength = set.breaking_load_n / a, force = set.prestress_pa * a;
            if (strength < PLAUSIBLE_STRENGTH_MIN_PA || strength > PLAUSIBLE_STRENGTH_MAX_PA)
                nc_warn(sink, "%s.breaking_load_n: %g N over the area %g m² is a strength of %g Pa, "
                           "outside the plausible 1e7..3e9 Pa (rope grade 1770: about 1.4e9 "
                           "of the metallic area; kN given as N?)", w, set.breaking_load_n, a,
                     strength);
            if (force > set.breaking_load_n)
                nc_warn(sink, "%s.%s: the pretension %g N exceeds breaking_load_n %g N", w,
                     has_n ? "pretension_n" : "prestress_pa", force, set.breaking_load_n);
        }
        snprintf(set.name, sizeof set.name, "%s", name);
        set.behaviour = b == 0 ? FEM_CABLE : FEM_TRUSS;
        int index = fem_model_add_set(m, &set, err);
        if (index < 0) return -1;
        m->set_types[index] = st;
    }
    return 0;
}

static int set_by_name(const fem_model *m, const cJSON *o, const char *w, const char *key,
                       int *set, nc_error *err)
{
    const char *name;
    *set = 0;
    if (nc_json_string_opt(o, w, key, NULL, &name, err)) return -1;
    if (!name) return 0;
    *set = fem_model_find_set(m, name);
    if (*set < 0) return nc_error_set(err, 1, "%s.%s: no element set named \"%s\"", w, key, name);
    return 0;
}

static int parse_explicit_mesh(fem_model *m, const cJSON *root, const char *file, nc_error *err)
{
    const cJSON *nodes, *elems;
    int nn, ne;
    if (nc_json_array(root, file, "nodes", &nodes, &nn, err) ||
        nc_json_array(root, file, "elements", &elems, &ne, err))
        return -1;
    if (nn < 2) return nc_error_set(err, 1, "%s: nodes: expected at least 2 nodes, got %d", file, nn);
    if (ne < 1) return nc_error_set(err, 1, "%s: elements: expected at least 1 element", file);
    if (fem_model_alloc(m, nn, ne, err)) return -1;
    int i = 0;
    for (const cJSON *p = nodes->child; p; p = p->next, i++) {
        int ok = cJSON_IsArray(p) && cJSON_GetArraySize(p) == 3;
        const cJSON *v = ok ? p->child : NULL;
        for (int c = 0; ok && c < 3; c++, v = v->next) {
            ok = cJSON_IsNumber(v) && isfinite(v->valuedouble);
            if (ok) m->X[3 * i + c] = v->valuedouble;
        }
        if (!ok) return nc_error_set(err, 1, "%s: nodes[%d]: expected [x, y, z] of finite numbers (m)", file, i);
    }
    static const char *const ekeys[] = {"nodes", "set", NULL};
    int e = 0;
    for (const cJSON *p = elems->child; p; p = p->next, e++) {
        char w[WHERE_MAX];
        snprintf(w, sizeof w, "%s: elements[%d]", file, e);
        const cJSON *pair = p;
        int set = 0;
        if (cJSON_IsObject(p)) {
            if (nc_json_check_keys(p, w, ekeys, err) || set_by_name(m, p, w, "set", &set, err)) return -1;
            pair = cJSON_GetObjectItemCaseSensitive(p, "nodes");
        }
        int ok = cJSON_IsArray(pair) && cJSON_GetArraySize(pair) == 2;
        const cJSON *v = ok ? pair->child : NULL;
        for (int c = 0; ok && c < 2; c++, v = v->next) {
            ok = cJSON_IsNumber(v) && v->valuedouble == floor(v->valuedouble);
            if (ok && (v->valuedouble < 0 || v->valuedouble >= nn))
                return nc_error_set(err, 1, "%s: node index %g out of range 0..%d", w, v->valuedouble, nn - 1);
            if (ok) m->conn[2 * e + c] = (int)v->valuedouble;
        }
        if (!ok) return nc_error_set(err, 1, "%s: expected [k, l] (two node indices) or {\"nodes\": [k, l], \"set\": name}", w);
        if (m->conn[2 * e] == m->conn[2 * e + 1])
            return nc_error_set(err, 1, "%s: both ends are node %d", w, m->conn[2 * e]);
        m->element_set[e] = set;
    }
    return 0;
}

static int parse_net(fem_model *m, const cJSON *net, const char *file, nc_error *err)
{
    char w[WHERE_MAX];
    snprintf(w, sizeof w, "%s: net", file);
    static const char *const keys[] = {"origin_m", "edge1_m", "edge2_m", "count1", "count2", "set", NULL};
    double o[3], e1[3], e2[3];
    long c1, c2;
    int set;
    if (nc_json_check_keys(net, w, keys, err) || nc_json_vec3(net, w, "origin_m", o, err) ||
        nc_json_vec3(net, w, "edge1_m", e1, err) || nc_json_vec3(net, w, "edge2_m", e2, err) ||
        nc_json_int(net, w, "count1", 2, 100000, &c1, err) ||
        nc_json_int(net, w, "count2", 1, 100000, &c2, err) ||
        set_by_name(m, net, w, "set", &set, err))
        return -1;
    if (c1 * c2 > 20000000L) return nc_error_set(err, 1, "%s: count1 x count2 = %ld nodes is too many", w, c1 * c2);
    double n1 = sqrt(e1[0] * e1[0] + e1[1] * e1[1] + e1[2] * e1[2]);
    double n2 = sqrt(e2[0] * e2[0] + e2[1] * e2[1] + e2[2] * e2[2]);
    double cr[3] = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2], e1[0] * e2[1] - e1[1] * e2[0]};
    if (!(n1 > 0)) return nc_error_set(err, 1, "%s.edge1_m: expected a non-zero vector", w);
    if (c2 > 1 && !(sqrt(cr[0] * cr[0] + cr[1] * cr[1] + cr[2] * cr[2]) > 1e-12 * n1 * n2))
        return nc_error_set(err, 1, "%s.edge2_m: expected a vector not parallel to edge1_m", w);
    if (fem_model_generate_net(m, o, e1, e2, (int)c1, (int)c2, set, err)) return nc_error_prefix(err, "%s", w);
    return 0;
}

static int parse_gmsh(fem_model *m, const cJSON *mesh, const char *file, nc_error *err)
{
    char w[WHERE_MAX];
    snprintf(w, sizeof w, "%s: mesh", file);
    static const char *const keys[] = {"file", "set", NULL};
    const char *name;
    int set;
    if (nc_json_check_keys(mesh, w, keys, err) || nc_json_string(mesh, w, "file", &name, err) ||
        set_by_name(m, mesh, w, "set", &set, err))
        return -1;
    char path[1024], dir[512];
    nc_file_dir(file, dir, sizeof dir);
    nc_file_join(dir, name, path, sizeof path);
    fem_gmsh_mesh g;
    if (fem_gmsh_read(path, &g, err)) return nc_error_prefix(err, "%s.file", w);
    int rc = 0;
    if (g.n_lines < 1) {
        rc = nc_error_set(err, 1, "%s: %s has no 2-node line elements (type 1)", w, path);
        goto done;
    }
    if ((rc = fem_model_alloc(m, g.n_nodes, g.n_lines, err))) goto done;
    memcpy(m->X, g.X, 3 * (size_t)g.n_nodes * sizeof(double));
    memcpy(m->conn, g.lines, 2 * (size_t)g.n_lines * sizeof(int));
    for (int e = 0; e < g.n_lines; e++) {
        int s = set;
        for (int k = 0; k < g.n_groups; k++)
            if (g.groups[k].dim == 1 && g.groups[k].tag == g.line_physical[e]) {
                int named = fem_model_find_set(m, g.groups[k].name);
                if (named >= 0) s = named;
            }
        m->element_set[e] = s;
    }
    /* node sets from physical groups: points (dim 0) and all nodes of lines (dim 1) */
    int *buf = malloc((size_t)(2 * g.n_lines + g.n_points + 1) * sizeof *buf);
    unsigned char *seen = calloc((size_t)g.n_nodes, 1);
    if (!buf || !seen) rc = nc_error_set(err, 1, "%s: out of memory", w);
    for (int k = 0; !rc && k < g.n_groups; k++) {
        int c = 0;
        memset(seen, 0, (size_t)g.n_nodes);
        if (g.groups[k].dim == 0) {
            for (int p = 0; p < g.n_points; p++)
                if (g.point_physical[p] == g.groups[k].tag && !seen[g.points[p]]) {
                    seen[g.points[p]] = 1;
                    buf[c++] = g.points[p];
                }
        } else if (g.groups[k].dim == 1) {
            for (int e = 0; e < g.n_lines; e++)
                if (g.line_physical[e] == g.groups[k].tag)
                    for (int j = 0; j < 2; j++)
                        if (!seen[g.lines[2 * e + j]]) {
                            seen[g.lines[2 * e + j]] = 1;
                            buf[c++] = g.lines[2 * e + j];
                        }
        } else {
            continue;
        }
        if (!fem_model_find_node_set(m, g.groups[k].name))
            rc = fem_model_add_node_set(m, g.groups[k].name, buf, c, err);
    }
    free(buf);
    free(seen);
done:
    fem_gmsh_free(&g);
    return rc;
}

static int parse_node_sets(fem_model *m, const cJSON *root, const char *file, nc_error *err)
{
    const cJSON *o;
    if (nc_json_object_opt(root, file, "node_sets", &o, err)) return -1;
    if (!o) return 0;
    for (const cJSON *it = o->child; it; it = it->next) {
        char w[WHERE_MAX];
        snprintf(w, sizeof w, "%s: node_sets.%s", file, it->string);
        if (strlen(it->string) >= FEM_NAME_MAX) return nc_error_set(err, 1, "%s: name too long", w);
        int *nodes, count;
        if (parse_node_ref(m, it, w, &nodes, &count, err)) return -1;
        int rc = fem_model_add_node_set(m, it->string, nodes, count, err);
        free(nodes);
        if (rc) return -1;
    }
    return 0;
}

static int parse_supports(fem_model *m, const cJSON *root, const char *file, nc_error *err)
{
    const cJSON *arr;
    int n;
    if (nc_json_array_opt(root, file, "supports", &arr, &n, err)) return -1;
    static const char *const keys[] = {"nodes", "dofs", "displacement_m", NULL};
    int i = 0;
    for (const cJSON *o = n ? arr->child : NULL; o; o = o->next, i++) {
        char w[WHERE_MAX], wn[WHERE_MAX + 8];
        snprintf(w, sizeof w, "%s: supports[%d]", file, i);
        if (!cJSON_IsObject(o)) return nc_error_set(err, 1, "%s: expected an object {...}", w);
        const char *dofs;
        double disp[3];
        static const double zero[3] = {0, 0, 0};
        if (nc_json_check_keys(o, w, keys, err) || nc_json_string_opt(o, w, "dofs", "xyz", &dofs, err) ||
            nc_json_vec3_opt(o, w, "displacement_m", zero, disp, err))
            return -1;
        int mask[3] = {0, 0, 0};
        for (const char *c = dofs; *c; c++) {
            if (*c < 'x' || *c > 'z') return nc_error_set(err, 1, "%s.dofs: expected letters from \"xyz\", got \"%s\"", w, dofs);
            mask[*c - 'x'] = 1;
        }
        if (!dofs[0]) return nc_error_set(err, 1, "%s.dofs: expected letters from \"xyz\", got \"\"", w);
        int *nodes, count;
        nc_json_path(wn, sizeof wn, w, "nodes");
        if (parse_node_ref(m, cJSON_GetObjectItemCaseSensitive(o, "nodes"), wn, &nodes, &count, err)) return -1;
        for (int k = 0; k < count; k++)
            for (int c = 0; c < 3; c++)
                if (mask[c]) {
                    m->fixed[3 * nodes[k] + c] = 1;
                    m->u_prescribed[3 * nodes[k] + c] = disp[c];
                }
        free(nodes);
    }
    return 0;
}

static int parse_loads(fem_model *m, const cJSON *root, const char *file, nc_error *err)
{
    const cJSON *arr;
    int n;
    if (nc_json_array_opt(root, file, "point_loads", &arr, &n, err)) return -1;
    static const char *const keys[] = {"nodes", "force_n", NULL};
    int i = 0;
    for (const cJSON *o = n ? arr->child : NULL; o; o = o->next, i++) {
        char w[WHERE_MAX], wn[WHERE_MAX + 8];
        snprintf(w, sizeof w, "%s: point_loads[%d]", file, i);
        if (!cJSON_IsObject(o)) return nc_error_set(err, 1, "%s: expected an object {...}", w);
        double f[3];
        if (nc_json_check_keys(o, w, keys, err) || nc_json_vec3(o, w, "force_n", f, err)) return -1;
        int *nodes, count;
        nc_json_path(wn, sizeof wn, w, "nodes");
        if (parse_node_ref(m, cJSON_GetObjectItemCaseSensitive(o, "nodes"), wn, &nodes, &count, err)) return -1;
        for (int k = 0; k < count; k++)
            for (int c = 0; c < 3; c++) m->f_point[3 * nodes[k] + c] += f[c];
        free(nodes);
    }
    return 0;
}

static int parse_analysis(fem_model *m, const cJSON *root, const char *file, nc_error *err)
{
    const cJSON *o;
    fem_settings *s = &m->settings;
    if (nc_json_object_opt(root, file, "analysis", &o, err)) return -1;
    if (!o) return 0;
    char w[WHERE_MAX];
    snprintf(w, sizeof w, "%s: analysis", file);
    static const char *const keys[] = {"type", "load_steps", "integrator", "beta", "gamma",
                                       "rho_inf", "alpha_b", "dt_s", "end_time_s", "load_ramp_s",
                                       "max_iterations", "residual_tolerance_n",
                                       "relative_tolerance", "displacement_tolerance_m",
                                       "factorization", "newton", "contraction", "coupling_load",
                                       "fail_on_overload", "initial_state", NULL};
    static const char *const types[] = {"static", "dynamic", NULL};
    static const char *const integrators[] = {"newmark", "generalized_alpha", "bossak", NULL};
    static const char *const factorizations[] = {"auto", "ldlt", "llt", NULL};
    static const char *const newtons[] = {"modified", "full", NULL};
    static const char *const coupling_loads[] = {"end_of_step", "step_constant", NULL};
    static const char *const initial_states[] = {"reference", "static", NULL};
    int type, integ, fact, newton, coupling_load, initial_state;
    long steps, iters;
    if (nc_json_check_keys(o, w, keys, err) ||
        nc_json_choice_opt(o, w, "type", types, 1, &type, err) ||
        nc_json_int_opt(o, w, "load_steps", 1, 1, 1000000, &steps, err) ||
        nc_json_choice_opt(o, w, "integrator", integrators, 0, &integ, err) ||
        nc_json_choice_opt(o, w, "factorization", factorizations, 0, &fact, err) ||
        nc_json_choice_opt(o, w, "newton", newtons, 0, &newton, err) ||
        nc_json_choice_opt(o, w, "coupling_load", coupling_loads, 0, &coupling_load, err) ||
        nc_json_choice_opt(o, w, "initial_state", initial_states, 0, &initial_state, err) ||
        nc_json_bool_opt(o, w, "fail_on_overload", 0, &s->fail_on_overload, err) ||
        nc_json_number_range_opt(o, w, "contraction", 0.2, 0.0, 0.9, &s->contraction, err) ||
        nc_json_number_range_opt(o, w, "beta", 0.25, 1e-6, 0.5, &s->beta, err) ||
        nc_json_number_range_opt(o, w, "gamma", 0.5, 0.5, 1.0, &s->gamma, err) ||
        nc_json_number_range_opt(o, w, "rho_inf", 0.8, 0.0, 1.0, &s->rho_inf, err) ||
        nc_json_number_range_opt(o, w, "alpha_b", -0.1, -1.0 / 3.0, 0.0, &s->alpha_b, err) ||
        nc_json_number_range_opt(o, w, "dt_s", 1e-3, 1e-15, INFINITY, &s->dt_s, err) ||
        nc_json_number_range_opt(o, w, "end_time_s", 1.0, 0.0, INFINITY, &s->end_time_s, err) ||
        nc_json_number_range_opt(o, w, "load_ramp_s", 0.0, 0.0, INFINITY, &s->load_ramp_s, err) ||
        nc_json_int_opt(o, w, "max_iterations", s->max_iterations, 1, 10000, &iters, err) ||
        nc_json_number_range_opt(o, w, "residual_tolerance_n", 1e-8, 0.0, INFINITY, &s->residual_tol_n, err) ||
        nc_json_number_range_opt(o, w, "relative_tolerance", 1e-10, 0.0, 1.0, &s->relative_tol, err) ||
        nc_json_number_range_opt(o, w, "displacement_tolerance_m", 1e-9, 0.0, INFINITY, &s->displacement_tol_m, err))
        return -1;
    s->type = type == 0 ? FEM_STATIC : FEM_DYNAMIC;
    s->integrator = (fem_integrator)integ;
    s->load_steps = (int)steps;
    s->factorization = fact;
    s->modified_newton = newton == 0;
    s->coupling_load_constant = coupling_load == 1;
    s->initial_static = initial_state == 1;
    s->max_iterations = (int)iters;
    if (s->residual_tol_n == 0 && s->relative_tol == 0)
        return nc_error_set(err, 1, "%s: residual_tolerance_n and relative_tolerance cannot both be 0", w);
    if (s->initial_static && s->type == FEM_STATIC)
        return nc_error_set(err, 1, "%s: initial_state \"static\" is for a dynamic analysis (a "
                            "static one starts from the reference state and is its own equilibrium)", w);
    if (s->initial_static && s->load_ramp_s > 0)
        return nc_error_set(err, 1, "%s: initial_state \"static\" with load_ramp_s %g: the loads "
                            "are 0 at t = 0, so the equilibrium would hold the prestress only and "
                            "the ramp would then set the net swinging; use one or the other", w,
                            s->load_ramp_s);
    if (s->type == FEM_DYNAMIC) {
        /* end_time_s / dt_s steps: refuse a step lost in the float spacing of the time and a
         * run that would never end (nc_time.h) */
        char what[WHERE_MAX + 8];
        long steps;
        nc_json_path(what, sizeof what, w, "dt_s");
        if (nc_time_check_step(s->dt_s, s->end_time_s, what, err) ||
            nc_time_step_count(s->end_time_s, s->dt_s, NC_TIME_MAX_STEPS, what, &steps, err))
            return -1;
    }
    return 0;
}

static int parse_rest(fem_model *m, const cJSON *root, const char *file, nc_error *err)
{
    static const char *const mass_kinds[] = {"consistent", "lumped", NULL};
    static const double g_default[3] = {0, 0, -9.81};
    int mass;
    if (nc_json_bool_opt(root, file, "self_weight", 0, &m->self_weight, err) ||
        nc_json_vec3_opt(root, file, "gravity_m_s2", g_default, m->gravity, err) ||
        nc_json_choice_opt(root, file, "mass", mass_kinds, 0, &mass, err))
        return -1;
    m->lumped_mass = mass == 1;
    const cJSON *o;
    char w[WHERE_MAX];
    if (nc_json_object_opt(root, file, "rayleigh", &o, err)) return -1;
    if (o) {
        static const char *const keys[] = {"tau_per_s", "kappa_s", NULL};
        snprintf(w, sizeof w, "%s: rayleigh", file);
        if (nc_json_check_keys(o, w, keys, err) ||
            nc_json_number_range_opt(o, w, "tau_per_s", 0.0, 0.0, INFINITY, &m->tau_per_s, err) ||
            nc_json_number_range_opt(o, w, "kappa_s", 0.0, 0.0, INFINITY, &m->kappa_s, err))
            return -1;
    }
    if (nc_json_object_opt(root, file, "interface", &o, err)) return -1;
    if (o) {
        static const char *const keys[] = {"element_sets", NULL};
        snprintf(w, sizeof w, "%s: interface", file);
        const cJSON *arr;
        int n;
        if (nc_json_check_keys(o, w, keys, err) || nc_json_array(o, w, "element_sets", &arr, &n, err)) return -1;
        if (n < 1) return nc_error_set(err, 1, "%s.element_sets: expected at least one set name", w);
        m->interface_sets = malloc((size_t)n * sizeof(int));
        if (!m->interface_sets) return nc_error_set(err, 1, "out of memory");
        int i = 0;
        for (const cJSON *it = arr->child; it; it = it->next, i++) {
            int s = cJSON_IsString(it) ? fem_model_find_set(m, it->valuestring) : -1;
            if (s < 0) return nc_error_set(err, 1, "%s.element_sets[%d]: expected the name of an element set", w, i);
            m->interface_sets[m->n_interface_sets++] = s;
        }
    }
    const cJSON *mon = cJSON_GetObjectItemCaseSensitive(root, "monitor_nodes");
    if (mon) {
        snprintf(w, sizeof w, "%s: monitor_nodes", file);
        if (parse_node_ref(m, mon, w, &m->monitor_nodes, &m->n_monitor, err)) return -1;
        if (m->n_monitor < 1) return nc_error_set(err, 1, "%s: expected at least one node", w);
    }
    if (nc_json_object_opt(root, file, "output", &o, err)) return -1;
    if (o) {
        static const char *const keys[] = {"interval_steps", NULL};
        long every;
        snprintf(w, sizeof w, "%s: output", file);
        if (nc_json_check_keys(o, w, keys, err) ||
            nc_json_int_opt(o, w, "interval_steps", 1, 1, 1000000000L, &every, err))
            return -1;
        m->settings.output_interval = (int)every;
    }
    return 0;
}

int fem_input_load(const char *path, fem_model *m, nc_error *err)
{
    return fem_input_load_opt(path, m, NULL, err);
}

int fem_input_load_opt(const char *path, fem_model *m, const fem_input_options *opt,
                       nc_error *err)
{
    FILE *sink = opt ? opt->warnings : NULL;
    fem_model_init(m, path);
    cJSON *root;
    if (nc_json_load_file(path, &root, err)) return -1;
    int rc = -1;
    const char *file = path;
    static const char *const keys[] = {"description", "nodes", "elements", "net", "mesh",
                                       "element_sets", "node_sets", "supports", "point_loads",
                                       "self_weight", "gravity_m_s2", "mass", "rayleigh",
                                       "interface", "monitor_nodes", "output", "analysis", NULL};
    if (!cJSON_IsObject(root)) {
        nc_error_set(err, 1, "%s: expected a JSON object {...} at the top level", path);
        goto out;
    }
    if (nc_json_check_keys(root, file, keys, err) || parse_sets(m, root, file, sink, err)) goto out;
    const cJSON *net = cJSON_GetObjectItemCaseSensitive(root, "net");
    const cJSON *mesh = cJSON_GetObjectItemCaseSensitive(root, "mesh");
    const cJSON *nodes = cJSON_GetObjectItemCaseSensitive(root, "nodes");
    int sources = (net != NULL) + (mesh != NULL) + (nodes != NULL);
    if (sources != 1) {
        nc_error_set(err, 1, "%s: expected exactly one of \"nodes\"+\"elements\", \"net\" or \"mesh\", got %d", path, sources);
        goto out;
    }
    if (net) {
        if (!cJSON_IsObject(net)) { nc_error_set(err, 1, "%s: net: expected an object {...}", path); goto out; }
        if (cJSON_GetObjectItemCaseSensitive(root, "elements")) { nc_error_set(err, 1, "%s: elements: not allowed together with net", path); goto out; }
        if (parse_net(m, net, file, err)) goto out;
    } else if (mesh) {
        if (!cJSON_IsObject(mesh)) { nc_error_set(err, 1, "%s: mesh: expected an object {...}", path); goto out; }
        if (cJSON_GetObjectItemCaseSensitive(root, "elements")) { nc_error_set(err, 1, "%s: elements: not allowed together with mesh", path); goto out; }
        if (parse_gmsh(m, mesh, file, err)) goto out;
    } else if (parse_explicit_mesh(m, root, file, err)) {
        goto out;
    }
    if (parse_node_sets(m, root, file, err) || parse_supports(m, root, file, err) ||
        parse_loads(m, root, file, err) || parse_analysis(m, root, file, err) ||
        parse_rest(m, root, file, err) || fem_model_finalize(m, err))
        goto out;
    if (m->settings.fail_on_overload) {   /* an option that can never fire is a mistake */
        int any = 0;
        for (int k = 0; k < m->n_sets; k++) any |= m->sets[k].breaking_load_n > 0.0;
        if (!any)
            nc_warn(sink, "%s.analysis.fail_on_overload: no element set gives breaking_load_n, so "
                          "nothing can exceed it", file);
    }
    rc = 0;
out:
    cJSON_Delete(root);
    return rc;
}
