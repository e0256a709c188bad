/* dem_detect — the interface between the contact pass and its detectors, one per wall kind.
 *
 * Contract: a detector finds the contacts of one sphere i with one kind of partner (higher-
 * numbered spheres, planes, STL mesh features, net edges/nodes), in a deterministic order, and
 * for each one appends a record to the thread's list (dem_new_record: key and history),
 * computes the force (dem_contact_force) and sums it at once onto the sphere(s) or into the
 * spill list (dem_add_to_sphere / dem_spill_add) — dem_emit_wall_contact() does all of that
 * for a wall contact. It returns 0, or -1 when out of memory; *overflow is set when a sphere
 * touches more than DEM_MAX_FEATURES features of one mesh or of the net. Each detector lives in
 * its own file (dem_detect_<kind>.c) and exports one dem_detector; the table in
 * dem_contact_pass.c lists them in the order their contacts appear for a sphere.
 * The record and force functions are inline (always_inline): they run once per contact and step.
 * The pass calls a detector once per sphere, so a detector keeps its common case (no contact)
 * a lean loop and handles the contacts out of line.
 */
#ifndef DEM_DETECT_H
#define DEM_DETECT_H

#include <math.h>
#include <stdlib.h>

#include "dem_contact_hertz.h"
#include "dem_sim.h"

#define DEM_MAX_FEATURES 48 /* wall features touching one sphere in one mesh / the net */

static inline __attribute__((always_inline)) void dem_cross3(const double a[3], const double b[3],
                                                             double out[3])
{
    out[0] = a[1] * b[2] - a[2] * b[1];
    out[1] = a[2] * b[0] - a[0] * b[2];
    out[2] = a[0] * b[1] - a[1] * b[0];
}

/* A wall contact found by a detector, handed to dem_emit_wall_contact(). */
typedef struct dem_contact_in {
    int kind;
    int32_t j, aux;
    double overlap;
    double n[3];           /* unit normal from sphere i towards the other body */
    double lever_i;        /* distance from i's centre to the contact point along n */
    double lever_j;        /* same for sphere j (sphere contacts) */
    double v_other[3];     /* velocity of the other body's material point at the contact */
    double weight;         /* net edge parameter t */
    double reach;          /* net: sphere radius + cable radius */
    dem_pair pair;
} dem_contact_in;

/* Where a thread writes the contacts of the sphere it is working on, and where the forces go.
 * Forces are summed while contacts are found, in contact order (by sphere i, then discovery
 * order): directly into s->model.sph.force/torque for spheres whose contributions all come
 * from this thread's range, through the thread's spill list for walls, net nodes and spheres shared with
 * another range (those lists are summed afterwards in thread order, which is contact order).
 * So every sum runs in the same order whatever the number of threads. */
typedef struct dem_emit_ctx {
    dem_contacts *out;
    dem_spills *spill;
    size_t first;          /* index in out of the sphere's first contact */
} dem_emit_ctx;

/* Appends a contribution to a thread's spill list (-1 without memory). Out of line, as
 * dem_emit_wall_contact(): inlined they would crowd the registers of the detectors' loops. */
int dem_spill_add(dem_spills *sp, int kind, int32_t index, double weight, const double f[3],
                  const double t[3]);

/* Adds force f and torque t to sphere i (directly, or through the spills if it is shared). */
static inline int dem_add_to_sphere(const dem_sim *s, dem_emit_ctx *ctx, size_t i, const double f[3],
                                    const double t[3])
{
    if (s->work.shared_sphere[i]) return dem_spill_add(ctx->spill, DEM_CONTACT_SPHERE, (int32_t)i, 0.0, f, t);
    double *fi = s->model.sph.force + 3 * i, *ti = s->model.sph.torque + 3 * i;
    fi[0] += f[0];
    fi[1] += f[1];
    fi[2] += f[2];
    ti[0] += t[0];
    ti[1] += t[1];
    ti[2] += t[2];
    return 0;
}

/* Appends a contact record with key (i, kind, j, aux) to the thread's list and finds the history
 * of the same key from the previous step (ft, kt_prev, fn_prev, impact_speed; zero for a new
 * contact). Returns
 * the record index (or -1 without memory) and in *prev the previous record (or -1). Contacts of
 * a sphere usually come in the same order as in the previous step, so the record at the same
 * position is tried first. */
