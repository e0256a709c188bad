/* dem_contact_pass — finding every contact of a step and summing its force, in parallel and
 * with results that do not depend on the thread count.
 *
 * Contract: per step the current contact list becomes the history, the Verlet list is updated
 * (dem_neighbor_list.h), and each thread handles a fixed contiguous range of spheres: for each
 * sphere it runs the detectors of the table in dem_contact_pass.c in table order (spheres,
 * planes, meshes, net: dem_detect.h), which append contact records to the thread's buffer and
 * sum the forces onto spheres as they go. Walls, net nodes and spheres shared between ranges
 * receive theirs through the thread's spill list, summed after the parallel part in range
 * order. The buffers are concatenated in range order, so every sum runs in contact order
 * whatever the number of threads. Mesh and net features shared by several triangles/edges are
 * counted once.
 */
#ifndef DEM_CONTACT_PASS_H
#define DEM_CONTACT_PASS_H

#include "dem_contact_list.h"
#include "nc_error.h"

typedef struct dem_sim dem_sim;

/* A contact force contribution summed after the parallel contact pass, in a fixed order:
 * forces on walls and net nodes, and forces on the spheres that receive contributions from
 * more than one thread's range of spheres (so that every sum runs in the same order whatever
 * the thread count). */
typedef struct dem_spill {
    int32_t kind;          /* DEM_CONTACT_SPHERE (force and torque on sphere `index`), _PLANE,
                              _MESH (wall `index`), _NET_EDGE (edge `index`, weight), _NET_NODE */
    int32_t index;
    double weight;         /* net edge parameter t */
    double f[3];           /* force to add */
    double t[3];           /* torque to add (spheres) */
} dem_spill;

typedef struct dem_spills {
    size_t n, cap;
    dem_spill *r;
} dem_spills;

/* The per-thread work buffers of the contact pass (also used by the neighbour list, which
 * sets the ranges and the shared flags at every build). */
typedef struct dem_thread_work {
    int n_buffers;                 /* threads of every parallel loop (at most DEM_MAX_BUFFERS) */
    dem_contacts *buffers;         /* one per thread, concatenated in order */
    dem_spills *spills;            /* one per thread: sums done after the parallel pass */
    int *overflow;                 /* one per thread: 1 + the detector whose feature list of
                                      one sphere overflowed, 0 if none */
    size_t *range_first;           /* n_buffers + 1: the spheres of buffer b are
                                      range_first[b] .. range_first[b+1]-1, balanced by the
                                      expected work at every neighbour-list build (results do
                                      not depend on the ranges) */
    uint8_t *shared_sphere;        /* per sphere: 1 if a Verlet neighbour lies in another
                                      thread's range (its force sum goes through the spills) */
} dem_thread_work;

/* Allocates n_buffers buffers for n_spheres spheres (equal ranges until the first build). */
int dem_thread_work_alloc(dem_thread_work *w, int n_buffers, size_t n_spheres, nc_error *err);
void dem_thread_work_free(dem_thread_work *w);

/* Finds contacts at the current positions, computes forces for step dt and sums them into
 * s->model.sph.force/torque (per sphere), s->model.net.force and s->wall_force. */
int dem_contact_pass(dem_sim *s, double dt, nc_error *err);

#endif
