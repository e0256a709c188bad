/* fem_model — model storage, the regular-net generator and the consistency checks that
 * turn an input into arrays the solver can trust (see fem_model.h). */
#include "fem_model.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

void fem_settings_default(fem_settings *s)
{
    memset(s, 0, sizeof *s);
    s->type = FEM_DYNAMIC;
    s->integrator = FEM_NEWMARK;
    s->beta = 0.25;
    s->gamma = 0.5;
    s->rho_inf = 0.8;
    s->alpha_b = -0.1;
    s->dt_s = 1e-3;
    s->end_time_s = 1.0;
    s->load_steps = 1;
    s->max_iterations = 50;   /* fem_solver/README.md: a slack net snapping taut needed more than 20 */
    s->residual_tol_n = 1e-8;
    s->relative_tol = 1e-10;
    s->displacement_tol_m = 1e-9;
    s->output_interval = 1;
    s->modified_newton = 1;
    s->contraction = 0.2;
    s->coupling_load_constant = 0;
}

void fem_model_init(fem_model *m, const char *source)
{
    memset(m, 0, sizeof *m);
    snprintf(m->source, sizeof m->source, "%s", source ? source : "model");
    m->gravity[2] = -9.81;
    fem_settings_default(&m->settings);
}

int fem_model_alloc(fem_model *m, int n_nodes, int n_elements, nc_error *err)
{
    if (n_nodes < 2 || n_elements < 1)
        return nc_error_set(err, 1, "%s: a model needs at least 2 nodes and 1 element (got %d nodes, %d elements)",
                            m->source, n_nodes, n_elements);
    m->n_nodes = n_nodes;
    m->n_elements = n_elements;
    m->X = calloc(3 * (size_t)n_nodes, sizeof *m->X);
    m->conn = calloc(2 * (size_t)n_elements, sizeof *m->conn);
    m->element_set = calloc((size_t)n_elements, sizeof *m->element_set);
    m->fixed = calloc(3 * (size_t)n_nodes, 1);
    m->u_prescribed = calloc(3 * (size_t)n_nodes, sizeof *m->u_prescribed);
    m->f_point = calloc(3 * (size_t)n_nodes, sizeof *m->f_point);
    if (!m->X || !m->conn || !m->element_set || !m->fixed || !m->u_prescribed || !m->f_point)
        return nc_error_set(err, 1, "%s: out of memory for %d nodes, %d elements", m->source,
                            n_nodes, n_elements);
    return 0;
}

int fem_model_add_set(fem_model *m, const fem_element_set *set, nc_error *err)
{
    fem_element_set *grown = realloc(m->sets, (size_t)(m->n_sets + 1) * sizeof *grown);
    if (!grown) return nc_error_set(err, 1, "%s: out of memory", m->source);
    m->sets = grown;
    fem_set_type *types = realloc(m->set_types, (size_t)(m->n_sets + 1) * sizeof *types);
    if (!types) return nc_error_set(err, 1, "%s: out of memory", m->source);
    m->set_types = types;
    memset(&m->set_types[m->n_sets], 0, sizeof *types);
    m->sets[m->n_sets] = *set;
    return m->n_sets++;
}

int fem_model_add_node_set(fem_model *m, const char *name, const int *nodes, int count,
                           nc_error *err)
{
    fem_node_set *grown = realloc(m->node_sets, (size_t)(m->n_node_sets + 1) * sizeof *grown);
    if (!grown) return nc_error_set(err, 1, "%s: out of memory", m->source);
    m->node_sets = grown;
    fem_node_set *s = &m->node_sets[m->n_node_sets];
    memset(s, 0, sizeof *s);
    snprintf(s->name, sizeof s->name, "%s", name);
    s->nodes = malloc((size_t)(count > 0 ? count : 1) * sizeof *s->nodes);
    if (!s->nodes) return nc_error_set(err, 1, "%s: out of memory", m->source);
    if (count > 0) memcpy(s->nodes, nodes, (size_t)count * sizeof *nodes);
    s->count = count;
    m->n_node_sets++;
    return 0;
}

const fem_node_set *fem_model_find_node_set(const fem_model *m, const char *name)
{
    for (int i = 0; i < m->n_node_sets; i++)
        if (strcmp(m->node_sets[i].name, name) == 0) return &m->node_sets[i];
    return NULL;
}

int fem_model_find_set(const fem_model *m, const char *name)
{
    for (int i = 0; i < m->n_sets; i++)
        if (strcmp(m->sets[i].name, name) == 0) return i;
    return -1;
}

