/* cpl_energy — energy balance of the accepted steps and the energy guard (cpl_energy.h). */
#include "cpl_energy.h"

#include <math.h>
#include <string.h>

cpl_energy_report cpl_energy_report_none(void)
{
    cpl_energy_report r = {0, NAN, NAN, NAN, NAN, NAN, NAN, NAN};
    return r;
}

void cpl_energy_settings_default(cpl_energy_settings *s)
{
    s->tol_rel = 0.01;
    s->tol_abs_j = 1e-9;
}

void cpl_energy_init(cpl_energy *e, const cpl_energy_settings *s)
{
    memset(e, 0, sizeof *e);
    e->s = *s;
    e->available = 1;
    e->fem_last = cpl_energy_report_none();
    e->first_step = -1;
    e->first_time_s = NAN;
    e->first_created_j = NAN;
    e->first_limit_j = NAN;
}

static double total(const cpl_energy_report *r)
{
    return r->kinetic_j + r->elastic_j + r->potential_j;
}

static void unavailable(cpl_energy_record *rec)
{
    double *fields[] = {&rec->fem_kinetic_j, &rec->fem_elastic_j, &rec->fem_potential_j,
                        &rec->dem_kinetic_j, &rec->dem_elastic_j, &rec->dem_potential_j,
                        &rec->fem_interface_work_j, &rec->dem_interface_work_j,
                        &rec->interface_created_j, &rec->fem_dissipated_j, &rec->dem_dissipated_j,
                        &rec->fem_numerical_j,
                        &rec->external_work_j, &rec->created_j, &rec->input_j, &rec->limit_j,
                        &rec->closure_j};
    for (size_t i = 0; i < sizeof fields / sizeof *fields; i++) *fields[i] = NAN;
    rec->available = 0;
    rec->above = 0;
}

void cpl_energy_step(cpl_energy *e, long step, double end_time_s, const cpl_energy_report *fem,
                     const cpl_energy_report *dem, cpl_energy_record *rec)
{
    /* a step without an FEM solve: the structure keeps its state, no work, no dissipation */
    cpl_energy_report f;
    if (fem) {
        f = *fem;
    } else {
        f = e->fem_last;
        f.interface_work_j = f.external_work_j = f.dissipated_j = 0.0;
        f.numerical_j = isfinite(f.numerical_j) ? 0.0 : NAN;
        if (!e->started) f.valid = 0;
    }
    if (!e->available || !f.valid || !dem->valid) {
        e->available = 0;
        unavailable(rec);
        return;
    }
    e->fem_last = f;
    if (!e->started) {
        /* the start state from the first step's balance of each side */
        e->e0_j = total(&f) - f.external_work_j - f.interface_work_j + f.dissipated_j +
                  total(dem) - dem->external_work_j - dem->interface_work_j + dem->dissipated_j;
        e->started = 1;
        /* the start state's kinetic + elastic energy counts as input too: a first step that
         * holds a whole impact (a rock that bounced within it) has already lost it. Its
         * potential is taken as at the step's end, so what fell in the step counts too. */
        e->input_j = fmax(e->input_j, e->e0_j - f.potential_j - dem->potential_j);
    }
    double mismatch = f.interface_work_j + dem->interface_work_j;
    e->sum_mismatch_j += mismatch;
    e->sum_fem_diss_j += f.dissipated_j;
    e->sum_dem_diss_j += dem->dissipated_j;
    e->sum_ext_j += f.external_work_j + dem->external_work_j;
    e->input_j = fmax(e->input_j, f.kinetic_j + f.elastic_j + dem->kinetic_j + dem->elastic_j);

    rec->available = 1;
    rec->fem_kinetic_j = f.kinetic_j;
    rec->fem_elastic_j = f.elastic_j;
    rec->fem_potential_j = f.potential_j;
    rec->dem_kinetic_j = dem->kinetic_j;
    rec->dem_elastic_j = dem->elastic_j;
    rec->dem_potential_j = dem->potential_j;
    rec->fem_interface_work_j = f.interface_work_j;
    rec->dem_interface_work_j = dem->interface_work_j;
    rec->interface_created_j = mismatch;
    rec->fem_dissipated_j = f.dissipated_j;
    rec->fem_numerical_j = f.numerical_j;
    rec->dem_dissipated_j = dem->dissipated_j;
    rec->external_work_j = f.external_work_j + dem->external_work_j;
    rec->created_j = total(&f) + total(dem) - e->e0_j - e->sum_ext_j;
    rec->input_j = e->input_j;
    rec->limit_j = e->s.tol_rel * e->input_j + e->s.tol_abs_j;
    rec->closure_j = total(&f) + total(dem) - e->e0_j - e->sum_ext_j + e->sum_fem_diss_j +
                     e->sum_dem_diss_j - e->sum_mismatch_j;
    e->created_j = rec->created_j;
    e->closure_j = rec->closure_j;
    rec->above = rec->created_j > rec->limit_j;
    if (rec->above) {
        e->above_steps++;
        if (e->first_step < 0) {
            e->first_step = step;
            e->first_time_s = end_time_s;
            e->first_created_j = rec->created_j;
            e->first_limit_j = rec->limit_j;
        }
        e->max_excess_j = fmax(e->max_excess_j, rec->created_j - rec->limit_j);
    }
}
