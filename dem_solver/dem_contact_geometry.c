/* dem_contact_geometry — closest point on a segment and on a triangle (Voronoi regions). */
#include "dem_contact_geometry.h"

static double dot3(const double a[3], const double b[3])
{
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

static double dist2(const double a[3], const double b[3])
{
    double d[3] = {a[0] - b[0], a[1] - b[1], a[2] - b[2]};
    return dot3(d, d);
}

double dem_closest_on_segment(const double p[3], const double a[3], const double b[3],
                              double q[3], double *t)
{
    double ab[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
    double ap[3] = {p[0] - a[0], p[1] - a[1], p[2] - a[2]};
    double len2 = dot3(ab, ab);
    double s = len2 > 0.0 ? dot3(ap, ab) / len2 : 0.0;
    if (s < 0.0) s = 0.0;
    if (s > 1.0) s = 1.0;
    for (int k = 0; k < 3; k++) q[k] = a[k] + s * ab[k];
    *t = s;
    return dist2(p, q);
}

/* Ericson, Real-Time Collision Detection, 5.1.5, with the region reported. */
double dem_closest_on_triangle(const double p[3], const double a[3], const double b[3],
                               const double c[3], double q[3], dem_tri_feature *feature)
{
    double ab[3], ac[3], ap[3], bp[3], cp[3];
    for (int k = 0; k < 3; k++) {
        ab[k] = b[k] - a[k];
        ac[k] = c[k] - a[k];
        ap[k] = p[k] - a[k];
        bp[k] = p[k] - b[k];
        cp[k] = p[k] - c[k];
    }
    double d1 = dot3(ab, ap), d2 = dot3(ac, ap);
    if (d1 <= 0.0 && d2 <= 0.0) {
        for (int k = 0; k < 3; k++) q[k] = a[k];
        *feature = DEM_TRI_VERT0;
        return dist2(p, q);
    }
    double d3 = dot3(ab, bp), d4 = dot3(ac, bp);
    if (d3 >= 0.0 && d4 <= d3) {
        for (int k = 0; k < 3; k++) q[k] = b[k];
        *feature = DEM_TRI_VERT1;
        return dist2(p, q);
    }
    double vc = d1 * d4 - d3 * d2;
    if (vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0) {
        double v = d1 / (d1 - d3);
        for (int k = 0; k < 3; k++) q[k] = a[k] + v * ab[k];
        *feature = DEM_TRI_EDGE0;
        return dist2(p, q);
    }
    double d5 = dot3(ab, cp), d6 = dot3(ac, cp);
    if (d6 >= 0.0 && d5 <= d6) {
        for (int k = 0; k < 3; k++) q[k] = c[k];
        *feature = DEM_TRI_VERT2;
        return dist2(p, q);
    }
    double vb = d5 * d2 - d1 * d6;
    if (vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0) {
        double w = d2 / (d2 - d6);
        for (int k = 0; k < 3; k++) q[k] = a[k] + w * ac[k];
        *feature = DEM_TRI_EDGE2;
        return dist2(p, q);
    }
    double va = d3 * d6 - d5 * d4;
    if (va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0) {
        double w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
        for (int k = 0; k < 3; k++) q[k] = b[k] + w * (c[k] - b[k]);
        *feature = DEM_TRI_EDGE1;
        return dist2(p, q);
    }
    double denom = va + vb + vc;
    if (denom == 0.0) { /* degenerate triangle: fall back to vertex a */
        for (int k = 0; k < 3; k++) q[k] = a[k];
        *feature = DEM_TRI_VERT0;
        return dist2(p, q);
    }
    double v = vb / denom, w = vc / denom;
    for (int k = 0; k < 3; k++) q[k] = a[k] + ab[k] * v + ac[k] * w;
    *feature = DEM_TRI_FACE;
    return dist2(p, q);
}
