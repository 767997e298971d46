#!/usr/bin/env python3
"""Straightness separation: trueaxis against what a metrologist would otherwise use, same data,
same run.

  /usr/bin/python3 benchmarks/peers_separation.py [STATIONS]   (default 1000000)

Peers (numpy/scipy from Debian's python3-numpy / python3-scipy, benchmark-only):
  * three-point: the same recurrence as two numpy cumulative sums (the patent's double summation),
    and the closing fit, vectorised;
  * lsq: the same least-squares system (3 probes at 0, h, 2h; pins at the workpiece's first, middle
    and last positions and two probe offsets) built as a scipy sparse matrix and solved by sparse
    LU (SuperLU) with the columns ordered station by station. The system is square here, so the LU
    solution is the least-squares one.

Prints the times (best of 3), the ratio peer time / trueaxis time (above 1: trueaxis is faster),
how far trueaxis's lsq profile is from the sparse direct solve after both are put in the same
reference (relative to the profile), and how far its per-point uncertainties are from the exact
propagation of every reading through that solve and reference (1000 stations: a dense Jacobian).
"""
import sys
import time

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

import trueaxis as ta


def best(f, reps=3):
    t = []
    out = None
    for _ in range(reps):
        t0 = time.perf_counter()
        out = f()
        t.append(time.perf_counter() - t0)
    return min(t), out


def line_residual(x, Y):
    """Y (a profile, or profiles as columns) less its least-squares line in x."""
    X = np.stack((np.ones_like(x), x - x.mean()), axis=1)
    return Y - X @ np.linalg.lstsq(X, Y, rcond=None)[0]


