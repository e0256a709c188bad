/* dem_contact_geometry — closest points for the contact tests of eqs. (13)–(15): sphere against a
 * segment (net edge) and against a triangle, telling which feature (face, edge, vertex) holds
 * the closest point so that shared features can be counted once.
 */
#ifndef DEM_CONTACT_GEOMETRY_H
#define DEM_CONTACT_GEOMETRY_H

/* Closest point q on segment a-b to p; *t in [0,1] is its parameter (q = a + t (b - a)).
 * Returns the squared distance. */
double dem_closest_on_segment(const double p[3], const double a[3], const double b[3],
                              double q[3], double *t);

/* Feature of a triangle holding the closest point. */
typedef enum {
    DEM_TRI_FACE = 0,
    DEM_TRI_EDGE0 = 1, /* edge v0-v1 */
    DEM_TRI_EDGE1 = 2, /* edge v1-v2 */
    DEM_TRI_EDGE2 = 3, /* edge v2-v0 */
    DEM_TRI_VERT0 = 4,
    DEM_TRI_VERT1 = 5,
    DEM_TRI_VERT2 = 6
} dem_tri_feature;

/* Closest point q on triangle (a, b, c) to p and its feature; returns the squared distance. */
double dem_closest_on_triangle(const double p[3], const double a[3], const double b[3],
                               const double c[3], double q[3], dem_tri_feature *feature);

#endif
