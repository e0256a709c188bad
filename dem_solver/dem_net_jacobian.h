/* dem_net_jacobian — the Jacobian of the force a coupled step returns with respect to the
 * end-of-step interface motion it received (interface-Jacobian coupling,
 * docs/notes/damped_contact.md).
 *
 * Contract: dem_sim_solve_coupled_jacobian() is dem_sim_solve_coupled() (the same results,
 * bit for bit) that also returns
 *   K = -dF/du^{n+1}   as 3x3 blocks (force node i, motion node j), row-major (row: force
 *                      direction on node i, column: motion direction of node j), N/m,
 *                      interface node indices (0..n_nodes-1, the order of the interface);
 *                      each (i, j) appears at most once (contributions are summed here), and
 *                      i, j are one node or the two nodes of one edge;
 *   C = -dF/du̇^{n+1} = 0 exactly: the received velocity is only checked and stored, the
 *                      wall moves from u^n to u^{n+1} at the velocity (u^{n+1} - u^n)/dt, so
 *                      the dashpots act on u^{n+1} through 1/dt and appear in K.
 * In the FEM's form F(u, u̇) = F^k - K (u - u^k) - C (u̇ - u̇^k) (fem_analysis_set_linearisation,
 * C_blocks NULL).
 *
 * What K contains: the exact derivative of what the DEM computes in the step: every sub-step
 * s of S with the wall at u^n + f_s (u^{n+1} - u^n) (f_s = (s+1)/S, or (s+1/2)/S with
 * wall_position "middle") and its velocity; the closest point on an edge and its parameter t
 * (the shape functions (1-t), t and their change along the edge), the normal and the
 * overlap; the crossed-cable sign flip; the lever of the particle's rotation; the law (normal
 * spring, dashpot through δ̇ and, with Hunt–Crossley, through the impact speed v0 an earlier
 * sub-step of the step set; the no-tension clamp of Hertz; the tangential spring with its
 * history carried through the sub-steps — its projection onto the turning tangent plane, the
 * unloading rescale kt/kt_prev and the Coulomb cap when sliding); the step average or, with
 * coupling_force "end_of_step", the last sub-step only.
 * The particles (particle_response):
 *  - DEM_JAC_FROZEN: every particle keeps the positions, velocities and spins it had in the
 *    actual run. The error is of order K dt² / m (a particle of mass m pushed by the
 *    contact over the coupling step dt): small for light, slow or short contacts, not for a
 *    heavy rock whose impact lasts about one coupling step — the granite sphere (R 0.4 m,
 *    710 kg) at 10 m/s on the steel net at dt 1e-3 s has K dt² / m ~ 1.4 and the frozen K is
 *    2.5 times the real one (tests/dem_solver/test_jacobian.c).
 *  - DEM_JAC_RESPOND_LOCAL (default): a particle (a free sphere, or a cluster as one rigid
 *    body) that touches one node or one edge's two nodes in the step also carries the
 *    derivative of its own motion through the sub-steps (symplectic Euler of
 *    dem_integrate.c driven by the change of its net forces and torques); its other
 *    contacts (spheres, planes, meshes) keep their forces and, on a turning cluster, their
 *    levers. For a free sphere that touches only the net this is the exact derivative of
 *    the real step (granite case: 7e-10 of max |K|). A cluster's rotation is linearised:
 *    its world-frame inertia is held at its orientation at its first recorded net contact
 *    of the step and the gyroscopic change of ω with the turn is left out, terms of
 *    relative order |ω| dt. Particles touching more net nodes stay frozen, so every block
 *    stays within one element (what a structure with a fixed element pattern can take).
 *  - DEM_JAC_RESPOND: every particle responds; a particle touching several edges then
 *    gives blocks between nodes that share no element. fem_solver grows its pattern by such
 *    pairs (fem_analysis_set_linearisation), so the participant (dem_participant.c) uses
 *    this mode.
 * In every mode a cluster touching more than DEM_JAC_MAX_NODES nodes is split into its
 * spheres, frozen (each sphere's share of K stays; a sphere touching more is dropped).
 * Why not the particles' mutual response: it couples every particle of a heap (a solve per
 * step instead of a sweep over the net contacts). The contact set is the one of the actual
 * run (K is a derivative: a contact that starts or ends exactly at u^{n+1} has a kink).
 *
 * Cost: off (dem_sim_solve_coupled, or jac NULL): nothing — the step runs exactly as
 * before. On: a record per net contact and sub-step during the step (the particle state at
 * the contact pass, the incoming history) and afterwards one sweep over those records with
 * a tangent of 3 columns per node the particle touches (at most DEM_JAC_MAX_NODES; a
 * particle touching more is left out of K and counted in n_dropped): linear
 * in the number of net contacts times sub-steps (each record's work in its particle's
 * columns only), plus a sort of the records and of the distinct blocks (summed per node pair
 * as they come, in a hash table). The results of the step are bit-identical with the option
 * on.
 */
#ifndef DEM_NET_JACOBIAN_H
#define DEM_NET_JACOBIAN_H

#include <stddef.h>
#include <stdint.h>

