/* dem_output — results of a DEM run: DIR/dem.h5, DIR/particles.xdmf and DIR/dem_net.xdmf.
 *
 * dem.h5 (SI; every dataset carries a "units" string attribute), k = output steps:
 *   /time [k] s;
 *   /particles/id, /particles/body, /particles/material [n] i32, /particles/radius [n] m
 *   (constant through a run), /particles/vertex [n] i32 (0..n-1, the XDMF's vertex cells); /particles/position [k,n,3] m, /particles/velocity [k,n,3] m/s,
 *   /particles/angular_velocity [k,n,3] rad/s (that of the sphere's body);
 *   /clusters/position [k,c,3] m, /clusters/orientation [k,c,4] (quaternion w x y z) when
 *   there are clusters;
 *   /walls/force [k,w,3] N (force ON each wall: planes, meshes, net; names in attribute
 *   "walls"); /energy/kinetic [k] J;
 *   coupled runs: /net/edges [e,2] i32, /net/node_ids [nn] i32, /net/position [j,nn,3] m,
 *   /net/force [j,nn,3] N (the net wall's nodes; row 0 is output step first_output_step,
 *   an attribute of /net).
 * particles.xdmf holds the spheres (Polyvertex, attributes radius, id, velocity,
 * angular_velocity), dem_net.xdmf the net wall (Polyline, contact_force); both are XDMF 3
 * temporal collections read by ParaView's default reader. The file is flushed after every
 * output step and the XDMF files are rewritten (temp file + rename), so all stay valid if
 * the run is stopped.
 */
#ifndef DEM_OUTPUT_H
#define DEM_OUTPUT_H

#include "dem_sim.h"
#include "nc_h5.h"

typedef struct dem_text {
    char *data;
    size_t len, cap;
} dem_text;

typedef struct dem_output {
    nc_h5_file h5;
    char dir[512];
    nc_h5_series time, wall_force, kinetic, pos, vel, omega, cl_pos, cl_quat, net_pos, net_force;
    long n_out;
    long net_rows;         /* rows of /net/position */
    size_t n_clusters;
    int net_written;       /* /net/edges written */
    size_t net_nodes, net_edges;
    double *scratch;       /* max(4 per body, 3 per sphere) */
    dem_text xdmf_particles, xdmf_net; /* formatted grids of every output step so far */
} dem_output;

int dem_output_open(dem_output *o, const dem_sim *s, const char *dir, nc_error *err);
/* net_force: the nodal forces of the last coupling step (3 per node) or NULL. */
int dem_output_write(dem_output *o, const dem_sim *s, const double *net_force, nc_error *err);
void dem_output_close(dem_output *o);

#endif
