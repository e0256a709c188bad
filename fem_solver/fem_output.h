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
 *   Per element set, over every monitored step (written at the end of the run; index k =
 *   element set k, as in /mesh/element_set): /element_sets/breaking_load [k] N (0: not given),
 *   /element_sets/peak_axial_force [k] N (the largest tensile axial force),
 *   /element_sets/peak_time [k] s (load factor for statics), /element_sets/peak_element [k]
 *   i32, /element_sets/exceeded_elements [k] i32 (elements whose force ever exceeded the
 *   breaking load), /element_sets/first_exceedance_time [k] s, and per element
 *   /element_sets/element_exceedance_time [m] s (first time above it; -1: never, no step);
 *   with a breaking load given, the root attribute overloaded_elements (their total) and,
 *   when it is > 0, the root string attribute overload (the warnings, one line per set).
 * The series' rows wait in memory, and fem.h5 is written at the first output step, then at
 * the end of the first step a fraction of a second of wall time after its last write
 * (fem_output_write_due), and by fem_output_flush; only then does fem.xdmf (XDMF 3, read by
 * ParaView's default reader) grow in place by the grids of the steps written (nc_xdmf.h), so both stay readable
 * if the run stops or is killed, holding the steps of the last write.
 * A run resumed from a checkpoint reopens the files (fem_output_reopen): the series are cut
 * back to the rows they held at the checkpoint, fem.xdmf is rewritten for those rows, and
 * later output is appended.
 */
#ifndef FEM_OUTPUT_H
#define FEM_OUTPUT_H

#include "fem_analysis.h"
#include "nc_h5.h"
#include "nc_xdmf.h"

/* One element set's largest axial force and breaking-load exceedance (fem_output_overload). */
typedef struct fem_set_overload {
    double breaking_load_n;   /* the set's breaking_load_n (0: not given, nothing exceeds) */
    double peak_n;            /* largest tensile axial force over the monitored steps (N) */
    double peak_time_s;       /* when (load factor for statics) */
    int peak_element;         /* where; -1: no step monitored (or no element in the set) */
    int exceeded;             /* elements whose axial force ever exceeded breaking_load_n */
    double first_time_s;      /* the first time one did; -1: none */
} fem_set_overload;

typedef struct fem_output {
    nc_h5_file h5;
    nc_h5_series time, step, load, disp, vel, pos, axial, strain, reaction;
    nc_h5_series mon_time, mon_disp, mon_vel;
    nc_h5_series stroke, dissipated;   /* only with element history (has_history) */
    int has_history;
    char dir[512];
    int n_out;         /* output rows appended (/output series; in fem.h5 once written) */
    int n_xdmf;        /* output rows fem.xdmf lists (written to fem.h5 before it lists them) */
    long n_mon;        /* monitor rows appended (/monitor series) */
    int cap;
    double *times;     /* output times, for the XDMF file */
    double *buf;       /* [3 max(n_nodes, n_elements)] scratch */
    double *force;     /* [3 max(n_nodes, n_elements)] scratch: force balance, strains */
    int n_support;
    int *support_nodes;
    int open;
    int finished;      /* fem_output_finish done: the file holds the run's summary */
    nc_xdmf_file xdmf; /* fem.xdmf, open from the first output step */
    const fem_model *model;
    double max_u_m, max_u_time_s;   /* run maximum of |u| over the monitored steps */
    int max_u_node;                 /* -1 before the first step */
    /* per element set and element over the monitored steps (fem_output_reserve_peaks) */
    double *peak_n, *peak_time_s;   /* [n_sets] largest axial force (N) and when */
    int *peak_element;              /* [n_sets] where; -1 before the first step */
    double *exceeded_s;             /* [n_elements] first time above the breaking load, -1 never */
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
/* Room for the per-set peaks and exceedance times of model m, as before the first step,
 * unless o has them already (open, reopen and the checkpoint's save and load call it). */
int fem_output_reserve_peaks(fem_output *o, const fem_model *m, nc_error *err);
/* Appends the monitor rows of the current state (call every step); tracks the largest |u|
 * and, from s->axial (current: fem_analysis_update_axial), each set's largest axial force
 * and the elements above their set's breaking_load_n. */
int fem_output_monitor(fem_output *o, const fem_analysis *s, double time_s, nc_error *err);
/* Appends one full output step (the first is written at once, with fem.xdmf). */
int fem_output_step(fem_output *o, const fem_analysis *s, double time_s, nc_error *err);
/* Call once per step, after its monitor and output rows: writes the rows waiting in memory
 * when NC_H5_FLUSH_INTERVAL_S passed since the last write (nc_h5_flush_due), then the grids
 * of the output steps written to fem.xdmf. With sparse output the monitor rows, which come
 * every step, would otherwise wait until the next output step. */
int fem_output_write_due(fem_output *o, nc_error *err);
/* Writes the rows waiting in memory to fem.h5 and their grids to fem.xdmf. */
int fem_output_flush(fem_output *o, nc_error *err);
/* The same with fem.h5 flushed to the disk (fsync): the rows a checkpoint counts survive a
 * crash of the machine. */
int fem_output_sync(fem_output *o, nc_error *err);
/* What a run writes last, before its verdict (a full disk fails the run): the largest |u|
 * (attributes of /output/displacement), /element_sets, then fem_output_flush. Once:
 * fem_output_close does it (errors ignored) when the run has not. */
int fem_output_finish(fem_output *o, nc_error *err);
/* Support reactions of the current state into r [3 n_support] (N), load factor lambda. */
void fem_output_reactions(fem_output *o, const fem_analysis *s, double lambda, double *r);
/* Each set's peak and exceedance so far into per_set [n_sets] (may be NULL); returns the
 * number of elements that exceeded their set's breaking_load_n. */
int fem_output_overload(const fem_output *o, const fem_model *m, fem_set_overload *per_set);
/* One line on set k of a set with a breaking load (no trailing newline): the warning when
 * elements exceeded it, else the largest force as a fraction of it (times as load factors
 * for statics). */
void fem_set_overload_text(const fem_model *m, int k, const fem_set_overload *r, char *out,
                           size_t size);
void fem_output_close(fem_output *o);

#endif
