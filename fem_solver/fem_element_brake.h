/* fem_element_brake — type "brake": the energy-dissipating device of a barrier's rope, a
 * two-node element with an elastic-plastic force-stroke law in its elongation
 * delta = l - L0 (l current, L0 reference node distance):
 *   elastic      F = k_e (delta - s_p)                      while F < F_y(s_p)
 *   plateau      F = F_y(s_p) = F_a + k_h s_p, s_p grows    (activation force F_a, hardening k_h)
 *   locked       s_p = s_max: F = k_e e up to F_y(s_max) = F_y,max, beyond it
 *                F = F_y,max + k_lock (e - F_y,max / k_e),  e = delta - s_max
 *   no compression: F = 0 (and no stiffness) when delta < s_p (a brake is in a rope); unloading is elastic.
 * History per member: [0] plastic stroke s_p (m), [1] dissipated energy (J), the plastic work
 * integral of F_y ds_p = F_a s_p + k_h s_p^2 / 2 accumulated step by step. */
#ifndef FEM_ELEMENT_BRAKE_H
#define FEM_ELEMENT_BRAKE_H

/* set->param layout */
enum { FEM_BRAKE_KE, FEM_BRAKE_FA, FEM_BRAKE_KH, FEM_BRAKE_SMAX, FEM_BRAKE_KLOCK };

/* The law: force (N) at elongation delta from the committed stroke sp0; *kt the tangent
 * dF/d delta (N/m), *sp the stroke at this elongation. */
double fem_brake_force(const double *param, double delta_m, double sp0_m, double *kt, double *sp);

#endif
