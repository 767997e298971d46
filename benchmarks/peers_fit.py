#!/usr/bin/env python3
"""Sphere and cylinder fits: trueaxis.fit against scipy.optimize.least_squares, same points, same
run.

  /usr/bin/python3 benchmarks/peers_fit.py [SIZES...]   (default 25 1000 100000 1000000)

Points: a hemisphere cap of a 25 mm ball at (400, 300, 200) mm with 0.5 µm noise (as in
benchmarks/geometry/fit_bench.cpp), and a Ø50 × 100 mm cylinder on a tilted axis with the same
noise. The peer is scipy's least_squares (Debian's python3-scipy, benchmark-only) with the
analytic Jacobian of the orthogonal distances, started like trueaxis from the algebraic fit
(sphere) or from the principal axis of the points (cylinder); method 'lm' (MINPACK) and 'trf'.
trueaxis's time includes what it returns and scipy's does not: the uncertainties, the 80-bit
polish and the residuals.

Prints the times (best of several runs), the ratio scipy / trueaxis (above 1: trueaxis is faster)
and how far the diameters are apart. The cylinder's ratio to the sphere fit of as many points is
the other figure of interest (target: at most 10).
"""
import sys

import numpy as np
from scipy.optimize import least_squares

import trueaxis as ta
from peers_timing import best


def sphere_points(n, rng):
    th = np.arccos(rng.uniform(0, 1, n))
    ph = 2 * np.pi * rng.uniform(0, 1, n)
    r = 12.5 + rng.normal(0, 0.5e-3, n)
    d = np.stack([np.sin(th) * np.cos(ph), np.sin(th) * np.sin(ph), np.cos(th)], axis=1)
    return np.array([400.0, 300, 200]) + r[:, None] * d


def cylinder_points(n, rng):
    a = np.array([0.1, 0.2, 1.0])
    a /= np.linalg.norm(a)
    e1 = np.cross(a, [1.0, 0, 0])
    e1 /= np.linalg.norm(e1)
    e2 = np.cross(a, e1)
    t = 100 * rng.uniform(0, 1, n)
    ph = 2 * np.pi * rng.uniform(0, 1, n)
    r = 25 + rng.normal(0, 0.5e-3, n)
    return (np.array([100.0, 50, 20]) + t[:, None] * a
            + r[:, None] * (np.cos(ph)[:, None] * e1 + np.sin(ph)[:, None] * e2))


def scipy_sphere(p, method):
    c0 = p.mean(axis=0)
    q = p - c0
    A = np.hstack([2 * q, np.ones((len(q), 1))])
    sol = np.linalg.lstsq(A, (q * q).sum(axis=1), rcond=None)[0]
    x0 = np.append(sol[:3], np.sqrt(sol[3] + sol[:3] @ sol[:3]))

    def res(x):
        return np.linalg.norm(q - x[:3], axis=1) - x[3]

    def jac(x):
        d = q - x[:3]
        rho = np.linalg.norm(d, axis=1)
        return np.hstack([-d / rho[:, None], -np.ones((len(q), 1))])

    s = least_squares(res, x0, jac=jac, method=method, xtol=1e-15, ftol=1e-15, gtol=1e-15)
    return 2 * s.x[3]


def scipy_cylinder(p, method):
    # Parameters: a point (x0, y0) in the plane normal to the start axis through the centroid,
    # the axis tilt (ax, ay) and the radius.
    c0 = p.mean(axis=0)
    q = p - c0
    w, v = np.linalg.eigh(q.T @ q)
    R = v[:, [0, 1, 2]]  # largest eigenvalue last: the axis of a long cylinder
    q = q @ R
    r0 = np.sqrt((q[:, :2] ** 2).sum(axis=1)).mean()
    x0 = np.array([0.0, 0, 0, 0, r0])

    def parts(x):
        a = np.array([x[2], x[3], 1.0])
        a /= np.linalg.norm(a)
        d = q - np.array([x[0], x[1], 0.0])
        radial = d - np.outer(d @ a, a)
        return a, d, radial, np.linalg.norm(radial, axis=1)

    def res(x):
        return parts(x)[3] - x[4]

    def jac(x):  # numerical in the tilt, analytic elsewhere would need the normalisation's chain
        eps = 1e-8
        J = np.empty((len(q), 5))
        for k in range(5):
            h = np.zeros(5)
            h[k] = eps
            J[:, k] = (res(x + h) - res(x - h)) / (2 * eps)
        return J

    s = least_squares(res, x0, jac=jac, method=method, xtol=1e-15, ftol=1e-15, gtol=1e-15)
    return 2 * s.x[4]


def main():
    sizes = [int(a) for a in sys.argv[1:]] or [25, 1000, 100000, 1000000]
    rng = np.random.default_rng(1)
    print(f"{'fit':9s} {'points':>8s} {'trueaxis':>11s} {'scipy lm':>11s} {'ratio':>6s} "
          f"{'scipy trf':>11s} {'ratio':>6s}  |d_ta - d_lm| mm")
    for n in sizes:
        sp = sphere_points(n, rng)
        cp = cylinder_points(n, rng)
        t_s, fs = best(lambda: ta.fit("sphere", sp), least=2)
        rows = [("sphere", t_s, fs["diameter"], lambda m: scipy_sphere(sp, m))]
        t_c, fc = best(lambda: ta.fit("cylinder", cp), least=2)
        rows.append(("cylinder", t_c, fc["diameter"], lambda m: scipy_cylinder(cp, m)))
        for name, t, d, peer in rows:
            t_lm, d_lm = best(lambda: peer("lm"), budget=1.0, most=10, least=2)
            t_trf, _ = best(lambda: peer("trf"), budget=1.0, most=10, least=2)
            print(f"{name:9s} {n:8d} {t * 1e3:9.3f}ms {t_lm * 1e3:9.3f}ms {t_lm / t:6.1f} "
                  f"{t_trf * 1e3:9.3f}ms {t_trf / t:6.1f}  {abs(d - d_lm):.1e}")
        print(f"{'':9s} {n:8d} cylinder / sphere fit of as many points: {t_c / t_s:.1f}")


if __name__ == "__main__":
    main()
