#!/usr/bin/env python3
"""Distortion of sphere quadtrees: cube-sphere mappings, HEALPix, latitude/longitude.

The table of docs/globe.md ("Quadtree on the sphere") is this script's output.
For the grid of cells at a few subdivision levels it measures:
  - area ratio: max / min area of the grid's cells (spherical quads, exact
    areas of the two spherical triangles, Van Oosterom & Strackee 1983);
  - edge ratio: longest edge / mean edge (how much finer than needed the
    mean cell must be so the coarsest cell reaches a target spacing);
  - cells for the same longest edge, relative to the equal-angle cube:
    a grid of C cells whose longest edge is E (rad) needs C (E / l)^2 cells
    for a longest edge l, so the ratio of C E^2 between two schemes;
  - skew: max |corner angle - 90 deg| over all cells (angles between the
    great-circle arcs to the two neighbouring corners);
and, in the continuum limit, the Tissot indicatrix of the mapping (the
singular values a >= b of its Jacobian, by central differences):
  - max / min of the area element a*b,
  - max angular distortion 2 asin((a - b) / (a + b)) (Snyder 1987, ch. 4).

Pure Python (no numpy), a few seconds. Symmetry: a cube face is computed in
one quadrant (its four quadrants are congruent); HEALPix on one northern and
one equatorial base pixel (the southern row mirrors the northern one).
"""
import math

# ----------------------------------------------------------------- geometry

def normalize(v):
    n = math.sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2])
    return (v[0] / n, v[1] / n, v[2] / n)


def dot(a, b):
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


def cross(a, b):
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


def triangle_area(a, b, c):
    # Spherical excess of a unit-sphere triangle: tan(E/2) = |a.(b x c)| / (1 + a.b + b.c + c.a).
    num = abs(dot(a, cross(b, c)))
    den = 1.0 + dot(a, b) + dot(b, c) + dot(c, a)
    return 2.0 * math.atan2(num, den)


def corner_angle(a, b, d):
    # Angle at corner a between the great-circle arcs a->b and a->d.
    ab, ad = dot(a, b), dot(a, d)
    t1 = (b[0] - ab * a[0], b[1] - ab * a[1], b[2] - ab * a[2])
    t2 = (d[0] - ad * a[0], d[1] - ad * a[1], d[2] - ad * a[2])
    c = dot(t1, t2) / math.sqrt(dot(t1, t1) * dot(t2, t2))
    return math.degrees(math.acos(max(-1.0, min(1.0, c))))


def arc(a, b):
    return math.acos(max(-1.0, min(1.0, dot(a, b))))

# ----------------------------------------------------------------- mappings
# Cube face +z, face coordinates (x, y) in [-1, 1]^2.

def gnomonic(x, y):  # tangent cube: the GPU cube map (Sadourny 1972)
    return normalize((x, y, 1.0))


def equal_angle(x, y):  # Ronchi, Iacono & Paolucci 1996
    q = math.pi / 4.0
    return normalize((math.tan(q * x), math.tan(q * y), 1.0))


def nowell(x, y):  # "spherified cube" (Nowell 2005)
    x2, y2, z2 = x * x, y * y, 1.0
    return (x * math.sqrt(max(0.0, 1.0 - y2 / 2 - z2 / 2 + y2 * z2 / 3)),
            y * math.sqrt(max(0.0, 1.0 - x2 / 2 - z2 / 2 + x2 * z2 / 3)),
            math.sqrt(max(0.0, 1.0 - x2 / 2 - y2 / 2 + x2 * y2 / 3)))


def s2_quadratic(x, y):  # Google S2's quadratic warp of a gnomonic face
    def warp(s):  # s in [-1, 1]; S2 writes it for s' = (s + 1) / 2
        t = 0.5 * (s + 1.0)
        return (4.0 * t * t - 1.0) / 3.0 if t >= 0.5 else (1.0 - 4.0 * (1.0 - t) ** 2) / 3.0
    return normalize((warp(x), warp(y), 1.0))


def healpix_plane_to_sphere(xs, ys):
    # Inverse HEALPix projection (Calabretta & Roukema 2007, eqs. for the
    # equatorial and polar zones); (xs, ys) in the projection plane.
    if abs(ys) <= math.pi / 4.0:
        z = 8.0 / (3.0 * math.pi) * ys
        phi = xs
    else:
        sigma = 2.0 - 4.0 * abs(ys) / math.pi
        z = math.copysign(1.0 - sigma * sigma / 3.0, ys)
        phi_c = (2.0 * math.floor(2.0 * xs / math.pi) + 1.0) * math.pi / 4.0
        phi = phi_c if sigma < 1e-12 else phi_c + (xs - phi_c) / sigma
    s = math.sqrt(max(0.0, 1.0 - z * z))
    return (s * math.cos(phi), s * math.sin(phi), z)


def healpix_base(xc, yc):
    # A base pixel: the diamond of centre (xc, yc) and half-diagonal pi/4;
    # (u, v) in [0, 1]^2 along its two edges from its southern corner.
    q = math.pi / 4.0

    def f(u, v):
        # mapped from [-1, 1]^2 like the cube faces
        u, v = 0.5 * (u + 1.0), 0.5 * (v + 1.0)
        xs = xc + q * (u - v)
        ys = yc - q + q * (u + v)
        return healpix_plane_to_sphere(xs, min(ys, math.pi / 2.0))
    return f


HEALPIX_NORTH = healpix_base(math.pi / 4.0, math.pi / 4.0)
HEALPIX_EQUATOR = healpix_base(math.pi / 2.0, 0.0)

