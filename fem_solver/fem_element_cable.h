/* fem_element_cable — the 2-node total-Lagrangian cable/truss element (eqs. (8)–(12), docs/equations.md).
 *
 * Everything is expressed through the current chord d = x_l - x_k: the element force on
 * node l is f_l = (A S_tot / L) d, on node k it is -f_l (eq. (8)), and the 6x6 tangent is
 * [Kb -Kb; -Kb Kb] with the 3x3 block Kb = (E A / L^3) d d^T + (A S_tot / L) I (eq. (9)).
 * A cable with S_tot < 0 is slack: no force and no stiffness. Mass (eq. (11)) is
 * [m11 I, m12 I; m12 I, m11 I] with m = rho A L: consistent m11 = m/3, m12 = m/6;
 * lumped m11 = m/2, m12 = 0.
 */
#ifndef FEM_ELEMENT_CABLE_H
#define FEM_ELEMENT_CABLE_H

/* Returns the axial force N = A S_tot l / L (0 when slack); fills f_l[3] and Kb[9]
 * (row-major). *slack is set to 1 for a cable in compression. */
double fem_cable_response(const double d[3], double L0, double EA, double AS_pre, int is_cable,
                          double f_l[3], double Kb[9], int *slack);

/* Mass coefficients of eq. (11): *m11 (node with itself) and *m12 (node with the other). */
void fem_cable_mass(double rhoA, double L0, int lumped, double *m11, double *m12);

struct fem_element_ctx;
struct fem_model;
/* The current chord d = x_l - x_k of a two-node member. */
void fem_cable_chord(const struct fem_element_ctx *c, double d[3]);
/* Strain energy of segment e (cable/truss law, the model's L0, EA, AS, is_cable) at the
 * squared current length l2. */
double fem_cable_energy(const struct fem_model *m, int e, double l2);
/* The same for a two-node member in its current position (the cable and post types). */
double fem_cable_member_energy(const struct fem_element_ctx *c);

#endif
