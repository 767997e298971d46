#!/usr/bin/env python3
"""Error-map correction from Python: the binding against a plain numpy copy of the same points and
against what a metrologist would otherwise use, same data, same run.

  /usr/bin/python3 benchmarks/peers_map.py [POINTS]   (default 10000000)

The map is the benchmark's 17 x 13 x 11 grid over 800 x 600 x 500 mm (benchmarks/map/
error_map_bench.cpp); the points are uniform in its box (1 mm inside). Timed, best of 5:
  * copy: np.copyto of the points into a second array (the memory floor: read and write once);
  * ErrorMap.correct(p): a new array returned (one copy into fresh memory, then x - e(x));
  * ErrorMap.correct(p, out=buf): into a reused array (what the C++ benchmark BM_Correct times:
    copy, then correct in place);
  * ErrorMap.correct(p, out=p): in place, no copy;
  * scipy RegularGridInterpolator (trilinear, the three components at once) and x - e(x), the
    peer (Debian's python3-scipy, benchmark-only).
Prints each time and its ratio to the copy. The binding is compared with the C++ path by the same
ratio from `trueaxis_bench --benchmark_filter='BM_Memcpy|BM_Correct$'` (see BENCHMARKS.md).
"""
import sys
import time

import numpy as np

import trueaxis as ta


def best(f, reps=5):
    t = []
    for _ in range(reps):
        t0 = time.perf_counter()
        f()
        t.append(time.perf_counter() - t0)
    return min(t)


def main():
    n = int(sys.argv[1]) if len(sys.argv) > 1 else 10_000_000
    x, y, z = np.linspace(0, 800, 17), np.linspace(0, 600, 13), np.linspace(0, 500, 11)
    X, Y, Z = np.meshgrid(x, y, z, indexing="ij")
    err_um = np.stack([10 * np.sin(X / 300), 10 * np.cos(Y / 250), 10 * np.sin(Z / 200 + X / 500)],
                      axis=-1)
    m = ta.ErrorMap(x, y, z, err_um)
    # 1 mm inside the box, so the repeated in-place correction (10 µm per pass) stays in the grid.
    p = np.random.default_rng(1).uniform([1, 1, 1], [799, 599, 499], (n, 3))
    buf = np.empty_like(p)
    work = p.copy()

    t_copy = best(lambda: np.copyto(buf, p))
    rows = [("numpy copy (baseline)", t_copy)]
    rows.append(("ErrorMap.correct(p), new array", best(lambda: m.correct(p))))
    rows.append(("ErrorMap.correct(p, out=buf)", best(lambda: m.correct(p, out=buf))))
    want = buf.copy()
    rows.append(("ErrorMap.correct(w, out=w), in place", best(lambda: m.correct(work, out=work))))
    try:
        from scipy.interpolate import RegularGridInterpolator
    except ImportError:
        RegularGridInterpolator = None
    if RegularGridInterpolator is not None:
        rgi = RegularGridInterpolator((x, y, z), err_um * 1e-3)
        t_peer = best(lambda: p - rgi(p), reps=2)
        rows.append(("scipy RegularGridInterpolator, p - e(p)", t_peer))
        sample = slice(0, min(n, 100_000))
        diff = np.abs(p[sample] - rgi(p[sample]) - want[sample]).max()
    print(f"{n} points, {p.nbytes / 1e6:.0f} MB")
    for name, t in rows:
        print(f"  {name:42s} {t * 1e3:9.1f} ms  {t / t_copy:6.1f}x copy")
    if RegularGridInterpolator is not None:
        print(f"  trueaxis vs scipy (first {sample.stop} points): max |difference| {diff:.2e} mm")


if __name__ == "__main__":
    main()