static inline __attribute__((always_inline)) long dem_new_record(const dem_sim *s, dem_emit_ctx *ctx,
                                                                 size_t i, int kind, int32_t j,
                                                                 int32_t aux, double ft[3],
                                                                 double *kt_prev, double *fn_prev,
                                                                 double *impact_speed, int32_t *prev)
{
    dem_contacts *out = ctx->out;
    if (out->n == out->cap && dem_contacts_reserve(out, out->n + 1, NULL)) return -1;
    size_t c = out->n++;
    out->i[c] = (int32_t)i;
    out->kind[c] = kind;
    out->j[c] = j;
    out->aux[c] = aux;
    const dem_contacts *pv = &s->contact.prev;
    int32_t lo = s->contact.prev_first[i], hi = s->contact.prev_first[i + 1];
    int32_t hint = lo + (int32_t)(c - ctx->first);
    int32_t found = -1;
    if (hint < hi && pv->j[hint] == j && pv->kind[hint] == kind && pv->aux[hint] == aux) {
        found = hint;
    } else {
        for (int32_t p = lo; p < hi; p++)
            if (pv->kind[p] == kind && pv->j[p] == j && pv->aux[p] == aux) {
                found = p;
                break;
            }
    }
    if (found >= 0) {
        const double *h = pv->ft + 3 * (size_t)found;
        ft[0] = h[0];
        ft[1] = h[1];
        ft[2] = h[2];
        *kt_prev = pv->kt_prev[found];
        *fn_prev = pv->fn_prev[found];
        *impact_speed = pv->impact_speed[found];
    } else {
        ft[0] = ft[1] = ft[2] = 0.0;
        *kt_prev = 0.0;
        *fn_prev = 0.0;
        *impact_speed = 0.0;   /* set by dem_contact_force() at the first touch */
    }
    *prev = found;
    return (long)c;
}

/* Stores the updated history and geometry of record c. */
static inline __attribute__((always_inline)) void dem_store_record(dem_contacts *out, size_t c,
                                                                   const double ft[3], double kt_prev,
                                                                   double fn_prev, double impact_speed,
                                                                   double overlap,
                                                                   const double n[3])
{
    double *h = out->ft + 3 * c, *nn = out->normal + 3 * c;
    h[0] = ft[0];
    h[1] = ft[1];
    h[2] = ft[2];
    out->kt_prev[c] = kt_prev;
    out->fn_prev[c] = fn_prev;
    out->impact_speed[c] = impact_speed;
    out->overlap[c] = overlap;
    nn[0] = n[0];
    nn[1] = n[1];
    nn[2] = n[2];
}

/* A contact of sphere i with a wall (plane, mesh feature, net edge or node): the record with
 * its history, the force, the torque on i and the reaction on the wall (through the spills). */
int dem_emit_wall_contact(const dem_sim *s, dem_emit_ctx *ctx, size_t i, dem_contact_in *in,
                          double dt);

/* A wall feature (mesh face/edge/vertex, net edge/node) within contact distance of a sphere. */
typedef struct dem_feature {
    int type;      /* 0 face, 1 edge, 2 vertex (mesh); 1 edge, 2 node (net) */
    int32_t id;    /* triangle / edge / vertex index */
    int32_t owner; /* triangle (mesh) or edge (net) that produced it; a net node: the
                      strand (rope) through it (dem_net_strands.h) */
    double q[3];   /* closest point */
    double d2;
    double t;      /* net edge parameter */
} dem_feature;

/* Adds feature x unless it is already listed; sets *overflow when the list is full. */
static inline void dem_add_feature(dem_feature *f, int *n, const dem_feature *x, int *overflow)
{
    for (int k = 0; k < *n; k++)
        if (f[k].type == x->type && f[k].id == x->id) return; /* shared feature: once */
    if (*n == DEM_MAX_FEATURES) {
        *overflow = 1;
        return;
    }
    f[(*n)++] = *x;
}

/* Contacts of sphere i with one kind of partner, forces for step dt. */
typedef int dem_detect_fn(const dem_sim *s, dem_emit_ctx *ctx, size_t i, double dt,
                          int *overflow);

typedef struct dem_detector {
    const char *name;                  /* kind of partner, for messages */
    int (*present)(const dem_sim *s);  /* 1 if the model has partners of this kind */
    dem_detect_fn *detect;
} dem_detector;

extern const dem_detector dem_detect_sphere; /* dem_detect_sphere.c: Verlet neighbours j > i */
extern const dem_detector dem_detect_plane;  /* dem_detect_plane.c */
extern const dem_detector dem_detect_mesh;   /* dem_detect_mesh.c: STL mesh faces, edges, vertices */
extern const dem_detector dem_detect_net;    /* dem_detect_net.c: net edges and nodes */

#endif