def lsq_system(n):
    """The system m_i(K) = w(K + i) + g(K) + i·θh(K) + o_i for i = 0, 1, 2 with the pins, as a
    sparse matrix (row 3K + i), and the positions of w(0..n+1) and g(0..n−1) among its unknowns."""
    Q = n + 2
    # Unknown order station by station: w(K), g(K), θh(K), then w(n), w(n+1), then o_1.
    def w(j):
        return 3 * j if j < n else 3 * n + (j - n)

    o1 = 3 * n + 2
    nv = o1 + 1
    pinned = {w(0), w(Q // 2), w(Q - 1)}
    rows, cols, vals = [], [], []
    K = np.arange(n)
    for i in range(3):
        r = 3 * K + i
        wcol = np.where(K + i < n, 3 * (K + i), 3 * n + (K + i - n))
        for c, v in ((wcol, 1.0), (3 * K + 1, 1.0), (3 * K + 2, float(i))):
            if v != 0:
                rows.append(r)
                cols.append(c)
                vals.append(np.full(n, v))
        if i == 1:
            rows.append(r)
            cols.append(np.full(n, o1))
            vals.append(np.ones(n))
    rows = np.concatenate(rows)
    cols = np.concatenate(cols)
    vals = np.concatenate(vals)
    keep = ~np.isin(cols, list(pinned))
    free = np.setdiff1d(np.arange(nv), list(pinned))
    newcol = -np.ones(nv, dtype=np.int64)
    newcol[free] = np.arange(free.size)
    A = sp.csc_matrix((vals[keep], (rows[keep], newcol[cols[keep]])), shape=(3 * n, free.size))
    return A, newcol[np.r_[np.arange(0, 3 * n, 3), 3 * n, 3 * n + 1]], newcol[1 : 3 * n : 3]


def sparse_lsq(m):
    """Solves the system by sparse LU; the pinned workpiece points are 0."""
    A, iw, ig = lsq_system(m.shape[0])
    b = (m - m.mean(axis=0)).reshape(-1)  # row 3K + i
    z = np.append(spla.spsolve(A, b, permc_spec="NATURAL"), 0.0)  # index −1: a pin
    return z[iw], z[ig]


def reported(x, xw, W, G):
    """The reference trueaxis states its lsq results in (residuals from each profile's LS line,
    the parabola three probes cannot see moved into the workpiece), applied to the columns of W
    (workpiece) and G (guide): a linear map, so it carries a Jacobian as well as a profile."""
    W, G = line_residual(xw, W), line_residual(x, G)
    xc = 0.5 * (x.min() + x.max())
    L = 0.5 * (x.max() - x.min())
    c = np.linalg.lstsq(np.vander((x - xc) / L, 3), G, rcond=None)[0][0]  # t² coefficients
    W = W + np.outer(((xw - xc) / L) ** 2, c)
    G = G - np.outer(((x - xc) / L) ** 2, c)
    return line_residual(xw, W), line_residual(x, G)


def lsq_uncertainty_check(n=1000, sigma=0.01):
    """trueaxis's per-point lsq uncertainties against the exact propagation of every reading
    through the sparse LU solve and the reference (the Jacobian from unit readings), relative to
    the largest."""
    d = ta.simulate_straightness(stations=n, step=1.0, offsets=[0, 1, 2], noise=sigma, seed=2)
    x, m = np.asarray(d["x"]), np.asarray(d["readings"])
    res = ta.separate(x, m, offsets=[0, 1, 2], method="lsq", sigma=sigma)
    A, iw, ig = lsq_system(n)
    # Unit readings, centred per probe as the solve centres them; reading (K, i) is row 3K + i.
    E = np.eye(3 * n).reshape(n, 3, 3 * n)
    E = (E - E.mean(axis=0)).reshape(3 * n, 3 * n)
    Z = np.vstack((spla.splu(A, permc_spec="NATURAL").solve(E), np.zeros((1, 3 * n))))
    xw = x[0] + np.arange(n + 2) * (x[1] - x[0])
    Jw, Jg = reported(x, xw, Z[iw], Z[ig])
    out = []
    for J, name in ((Jw, "workpiece"), (Jg, "guide")):
        u_lu = sigma * np.sqrt((J**2).sum(axis=1))
        u_ta = np.asarray(res[name]["uncertainty"])
        out.append(np.abs(u_ta - u_lu).max() / u_lu.max())
    return out


def main():
    n = int(sys.argv[1]) if len(sys.argv) > 1 else 1_000_000
    d = ta.simulate_straightness(stations=n, step=1.0, offsets=[0, 1, 2], noise=0.01, seed=1)
    x, m = np.asarray(d["x"]), np.asarray(d["readings"])  # mm, µm

    # Three-point: trueaxis's library path against the same recurrence in numpy.
    t_b, _ = best(lambda: ta.separate(x, m, offsets=[0, 1, 2], method="three-point"))

    def numpy_three_point():
        dA, dB, dC = (m[:, i] - m[0, i] for i in range(3))
        f = -2 * dA[1:-1] + dA[2:] + 2 * dB[:-2] - dC[:-2]
        X = np.concatenate(([0.0, 0.0], np.cumsum(np.cumsum(f))))
        k = np.arange(n, dtype=float)
        a = np.stack((k[2:], k[2:] * (k[2:] - 1) / 2), axis=1)
        ab = np.linalg.lstsq(a, -X[2:], rcond=None)[0]
        X += k * ab[0] + k * (k - 1) / 2 * ab[1]
        wv = dA - X
        return line_residual(x, wv), line_residual(x, X)

    t_np, _ = best(numpy_three_point)

    # lsq: trueaxis (with its per-point uncertainty, as the CLI and Python report it) against a
    # sparse LU of the same system (values only).
    t_c, res = best(lambda: ta.separate(x, m, offsets=[0, 1, 2], method="lsq", sigma=0.01))
    t_lu, (wv, gv) = best(lambda: sparse_lsq(m))
    xw = x[0] + np.arange(n + 2)
    wv, gv = (v[:, 0] for v in reported(x, xw, wv[:, None], gv[:, None]))
    w_ta = np.asarray(res["workpiece"]["value"])
    g_ta = np.asarray(res["guide"]["value"])
    scale = max(np.abs(w_ta).max(), 1e-300)

    print(f"stations: {n}")
    print(f"three-point: trueaxis {t_b * 1e3:8.1f} ms   numpy recurrence {t_np * 1e3:8.1f} ms"
          f"   ratio {t_np / t_b:5.2f}")
    print(f"lsq:         trueaxis {t_c * 1e3:8.1f} ms   scipy sparse LU   {t_lu * 1e3:8.1f} ms"
          f"   ratio {t_lu / t_c:5.2f}   (trueaxis includes per-point uncertainties)")
    print(f"lsq against sparse LU: workpiece {np.abs(w_ta - wv).max() / scale:.2e}, guide "
          f"{np.abs(g_ta - gv).max() / scale:.2e} of the profile")
    uw, ug = lsq_uncertainty_check()
    print(f"lsq uncertainty against the exact propagation through the sparse LU (1000 stations): "
          f"workpiece {uw:.2e}, guide {ug:.2e} of the largest")


if __name__ == "__main__":
    main()
