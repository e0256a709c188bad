/* fem_output — DIR/fem.h5 and DIR/fem.xdmf of a FEM run.
 *
 * Layout (SI; every dataset carries a "units" string attribute):
 *   /mesh/coordinates [n,3] m, /mesh/elements [m,2] i32, /mesh/element_set [m] i32,
 *   /mesh/reference_length [m] m, /mesh/support_nodes [r] i32 (nodes with a prescribed dof),
 *   /mesh/support_dofs [r,3] i32 (1 = that dof is prescribed);
 *   output steps (every output interval, and the static solution) as growing series
 *   /output/time [k] s (load factor for statics), /output/step [k] i32,
 *   /output/load_factor [k], /output/displacement, /output/velocity, /output/position
 *   (= coordinates + displacement) [k,n,3], /output/axial_force [k,m] N,
 *   /output/strain [k,m] (engineering strain (l - L0)/L0 of each element from the reference
 *   geometry), /output/reaction [k,r,3] N (force the support exerts on the net at each
 *   support node: F_int + M a + C v - loads on the prescribed dofs, 0 on free dofs);
 *   with element types that keep history (brakes): /output/element_stroke [k,m] m (plastic
 *   stroke) and /output/element_dissipated_energy [k,m] J, 0 for the other elements;
 *   every step /monitor/time [s], /monitor/node_ids [p] i32, /monitor/displacement and
 *   /monitor/velocity [s,p,3]. /output/displacement holds the run's largest |u| as
 *   attributes max_magnitude (m), max_time (s) and max_node, over every monitored step.
 * The file is flushed after every output step and fem.xdmf (XDMF 3, read by ParaView's
 * default reader) is rewritten via a temporary file and rename (at most every 2 s beyond
 * 200 output steps) so both stay readable if the run stops.
 * A run resumed from a checkpoint reopens the files (fem_output_reopen): the series are cut
 * back to the rows they held at the checkpoint, fem.xdmf is rewritten for those rows, and
 * later output is appended.
 */
#ifndef FEM_OUTPUT_H
#define FEM_OUTPUT_H

#include "fem_analysis.h"
#include "nc_h5.h"

typedef struct fem_output {
    nc_h5_file h5;
    nc_h5_series time, step, load, disp, vel, pos, axial, strain, reaction;
    nc_h5_series mon_time, mon_disp, mon_vel;
    nc_h5_series stroke, dissipated;   /* only with element history (has_history) */
    int has_history;
    char dir[512];
    int n_out;         /* output rows written (/output series) */
    long n_mon;        /* monitor rows written (/monitor series) */
    int cap;
    double *times;     /* output times, for the XDMF file */
    double *buf;       /* [3 max(n_nodes, n_elements)] scratch */
    double *force;     /* [3 max(n_nodes, n_elements)] scratch: force balance, strains */
    int n_support;
    int *support_nodes;
    int open;
    int xdmf_current;  /* the XDMF file lists every output step written */
    double last_xdmf_s;
    const fem_model *model;
    double max_u_m, max_u_time_s;   /* run maximum of |u| over the monitored steps */
    int max_u_node;                 /* -1 before the first step */
} fem_output;

/* Creates DIR/fem.h5 (truncating) with the mesh and empty series. */
int fem_output_open(fem_output *o, const fem_model *m, const char *dir, nc_error *err);
/* Reopens DIR/fem.h5 of a resumed run to append to it: n_out, times[0..n_out), n_mon and the
 * max |u| fields are those of the checkpoint (already set; times reserved with
 * fem_output_reserve_times); every series is cut back to them and fem.xdmf is rewritten.
 * o must not be open. */
int fem_output_reopen(fem_output *o, const fem_model *m, const char *dir, nc_error *err);
/* Room for count output times in o->times. */
int fem_output_reserve_times(fem_output *o, int count, nc_error *err);
/* Appends the monitor rows of the current state (call every step); tracks the largest |u|. */
int fem_output_monitor(fem_output *o, const fem_analysis *s, double time_s, nc_error *err);
/* Appends one full output step, flushes, rewrites the XDMF file. */
int fem_output_step(fem_output *o, const fem_analysis *s, double time_s, nc_error *err);
/* Support reactions of the current state into r [3 n_support] (N), load factor lambda. */
void fem_output_reactions(fem_output *o, const fem_analysis *s, double lambda, double *r);
void fem_output_close(fem_output *o);

#endif