int fem_model_generate_net(fem_model *m, const double origin[3], const double edge1[3],
                           const double edge2[3], int count1, int count2, int set,
                           nc_error *err)
{
    if (count1 < 2 || count2 < 1)
        return nc_error_set(err, 1, "%s: net: expected count1 >= 2 and count2 >= 1, got %d, %d",
                            m->source, count1, count2);
    long n = (long)count1 * count2;
    long e = (long)(count1 - 1) * count2 + (long)count1 * (count2 - 1);
    if (n > 50000000L) return nc_error_set(err, 1, "%s: net: %ld nodes is too many", m->source, n);
    if (fem_model_alloc(m, (int)n, (int)e, err)) return -1;
    for (int j = 0; j < count2; j++)
        for (int i = 0; i < count1; i++) {
            double s = (double)i / (count1 - 1);
            double t = count2 > 1 ? (double)j / (count2 - 1) : 0.0;
            for (int c = 0; c < 3; c++)
                m->X[3 * (i + count1 * j) + c] = origin[c] + s * edge1[c] + t * edge2[c];
        }
    int k = 0;
    for (int j = 0; j < count2; j++)
        for (int i = 0; i + 1 < count1; i++, k++) {
            m->conn[2 * k] = i + count1 * j;
            m->conn[2 * k + 1] = i + 1 + count1 * j;
            m->element_set[k] = set;
        }
    for (int j = 0; j + 1 < count2; j++)
        for (int i = 0; i < count1; i++, k++) {
            m->conn[2 * k] = i + count1 * j;
            m->conn[2 * k + 1] = i + count1 * (j + 1);
            m->element_set[k] = set;
        }
    /* node sets */
    int *buf = malloc((size_t)n * sizeof *buf);
    if (!buf) return nc_error_set(err, 1, "%s: out of memory", m->source);
    int c = 0;
    for (int j = 0; j < count2; j++)
        for (int i = 0; i < count1; i++)
            if (i == 0 || j == 0 || i == count1 - 1 || j == count2 - 1) buf[c++] = i + count1 * j;
    int rc = fem_model_add_node_set(m, "boundary", buf, c, err);
    int corners[4] = {0, count1 - 1, count1 * (count2 - 1), count1 * count2 - 1};
    if (!rc) rc = fem_model_add_node_set(m, "corners", corners, count2 > 1 ? 4 : 2, err);
    if (!rc && count1 % 2 == 1 && count2 % 2 == 1) {
        int centre = count1 / 2 + count1 * (count2 / 2);
        rc = fem_model_add_node_set(m, "center", &centre, 1, err);
    }
    c = 0;
    for (int j = 0; j < count2; j++) buf[c++] = count1 * j;
    if (!rc) rc = fem_model_add_node_set(m, "edge1_start", buf, c, err);
    c = 0;
    for (int j = 0; j < count2; j++) buf[c++] = count1 - 1 + count1 * j;
    if (!rc) rc = fem_model_add_node_set(m, "edge1_end", buf, c, err);
    c = 0;
    for (int i = 0; i < count1; i++) buf[c++] = i;
    if (!rc) rc = fem_model_add_node_set(m, "edge2_start", buf, c, err);
    c = 0;
    for (int i = 0; i < count1; i++) buf[c++] = i + count1 * (count2 - 1);
    if (!rc) rc = fem_model_add_node_set(m, "edge2_end", buf, c, err);
    free(buf);
    return rc;
}

static const char *dof_name(int d)
{
    return d == 0 ? "x" : d == 1 ? "y" : "z";
}

/* Members of the element types: one per element, except a chain type's runs (consecutive
 * elements of one set, each starting at the previous one's end node). */
