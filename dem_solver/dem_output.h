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
 * temporal collections read by ParaView's default reader. The series' rows wait in memory and
 * dem.h5 is written at the first output step, then at an output step a fraction of a second
 * of wall time after its last write (nc_h5_flush_due), at a checkpoint (dem_output_sync) and
 * by dem_output_flush; only then do the XDMF files grow in place by the grids of the steps
 * written (nc_xdmf.h), so all stay valid if the run is stopped or killed, holding the steps
 * of the last write.
 *
 * dem_output_open() only prepares the writer: dem.h5 is created (truncating) by the first
 * dem_output_write(), so a coupled participant touches no result file before its first
 * BEGIN_STEP; dem_output_resume() instead reopens the files of a run continued from a
 * checkpoint (protocol/README.md §3.3): every series is cut back to the rows the checkpoint
 * counted (n_out, net_rows), the XDMF files are written again for exactly those rows, and
 * later output is appended.
 */
#ifndef DEM_OUTPUT_H
#define DEM_OUTPUT_H

#include "dem_sim.h"
#include "nc_h5.h"
#include "nc_xdmf.h"

typedef struct dem_text {
    char *data;
    size_t len, cap;
} dem_text;

typedef struct dem_output {
    nc_h5_file h5;
    char dir[512];
    nc_h5_series time, wall_force, kinetic, pos, vel, omega, cl_pos, cl_quat, net_pos, net_force;
    int created;           /* dem.h5 created or reopened */
    long n_out;
    long net_rows;         /* rows of /net/position */
    size_t n_clusters;
    int net_written;       /* /net/edges written */
    size_t net_nodes, net_edges;
    double *scratch;       /* max(4 per body, 3 per sphere) */
    dem_text xdmf_particles, xdmf_net; /* the grids of the steps not yet written (on resume
                                          * all the checkpoint's steps) */
    nc_xdmf_file particles_xdmf, net_xdmf;
} dem_output;

/* Prepares writing into the folder dir (which must exist and be writable); creates no file. */
int dem_output_open(dem_output *o, const dem_sim *s, const char *dir, nc_error *err);
/* Reopens dir/dem.h5 as it was at a checkpoint whose counters o->n_out, o->net_rows and
 * o->net_written were loaded (dem_checkpoint_load); nothing to open when n_out is 0. */
int dem_output_resume(dem_output *o, const dem_sim *s, nc_error *err);
/* Writes the rows waiting in memory to dem.h5 and their grids to the XDMF files (a run calls
 * it before its verdict, so that a full disk fails the run). */
int dem_output_flush(dem_output *o, nc_error *err);
/* dem_output_flush, then dem.h5 to the disk (fsync): the rows a checkpoint counts survive a
 * crash. */
int dem_output_sync(dem_output *o, nc_error *err);
/* net_force: the nodal forces of the last coupling step (3 per node) or NULL. */
int dem_output_write(dem_output *o, const dem_sim *s, const double *net_force, nc_error *err);
void dem_output_close(dem_output *o);

#endif