#include "dem_contact_hertz.h"
#include "dem_coupling.h"
#include "nc_error.h"

/* One net contact in one sub-step, as the contact pass saw it. */
typedef struct dem_jac_record {
    int32_t sub, i, kind, j;   /* sub-step, sphere, DEM_CONTACT_NET_EDGE / _NODE, edge / node */
    int32_t aux;               /* a node contact's strand (the contact's key with i, kind, j) */
    int32_t body;              /* the sphere's body (a free sphere's own, or its cluster) */
    int32_t link;              /* the same contact in the previous sub-step's records, or -1 */
    int32_t has_prev;          /* its history was found in the previous DEM step */
    double p[3], v[3], w[3];   /* sphere centre (m), velocity (m/s), body spin (rad/s) */
    double offset[3];          /* sphere centre - its body's centre of mass (m; 0 when free) */
    double quat[4];            /* the body's orientation (w, x, y, z) */
    double radius, reach;      /* sphere radius, radius + cable radius (m) */
    dem_pair pair;
    double ft[3], kt_prev, fn_prev, impact_speed, n_prev[3]; /* incoming history (used in
                                                                sub-step 0) */
    double f_base[3], t_base[3]; /* force and torque on the sphere at the solve's displacement */
} dem_jac_record;

/* Particle response (dem_net_jacobian.particle_response). */
enum {
    DEM_JAC_FROZEN = 0,        /* every particle frozen */
    DEM_JAC_RESPOND_LOCAL = 1, /* particles (free spheres, clusters) that touch one node or
                                  one edge respond, the others are frozen: blocks stay
                                  within one element */
    DEM_JAC_RESPOND = 2        /* every particle responds: blocks may join any two nodes
                                  one particle touches */
};

/* Most net nodes one particle may touch in one step (the columns of its tangents). */
#define DEM_JAC_MAX_NODES 32

/* Per-record state of a replay: outgoing history and its tangent. */
typedef struct dem_jac_state {
    double ft[3], kt, fn, impact_speed, n[3];
    double dft[3][3 * DEM_JAC_MAX_NODES], dkt[3 * DEM_JAC_MAX_NODES];
    double dv0[3 * DEM_JAC_MAX_NODES];   /* of impact_speed (Hunt–Crossley v0) */
} dem_jac_state;

typedef struct dem_net_jacobian {
    /* option, set by the caller after init (default DEM_JAC_RESPOND_LOCAL) */
    int particle_response;     /* DEM_JAC_FROZEN / _RESPOND_LOCAL / _RESPOND (above) */
    /* result of the last solve */
    size_t n_dropped;          /* particles touching more than DEM_JAC_MAX_NODES nodes: their
                                  forces are exact, their share of K is left out */
    size_t n_blocks, cap_blocks;
    int32_t *nodes;            /* 2 n_blocks: (force node i, motion node j) */
    double *K;                 /* 9 n_blocks, N/m */
    /* record of the last solve (read by dem_net_jacobian_replay) */
    size_t n_rec, cap_rec;
    dem_jac_record *rec;
    long n_sub;                /* sub-steps of the last solve (0 after a free flight) */
    size_t cap_sub;
    double *frac, *weight;     /* per sub-step: wall fraction, weight of its force in F */
    size_t *sub_first;         /* n_sub + 1: first record of each sub-step */
    double h, dt_step;
    size_t n_nodes;
    double *start;             /* 3 n_nodes: wall at the start of the step */
    int force_at_end;
} dem_net_jacobian;

void dem_net_jacobian_init(dem_net_jacobian *jac);
void dem_net_jacobian_free(dem_net_jacobian *jac);

/* dem_sim_solve_coupled() that also fills jac (above). jac NULL: exactly dem_sim_solve_coupled. */
int dem_sim_solve_coupled_jacobian(dem_sim *s, double dt_step, const double *disp_end,
                                   const double *vel_end, double *force_out,
                                   dem_coupled_info *info, dem_net_jacobian *jac, nc_error *err);

/* The frozen-particle step again at another end displacement disp_end (3 n_nodes), from the
 * record of the last dem_sim_solve_coupled_jacobian(): force_out (3 n_nodes, may be NULL)
 * receives the returned force, and with want_K 1 jac's blocks are recomputed there (2:
 * also take the particles' reference forces there, as the solve does). The particles move
 * as particle_response says. At the displacement of the solve it reproduces that solve's
 * force (to rounding: a node contact's closest point is taken as the node itself) and its K.
 * For tests (finite differences of what K linearises) and diagnostics. */
int dem_net_jacobian_replay(const dem_sim *s, dem_net_jacobian *jac, const double *disp_end,
                            double *force_out, int want_K, nc_error *err);

/* Internal to dem_coupling.c: start a record for a step of `substeps` sub-steps, record the
 * net contacts of sub-step `sub` (call between dem_sim_step_forces and _advance). */
int dem_net_jacobian_begin(dem_net_jacobian *jac, const dem_sim *s, double dt_step,
                           long substeps, nc_error *err);
int dem_net_jacobian_record(dem_net_jacobian *jac, const dem_sim *s, long sub, nc_error *err);

#endif
