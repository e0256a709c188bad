/* fem_element_post — type "post": a hinged strut of a barrier (a steel post between its
 * base hinge, a pinned support node, and its top, where the support ropes and guy ropes
 * attach). It is the truss of eqs. (8)–(12) that keeps compression whatever the set's
 * behaviour (fem_model_finalize sets it), so the post's compression and the ropes holding it
 * follow from statics; a two-node pin-ended member has no bending, which is what a hinged
 * post is. Reported with a negative axial force when in compression. */
#include "fem_element.h"
#include "fem_element_cable.h"
#include "fem_model.h"

static double post_pair(const fem_element_ctx *c, double f_l[3], double Kb[9], int *slack)
{
    const fem_model *m = c->m;
    const int e = c->first;
    double d[3];
    fem_cable_chord(c, d);
    return fem_cable_response(d, m->L0[e], m->EA[e], m->AS[e], 0, f_l, Kb, slack);
}

const fem_element_ops fem_element_post_ops = {
    .name = "post",
    .uses_section = 1,
    .pair_response = post_pair,
    .strain_energy = fem_cable_member_energy,   /* a truss stores what a cable does */
};
