/* cpl_energy — the coupled run's energy balance and the energy guard.
 *
 * Each participant reports with its SOLVE reply (cpl_energy_report, protocol/README.md §3)
 * its kinetic, elastic and potential energy at the end of the step and, over the step, the
 * work done on it across the interface, the work of its own external loads and the energy it
 * dissipated. Per accepted step the balance keeps:
 *   interface mismatch = W_fem + W_dem: the work the structure received from the coupling
 *       force (as the FEM integrates it) plus the work the moving net did on the particles
 *       (minus the averaged force times the wall's displacement increment). Zero for an
 *       energy-exact exchange; > 0 is energy the coupling itself created.
 *   created(n) = E(n) − E(0) − Σ W_ext, E = kinetic + elastic + potential of both sides: how
 *       far the coupled system's energy has risen above its start plus what external loads
 *       put in. The structure, the particles and their contacts are passive (conservative
 *       or dissipative), so a correct model keeps created <= 0; > 0 is energy the numerical
 *       model produced, wherever it came from (the coupling, an integrator, an unresolved
 *       contact). It does not depend on how the interface work and the dissipation are split
 *       between the two sides, but it is a lower bound: creation that physical damping
 *       removes again in the same run does not show (the mismatch and the dissipated terms
 *       are kept for that).
 *   input(n) = the largest kinetic + elastic energy of both sides reached in steps 0..n
 *       and at the start (E(0) less the potentials at the end of step 0; the potentials are
 *       left out: their zero is arbitrary; what falls is converted to kinetic or elastic
 *       energy, which is counted).
 *   closure(n) = created(n) + Σ D − Σ mismatch: zero when the reports are consistent (each
 *       side's balance closes; a check of the reports, not a guard).
 * The guard fires when created(n) > tol_rel · input(n) + tol_abs_j; the first such step is
 * kept (step, time) and the steps above the limit are counted. Without energy reports from
 * both participants the balance is unavailable (every value NAN) and the guard is off.
 */
#ifndef CPL_ENERGY_H
#define CPL_ENERGY_H

/* What one participant reports with a solve (all J); valid = 0: it did not report. */
typedef struct cpl_energy_report {
    int valid;
    double kinetic_j, elastic_j, potential_j;   /* at the end of the step */
    double interface_work_j;   /* work done on this participant across the interface */
    double external_work_j;    /* what its own loads put in over the step beyond the change
                                  of their potential (0 for constant loads) */
    double dissipated_j;       /* energy dissipated over the step */
    double numerical_j;        /* the integrator's share of it (information only; NAN when
                                  not reported) */
} cpl_energy_report;

/* A report with valid = 0 and NAN values. */
cpl_energy_report cpl_energy_report_none(void);

/* The balance after an accepted step (NAN when unavailable). */
typedef struct cpl_energy_record {
    int available;
    double fem_kinetic_j, fem_elastic_j, fem_potential_j;
    double dem_kinetic_j, dem_elastic_j, dem_potential_j;
    double fem_interface_work_j, dem_interface_work_j;   /* of the step */
    double interface_created_j;                          /* their sum, of the step */
    double fem_dissipated_j, dem_dissipated_j;           /* of the step */
    double fem_numerical_j;    /* of the step: the part of fem_dissipated_j the structure's
                                  integrator dissipated, not its damping or elements (NAN
                                  when the FEM does not say) */
    double external_work_j;                              /* of the step, both sides */
    double created_j;          /* accumulated, see above */
    double input_j;            /* reference energy of the guard */
    double limit_j;            /* tol_rel · input + tol_abs */
    double closure_j;          /* consistency of the reports, accumulated */
    int above;                 /* created_j > limit_j at this step */
} cpl_energy_record;

typedef struct cpl_energy_settings {
    double tol_rel;            /* share of the input energy the run may create (0.01) */
    double tol_abs_j;          /* absolute floor of the limit, J (1e-9) */
} cpl_energy_settings;

typedef struct cpl_energy {
    cpl_energy_settings s;
    int started, available;
    double e0_j;               /* total energy at the start (first report's start state) */
    double sum_mismatch_j, sum_fem_diss_j, sum_dem_diss_j, sum_ext_j;
    double input_j;
    double created_j, closure_j;  /* of the last accepted step */
    cpl_energy_report fem_last;   /* last FEM report (a skipped FEM solve keeps its state) */
    long above_steps;          /* accepted steps above the limit */
    long first_step;           /* first step above the limit, -1: none */
    double first_time_s;       /* its end time */
    double first_created_j, first_limit_j;
    double max_excess_j;       /* largest created − limit */
} cpl_energy;

void cpl_energy_settings_default(cpl_energy_settings *s);
void cpl_energy_init(cpl_energy *e, const cpl_energy_settings *s);
/* One accepted step [t, t + dt): fem may be NULL when the FEM was not solved in it (its
 * state stays, no work, no dissipation). Fills rec. */
void cpl_energy_step(cpl_energy *e, long step, double end_time_s, const cpl_energy_report *fem,
                     const cpl_energy_report *dem, cpl_energy_record *rec);

#endif
