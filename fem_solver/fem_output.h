/* fem_output — DIR/fem.h5 and DIR/fem.xdmf of a FEM run.
 *
 * Layout (all SI): /mesh/coordinates [n,3] f64, /mesh/elements [m,2] i32,
 * /mesh/element_set [m] i32; output steps (every output interval, and the static solution)
 * as growing series /output/time [k], /output/step [k] i32, /output/displacement [k,n,3],
 * /output/velocity [k,n,3], /output/position [k,n,3] (= coordinates + displacement),
 * /output/axial_force [k,m]; every step /monitor/time [s], /monitor/node_ids [p] i32,
 * /monitor/displacement [s,p,3], /monitor/velocity [s,p,3]. The file is flushed after every
 * output step and the XDMF file is rewritten (at most every 2 s beyond 200 output steps) (via a temporary file and rename) so both stay
 * readable if the run stops.
 */
#ifndef FEM_OUTPUT_H
#define FEM_OUTPUT_H

#include "fem_analysis.h"
#include "nc_h5.h"

typedef struct fem_output {
    nc_h5_file h5;
    nc_h5_series time, step, disp, vel, pos, axial;
    nc_h5_series mon_time, mon_disp, mon_vel;
    char dir[512];
    int n_out;
    int cap;
    double *times;     /* output times, for the XDMF file */
    double *buf;       /* [3 n_nodes] scratch */
    int open;
    int xdmf_current;  /* the XDMF file lists every output step written */
    double last_xdmf_s;
    const fem_model *model;
} fem_output;

int fem_output_open(fem_output *o, const fem_model *m, const char *dir, nc_error *err);
/* Appends the monitor rows of the current state (call every step). */
int fem_output_monitor(fem_output *o, const fem_analysis *s, double time_s, nc_error *err);
/* Appends one full output step, flushes, rewrites the XDMF file. */
int fem_output_step(fem_output *o, const fem_analysis *s, double time_s, nc_error *err);
void fem_output_close(fem_output *o);

#endif
