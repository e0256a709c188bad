/* fem_element_ring — type "ring" (two-phase ring-net connection, fem_element_ring.c). */
#ifndef FEM_ELEMENT_RING_H
#define FEM_ELEMENT_RING_H

/* param layout: bending stiffness k_b (N/m), membrane stiffness k_m (N/m), elongation delta_m
 * at which the ring is stretched taut (m) */
enum { FEM_RING_KB, FEM_RING_KM, FEM_RING_DM };

/* Force (N) at elongation delta (m); *kt = dF/d delta. */
double fem_ring_force(const double *param, double delta_m, double *kt);

#endif