static int build_members(fem_model *m, nc_error *err)
{
    const int ne = m->n_elements;
    free(m->member_first); free(m->member_of); free(m->history_offset);
    m->member_first = malloc(((size_t)ne + 1) * sizeof *m->member_first);
    m->member_of = malloc((size_t)ne * sizeof *m->member_of);
    m->history_offset = malloc((size_t)ne * sizeof *m->history_offset);
    if (!m->member_first || !m->member_of || !m->history_offset)
        return nc_error_set(err, 1, "%s: out of memory", m->source);
    for (int s = 0; s < m->n_sets; s++)
        if (!fem_element_type(m->set_types[s].type))
            return nc_error_set(err, 1, "%s: element_sets[%d]: unknown element type %d", m->source,
                                s, m->set_types[s].type);
    int nb = 0, hist = 0;
    m->max_chain_nodes = 2;
    for (int e = 0; e < ne; e++) {
        const fem_element_ops *ops = fem_element_type(m->set_types[m->element_set[e]].type);
        int extend = ops->chain && e > 0 && m->element_set[e - 1] == m->element_set[e] &&
                     m->conn[2 * (e - 1) + 1] == m->conn[2 * e];
        if (!extend) {
            m->member_first[nb] = e;
            m->history_offset[nb] = hist;
            hist += ops->history_count;
            nb++;
        }
        m->member_of[e] = nb - 1;
        int nodes = e - m->member_first[nb - 1] + 2;
        if (nodes > m->max_chain_nodes) m->max_chain_nodes = nodes;
    }
    m->member_first[nb] = ne;
    m->n_members = nb;
    m->history_count = hist;
    /* a rope through a node twice would make its chain blocks overlap */
    for (int b = 0; b < nb; b++) {
        int first = m->member_first[b], count = m->member_first[b + 1] - first;
        if (count < 2) continue;
        for (int i = 0; i < count; i++)
            for (int j = i + 1; j <= count; j++) {
                int a = m->conn[2 * (first + i)];
                int c = j < count ? m->conn[2 * (first + j)] : m->conn[2 * (first + count - 1) + 1];
                if (a == c)
                    return nc_error_set(err, 1, "%s: elements[%d..%d] (a %s of set \"%s\"): the rope passes node %d twice",
                                        m->source, first, first + count - 1,
                                        fem_element_type(m->set_types[m->element_set[first]].type)->name,
                                        m->sets[m->element_set[first]].name, a);
            }
    }
    for (int b = 0; b < nb; b++) {
        const int first = m->member_first[b], set = m->element_set[first];
        const fem_element_ops *ops = fem_element_type(m->set_types[set].type);
        if (!ops->check) continue;
        fem_element_ctx c = {.m = m, .set = &m->sets[set], .param = m->set_types[set].param,
                             .member = b, .first = first, .count = m->member_first[b + 1] - first};
        if (ops->check(&c, err)) return -1;
    }
    return 0;
}

