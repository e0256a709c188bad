#!/usr/bin/env python3
# apply_fix.py TREE: applies proposed_fix.patch by pattern to a copy of the repo (for when the
# dem_solver files moved on). The new test file comes from $NC_FIX_TEST.
# applies the coupling_force change to a tree given as argv[1] (idempotent-unsafe: run on a fresh copy)
import sys, os, re, shutil
root = sys.argv[1]
def edit(rel, old, new, regex=False):
    p = os.path.join(root, rel); s = open(p).read()
    if regex:
        s2, n = re.subn(old, new, s, count=1, flags=re.S)
        assert n == 1, (rel, old[:60])
    else:
        assert old in s, (rel, old[:60]); s2 = s.replace(old, new, 1)
    open(p, 'w').write(s2)
edit('dem_solver/dem_model.h', """    double near_distance_m;/* "near_interface" threshold on the surface gap */
""", """    double near_distance_m;/* "near_interface" threshold on the surface gap */
    int force_at_end;      /* coupled reply: 0 the time-averaged force of the step (impulse/dt),
                              1 the force of the last sub-step (wall at its end position) */
""")
edit('dem_solver/dem_config.c', """"restitution", "cable_radius_m", "near_distance_m", NULL};
    const cJSON *w;""", """"restitution", "cable_radius_m", "near_distance_m",
                                       "coupling_force", NULL};
    static const char *const force_kinds[] = {"average", "end_of_step", NULL};
    const cJSON *w;""")
edit('dem_solver/dem_config.c', r"""(nc_json_number_range_opt\(w, where, "near_distance_m", [^\n]*err\))\)\n        return -1;""",
     r"""\1 ||
        nc_json_choice_opt(w, where, "coupling_force", force_kinds, 0, &n->force_at_end, err))
        return -1;""", regex=True)
edit('dem_solver/dem_solver.c', r"""    for \(size_t k = 0; k < 3 \* nn; k\+\+\) force_out\[k\] = net->impulse\[k\] / dt_step;\n""",
"""    if (net->force_at_end) {
        /* The force of the last sub-step, whose wall is at its end-of-step position (see the
         * loop above): the load at t_n+1 that a structure with equilibrium at t_n+1 (Newmark,
         * Bossak) needs, and the force the particles received last. The step average stands
         * for the middle of the step: applied as the t_n+1 load it lags the wall by about
         * dt/2, a delayed contact spring that pumps energy into a light net
         * (scripts/diagnostics/rest_position.md). After a free flight nothing touches the net
         * and net->force is zero. */
        memcpy(force_out, net->force, 3 * nn * sizeof(double));
    } else {
        for (size_t k = 0; k < 3 * nn; k++) force_out[k] = net->impulse[k] / dt_step;
    }
""", regex=True)
edit('dem_solver/dem_solver.h', """ * nodes (impulse / dt_step). vel_end""", """ * nodes (impulse / dt_step), or with net.force_at_end (net_wall.coupling_force
 * "end_of_step") the force of the last sub-step, wall at its end position. vel_end""")
edit('dem_solver/README.md', r"""(\| `near_distance_m` \|[^\n]*\n)""", r"""\1| `coupling_force` | `"average"` or `"end_of_step"` | – | `"average"` | force in the SOLVE reply: the time average over the step (impulse / dt), or the force of the last sub-step, in which the wall is at its end-of-step position (the force at t_n+1). Use `"end_of_step"` with a structure whose equilibrium is written at t_n+1 (Newmark, Bossak): the average, applied as the load at t_n+1, lags the wall by about dt/2 and pumps energy into a light net (see `scripts/diagnostics/rest_position.md`) |
""", regex=True)
shutil.copy(os.environ.get('NC_FIX_TEST', '/tmp/nc_patch/tests/dem_solver/test_coupling_force.c'), os.path.join(root, 'tests/dem_solver/test_coupling_force.c'))
print("applied")
