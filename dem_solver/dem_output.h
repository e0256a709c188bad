/* dem_output — results of a DEM run: DIR/dem.h5 and DIR/dem.xdmf.
 *
 * dem.h5: /particles/{id,radius,body,material} (fixed), /time (series), /walls/force (series,
 * steps × walls × 3, force ON each wall: planes, meshes, net), /energy/kinetic (series) and per
 * output step k a group /steps/<k, 6 digits>/ with position, velocity, angular_velocity
 * (n × 3), cluster_position (c × 3) and cluster_orientation (c × 4, quaternion w x y z) when
 * there are clusters, and net_position / net_force (nodes × 3) in coupled runs (net edges in
 * /net/edges). The file is flushed after every output step; dem.xdmf is rewritten completely
 * (temp file + rename) after every output step, so both stay valid if the run is stopped.
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
    nc_h5_series time, wall_force, kinetic;
    long n_out;
    double *times;
    size_t times_cap;
    int net_written;       /* /net/edges written */
    size_t net_nodes, net_edges;
    int *has_net;          /* per output step: 1 when the net was written */
    double *scratch;       /* 4 per body: cluster output */
    dem_text xdmf_particles, xdmf_net; /* formatted grids of every output step so far */
} dem_output;

int dem_output_open(dem_output *o, const dem_sim *s, const char *dir, nc_error *err);
/* net_force: the nodal forces of the last coupling step (3 per node) or NULL. */
int dem_output_write(dem_output *o, const dem_sim *s, const double *net_force, nc_error *err);
void dem_output_close(dem_output *o);

#endif