int fem_model_finalize(fem_model *m, nc_error *err)
{
    if (m->n_sets < 1) return nc_error_set(err, 1, "%s: element_sets: at least one set is needed", m->source);
    for (int i = 0; i < 3 * m->n_nodes; i++)
        if (!isfinite(m->X[i]))
            return nc_error_set(err, 1, "%s: node %d: coordinate %s is not a finite number",
                                m->source, i / 3, dof_name(i % 3));
    size_t ne = (size_t)m->n_elements;
    m->L0 = malloc(ne * sizeof *m->L0);
    m->EA = malloc(ne * sizeof *m->EA);
    m->AS = malloc(ne * sizeof *m->AS);
    m->rhoA = malloc(ne * sizeof *m->rhoA);
    m->is_cable = malloc(ne);
    int *used = calloc((size_t)m->n_nodes, sizeof *used);
    if (!m->L0 || !m->EA || !m->AS || !m->rhoA || !m->is_cable || !used) {
        free(used);
        return nc_error_set(err, 1, "%s: out of memory", m->source);
    }
    for (int e = 0; e < m->n_elements; e++) {
        int k = m->conn[2 * e], l = m->conn[2 * e + 1], s = m->element_set[e];
        if (k < 0 || k >= m->n_nodes || l < 0 || l >= m->n_nodes) {
            free(used);
            return nc_error_set(err, 1, "%s: elements[%d]: node index %d out of range 0..%d",
                                m->source, e, (k < 0 || k >= m->n_nodes) ? k : l, m->n_nodes - 1);
        }
        if (s < 0 || s >= m->n_sets) {
            free(used);
            return nc_error_set(err, 1, "%s: elements[%d]: element set %d does not exist", m->source, e, s);
        }
        double d2 = 0;
        for (int c = 0; c < 3; c++) {
            double d = m->X[3 * l + c] - m->X[3 * k + c];
            d2 += d * d;
        }
        if (k == l || !(d2 > 0)) {
            free(used);
            return nc_error_set(err, 1, "%s: elements[%d]: nodes %d and %d coincide (zero length)",
                                m->source, e, k, l);
        }
        const fem_element_set *p = &m->sets[s];
        m->L0[e] = sqrt(d2);
        m->EA[e] = p->youngs_modulus_pa * p->area_m2;
        m->AS[e] = p->prestress_pa * p->area_m2;
        m->rhoA[e] = p->density_kg_m3 * p->area_m2;
        m->is_cable[e] = p->behaviour == FEM_CABLE && m->set_types[s].type == FEM_TYPE_CABLE;
        used[k] = used[l] = 1;
    }
    if (build_members(m, err)) {
        free(used);
        return -1;
    }
    for (int i = 0; i < m->n_nodes; i++)
        if (!used[i] && !(m->fixed[3 * i] && m->fixed[3 * i + 1] && m->fixed[3 * i + 2])) {
            free(used);
            return nc_error_set(err, 1, "%s: node %d is not connected to any element (fix it with a support or remove it)",
                                m->source, i);
        }
    /* interface: elements of the chosen sets (default: every cable set, or all if none) */
    unsigned char *in_set = calloc((size_t)m->n_sets, 1);
    if (!in_set) { free(used); return nc_error_set(err, 1, "%s: out of memory", m->source); }
    if (m->n_interface_sets > 0) {
        for (int i = 0; i < m->n_interface_sets; i++) in_set[m->interface_sets[i]] = 1;
    } else {
        int any = 0;
        for (int s = 0; s < m->n_sets; s++)
            any |= (in_set[s] = m->sets[s].behaviour == FEM_CABLE && m->set_types[s].type == FEM_TYPE_CABLE);
        if (!any) memset(in_set, 1, (size_t)m->n_sets);
    }
    for (int i = 0; i < m->n_nodes; i++) used[i] = -1;
    m->n_iface_elements = 0;
    for (int e = 0; e < m->n_elements; e++)
        if (in_set[m->element_set[e]]) m->n_iface_elements++;
    m->iface_conn = malloc(2 * (size_t)(m->n_iface_elements + 1) * sizeof *m->iface_conn);
    m->iface_nodes = malloc((size_t)m->n_nodes * sizeof *m->iface_nodes);
    if (!m->iface_conn || !m->iface_nodes) {
        free(used); free(in_set);
        return nc_error_set(err, 1, "%s: out of memory", m->source);
    }
    /* interface nodes in increasing model order, so the list is easy to read */
    for (int e = 0; e < m->n_elements; e++)
        if (in_set[m->element_set[e]]) used[m->conn[2 * e]] = used[m->conn[2 * e + 1]] = 0;
    m->n_iface_nodes = 0;
    for (int i = 0; i < m->n_nodes; i++)
        if (used[i] == 0) {
            used[i] = m->n_iface_nodes;
            m->iface_nodes[m->n_iface_nodes++] = i;
        }
    int k = 0;
    for (int e = 0; e < m->n_elements; e++)
        if (in_set[m->element_set[e]]) {
            m->iface_conn[2 * k] = used[m->conn[2 * e]];
            m->iface_conn[2 * k + 1] = used[m->conn[2 * e + 1]];
            k++;
        }
    free(in_set);
    /* default monitor: the node nearest the centroid of all nodes */
    if (m->n_monitor == 0) {
        double c[3] = {0, 0, 0};
        for (int i = 0; i < m->n_nodes; i++)
            for (int d = 0; d < 3; d++) c[d] += m->X[3 * i + d] / m->n_nodes;
        int best = 0;
        double best_d2 = INFINITY;
        for (int i = 0; i < m->n_nodes; i++) {
            double d2 = 0;
            for (int d = 0; d < 3; d++) d2 += (m->X[3 * i + d] - c[d]) * (m->X[3 * i + d] - c[d]);
            if (d2 < best_d2) { best_d2 = d2; best = i; }
        }
        m->monitor_nodes = malloc(sizeof *m->monitor_nodes);
        if (!m->monitor_nodes) { free(used); return nc_error_set(err, 1, "%s: out of memory", m->source); }
        m->monitor_nodes[0] = best;
        m->n_monitor = 1;
    }
    free(used);
    const fem_settings *s = &m->settings;
    if (s->type == FEM_DYNAMIC && !(s->dt_s > 0))
        return nc_error_set(err, 1, "%s: analysis.dt_s: expected a number > 0", m->source);
    return 0;
}

void fem_model_free(fem_model *m)
{
    if (!m) return;
    free(m->X); free(m->conn); free(m->element_set); free(m->sets); free(m->set_types);
    for (int i = 0; i < m->n_node_sets; i++) free(m->node_sets[i].nodes);
    free(m->node_sets);
    free(m->fixed); free(m->u_prescribed); free(m->f_point);
    free(m->interface_sets); free(m->monitor_nodes);
    free(m->L0); free(m->EA); free(m->AS); free(m->rhoA); free(m->is_cable);
    free(m->member_first); free(m->member_of); free(m->history_offset);
    free(m->iface_nodes); free(m->iface_conn);
    memset(m, 0, sizeof *m);
}