# ----------------------------------------------------------------- measures

def grid_stats(f, n, lo=-1.0, hi=1.0):
    """Cells of an n x n grid over [lo, hi]^2 in face coordinates."""
    h = (hi - lo) / n
    pts = [[f(lo + i * h, lo + j * h) for i in range(n + 1)] for j in range(n + 1)]
    areas, edges, skew = [], [], 0.0
    for j in range(n):
        row, nxt = pts[j], pts[j + 1]
        for i in range(n):
            a, b, c, d = row[i], row[i + 1], nxt[i + 1], nxt[i]
            areas.append(triangle_area(a, b, c) + triangle_area(a, c, d))
            edges.extend((arc(a, b), arc(a, d)))
            for p, q, r in ((a, b, d), (b, c, a), (c, d, b), (d, a, c)):
                skew = max(skew, abs(corner_angle(p, q, r) - 90.0))
    return areas, edges, skew


def tissot(f, samples, lo=-1.0, hi=1.0):
    """Continuum limit: area element and angular distortion of f."""
    eps = 1e-6
    amin, amax, omega = float("inf"), 0.0, 0.0
    for j in range(samples + 1):
        for i in range(samples + 1):
            x = lo + (hi - lo) * (i + 0.5) / (samples + 1)  # interior points
            y = lo + (hi - lo) * (j + 0.5) / (samples + 1)
            px1, px0, py1, py0 = f(x + eps, y), f(x - eps, y), f(x, y + eps), f(x, y - eps)
            fx = [(px1[k] - px0[k]) / (2 * eps) for k in range(3)]
            fy = [(py1[k] - py0[k]) / (2 * eps) for k in range(3)]
            e, g, ff = dot(fx, fx), dot(fy, fy), dot(fx, fy)  # first fundamental form
            tr, det = e + g, max(e * g - ff * ff, 0.0)
            disc = math.sqrt(max(tr * tr / 4.0 - det, 0.0))
            a = math.sqrt(tr / 2.0 + disc)
            b = math.sqrt(max(tr / 2.0 - disc, 0.0))
            amin, amax = min(amin, a * b), max(amax, a * b)
            omega = max(omega, 2.0 * math.degrees(math.asin((a - b) / (a + b))))
    return amax / amin, omega


def main():
    cube = [("tangent (gnomonic)", gnomonic), ("equal-angle", equal_angle),
            ("spherified (Nowell)", nowell), ("S2 quadratic", s2_quadratic)]
    levels = (3, 5, 7)  # cells per base-face edge: 8, 32, 128
    rows = []  # (name, level, cells, area ratio, edge ratio, longest edge, skew)
    for name, f in cube:
        for level in levels:
            n = 2 ** level
            # one quadrant [0, 1]^2 of the face: n/2 x n/2 cells
            areas, edges, skew = grid_stats(f, n // 2, 0.0, 1.0)
            rows.append((name, level, 6 * n * n, max(areas) / min(areas),
                         max(edges) / (sum(edges) / len(edges)), max(edges), skew))
    for level in levels:
        n = 2 ** level
        a1, e1, s1 = grid_stats(HEALPIX_NORTH, n)
        a2, e2, s2 = grid_stats(HEALPIX_EQUATOR, n)
        areas, edges = a1 + a2, e1 + e2
        rows.append(("HEALPix", level, 12 * n * n, max(areas) / min(areas),
                     max(edges) / (sum(edges) / len(edges)), max(edges), max(s1, s2)))
    reference = {r[1]: r[2] * r[5] ** 2 for r in rows if r[0] == "equal-angle"}

    print("Cell grids at level L (2^L cells per base-face edge). Cube: 6*4^L cells; HEALPix: 12*4^L.")
    print("%-22s %3s %9s %12s %13s %10s %9s" % ("scheme", "L", "cells", "area max/min", "edge max/mean",
                                               "cells rel.", "skew deg"))
    for name, level, cells, area_ratio, edge_ratio, longest, skew in rows:
        print("%-22s %3d %9d %12.3f %13.3f %10.2f %9.2f" % (name, level, cells, area_ratio, edge_ratio,
                                                          cells * longest ** 2 / reference[level], skew))
    # Latitude-longitude quadtree (2 root tiles, Cesium's geographic scheme):
    # cells of 180/2^L degrees; rows next to the poles are triangles. Its
    # longest edge is an equatorial cell's, pi / 2^L.
    for level in levels:
        n_rows = 2 ** level
        dlat = math.pi / n_rows
        areas = [math.sin((k + 1) * dlat - math.pi / 2) - math.sin(k * dlat - math.pi / 2) for k in range(n_rows)]
        cells = 2 * n_rows * n_rows
        print("%-22s %3d %9d %12.1f %13s %10.2f %9s" % ("lat/lon (geographic)", level, cells,
                                                      max(areas) / min(areas), "-",
                                                      cells * dlat ** 2 / reference[level], "90 (poles)"))

    print()
    print("Continuum limit (Tissot indicatrix on a 60 x 60 sample grid per face / base pixel):")
    print("%-22s %14s %20s" % ("scheme", "area max/min", "max angular dist. deg"))
    for name, f in cube:
        r, w = tissot(f, 60, 0.0, 1.0)
        print("%-22s %14.3f %20.2f" % (name, r, w))
    r1, w1 = tissot(HEALPIX_NORTH, 60)
    r2, w2 = tissot(HEALPIX_EQUATOR, 60)
    print("%-22s %14.3f %20.2f" % ("HEALPix", max(r1, r2), max(w1, w2)))


if __name__ == "__main__":
    main()
