#!/usr/bin/python3
"""make_terrain.py — writes terrain.stl (ASCII STL) for cases/terrain_net and cases/terrain_curtain.

A heightfield triangulated on a 0.25 m grid, x in [-0.5, 8] m (downhill = +x), y in [-2.5, 2.5] m:
  - a 30 degree slope from z = 2.5 m at x = 0 down to z = 0 at x = 2.5/tan(30) = 4.33 m,
  - with a shallow channel 0.06 y^2 and bumps 0.03 sin(2.1 x) cos(1.3 y) on the slope (both
    symmetric in y, so a rock released at y = 0 rolls straight down),
  - then a flat run-out z = 0 (x > 4.33 m) where the nets stand.
The slope/run-out edge is smoothed over 0.5 m. Usage: /usr/bin/python3 make_terrain.py [OUT.stl]
"""
import math
import sys

TAN30 = math.tan(math.radians(30.0))
X_FOOT = 2.5 / TAN30


def height(x, y):
    # smooth "softplus" blend of the slope line and the flat run-out (0.5 m transition)
    s = (X_FOOT - x) * TAN30            # the slope plane, < 0 beyond the foot
    w = 0.15
    base = w * math.log1p(math.exp(s / w)) if s / w < 50 else s
    on_slope = min(1.0, max(0.0, base / 0.3))   # 0 on the run-out, 1 on the slope
    return base + on_slope * (0.06 * y * y + 0.03 * math.sin(2.1 * x) * math.cos(1.3 * y))


def main():
    out = sys.argv[1] if len(sys.argv) > 1 else "terrain.stl"
    h = 0.25
    xs = [-0.5 + i * h for i in range(int(round(8.5 / h)) + 1)]
    ys = [-2.5 + j * h for j in range(int(round(5.0 / h)) + 1)]
    z = [[height(x, y) for y in ys] for x in xs]
    tris = []
    for i in range(len(xs) - 1):
        for j in range(len(ys) - 1):
            a = (xs[i], ys[j], z[i][j]); b = (xs[i + 1], ys[j], z[i + 1][j])
            c = (xs[i + 1], ys[j + 1], z[i + 1][j + 1]); d = (xs[i], ys[j + 1], z[i][j + 1])
            tris += [(a, b, c), (a, c, d)]     # counter-clockwise seen from above: normal up
    with open(out, "w") as f:
        f.write("solid terrain\n")
        for p, q, r in tris:
            u = [q[k] - p[k] for k in range(3)]; v = [r[k] - p[k] for k in range(3)]
            n = [u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]]
            ln = math.sqrt(sum(c * c for c in n))
            f.write("  facet normal %.6f %.6f %.6f\n    outer loop\n" % tuple(c / ln for c in n))
            for P in (p, q, r):
                f.write("      vertex %.6f %.6f %.6f\n" % P)
            f.write("    endloop\n  endfacet\n")
        f.write("endsolid terrain\n")
    print("%s: %d triangles" % (out, len(tris)))


if __name__ == "__main__":
    main()
