/* fem_run — the two ways the FEM program runs: standalone (static load steps or a dynamic
 * run to end_time with the model's own loads) and coupled (serving the netcouple protocol
 * as participant "fem"). A static load step whose Newton iteration fails or meets a singular
 * matrix is solved again by pseudo-time steps (fem_analysis_settle); a dynamic run starts
 * from the reference state or, with analysis.initial_state "static", at rest in its static
 * equilibrium (fem_run_initial_state), and a coupled one then gives the interface from there.
 *
 * Both write DIR/fem.h5 + DIR/fem.xdmf (fem_output.h), check *stop between steps (set by
 * the program's signal handler) and then finish cleanly: the results written so far are
 * flushed and closed. The coupled run creates them at the first BEGIN_STEP, or reopens them
 * on RESUME (fem_coupled.c); never before, so that a resumed run finds them intact.
 * Return 0 on success, 1 when stopped by *stop, -1 on error (err).
 */
#ifndef FEM_RUN_H
#define FEM_RUN_H

#include <signal.h>
#include "fem_model.h"
#include "fem_analysis.h"
#include "fem_output.h"

typedef struct fem_run_summary {
    long steps;                 /* steps or load increments done */
    long newton_iterations;     /* total */
    long output_steps;
    double final_time_s;
    double max_displacement_m;  /* largest nodal |u| of the run (standalone; coupled: at the end) */
    double max_displacement_time_s; /* when it occurred (load factor for statics); -1 unknown */
    int max_displacement_node;  /* where; -1 unknown */
    int overloaded_elements;    /* elements whose axial force exceeded their set's
                                   breaking_load_n at some monitored step */
    fem_set_overload *overload; /* [n_sets] the caller's array (NULL: not wanted): each set's
                                   largest axial force and exceedance (fem_output_overload) */
    double wall_s;
    int failed_solves;          /* coupled: SOLVE commands answered with an error */
    int semidefinite_retries;   /* coupled: steps solved again with the semi-definite part of
                                   the interface linearisation after a Newton failure */
    int initial_iterations;     /* dynamic, analysis.initial_state "static": Newton
                                   iterations of the initial equilibrium (-1: none) */
    int initial_steps;          /* its pseudo-time steps */
    int settled_increments;     /* static: load increments whose Newton iteration failed,
                                   solved by pseudo-time steps instead (fem_analysis_settle) */
    double initial_max_displacement_m; /* its largest nodal |u| from the reference */
    int initial_max_displacement_node;
    int warm_start_fallbacks;   /* coupled: repeated solves whose Newton start from the
                                   previous solution failed, solved again from the start of
                                   the step (their failed iterations are in newton_iterations) */
    fem_stats stats;
} fem_run_summary;

/* The state a dynamic run starts from, in a freshly initialised analysis: the reference state
 * or, with analysis.initial_state "static", the static equilibrium under the loads at t = 0
 * (its iterations and largest displacement into sum); then a_0. A static analysis: nothing. */
int fem_run_initial_state(fem_analysis *s, fem_run_summary *sum, nc_error *err);

/* The runners below watch fem_analysis_settle (the initial equilibrium, and static
 * increments solved by pseudo-time steps) with `watch` (NULL: no progress), its stop flag
 * being the run's `stop`: a settling stopped by a signal fails with FEM_ERR_STOPPED. */
int fem_run_standalone(const fem_model *m, const char *output_dir,
                       const volatile sig_atomic_t *stop, const fem_settle_watch *watch,
                       fem_run_summary *summary, nc_error *err);

typedef struct fem_coupled_options {
    const char *endpoint;
    const char *endpoint_file;  /* NULL or a file to write the bound endpoint into */
    int idle_timeout_ms;        /* <= 0 waits forever */
    const fem_settle_watch *settle_watch; /* NULL: no progress while settling */
} fem_coupled_options;

int fem_run_coupled(const fem_model *m, const char *output_dir, const fem_coupled_options *opt,
                    const volatile sig_atomic_t *stop, fem_run_summary *summary,
                    nc_error *err);

#endif
