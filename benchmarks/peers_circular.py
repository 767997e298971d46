#!/usr/bin/env python3
"""The circular test's analysis (trueaxis.circular: ISO 230-4 figures and the diagnosis, with the
spike decay and reversal delay searched) against numpy's lstsq of the same design matrix, same
trace, same run.

  /usr/bin/python3 benchmarks/peers_circular.py [SAMPLES_PER_SECOND]   (default 1000: 10⁵ samples)

Trace: a ballbar test on the virtual machine, R 100 mm at 750 mm/min, both directions, position
loops of 40 and 36 /s, backlash 3 and 5 µm, a 3 µm reversal spike on Y, 0.1 µm of noise (as in
benchmarks/circular/circular_bench.cpp). The peer solves only the final least squares, with the
decay and delay trueaxis found given to it (numpy's lstsq, SVD-based; the design matrix built
beforehand and not timed); trueaxis's time includes the figures G, F, H, the search of decay and
delay, the uncertainties and shares, and the conversion from and to Python. Prints both times,
the ratio numpy / trueaxis (above 1: trueaxis is faster) and how far the two backlash estimates are
apart.
"""
import json
import math
import os
import sys
import tempfile

import numpy as np

import trueaxis as ta
from peers_timing import best


def design(trace, radius, feed, decay_deg, delays_deg):
    """The diagnosis' columns as the header of include/trueaxis/circular/circular.hpp states them."""
    th = np.radians(np.asarray(trace["angle_deg"]))
    s = np.where(np.asarray(trace["direction"]) == "ccw", 1.0, -1.0)
    c, sn, v = np.cos(th), np.sin(th), feed / 60.0
    d = math.radians(decay_deg)
    da, db = (math.radians(x) for x in delays_deg)
    cols = [c, sn, np.ones_like(th), -radius / 2 * np.sin(2 * th), radius / 2 * np.cos(2 * th),
            s * v / 2 * np.sin(2 * th), c * c * sn, sn * sn * c,
            s / 2 * np.sign(np.sin(th - s * da)) * c, -s / 2 * np.sign(np.cos(th - s * db)) * sn]
    w = np.mod(th, 2 * np.pi)
    for axis in (0, 1):
        for direction in (1.0, -1.0):
            total = np.zeros_like(th)
            first = (0.0 if axis == 0 else np.pi / 2) + direction * (da if axis == 0 else db)
            for at in (first, first + np.pi):  # the axis' last two reversals
                dt = np.mod(w - at if direction > 0 else at - w, 2 * np.pi)
                total += np.exp(-dt / d)
            total *= np.abs(c if axis == 0 else sn)
            cols.append(np.where(s == direction, total, 0.0))
    return np.stack(cols, axis=1)


def main():
    rate = float(sys.argv[1]) if len(sys.argv) > 1 else 1000.0
    with tempfile.TemporaryDirectory() as tmp:
        servo = os.path.join(tmp, "servo.json")
        with open(servo, "w") as f:
            json.dump({"X": {"gain_per_s": 40, "backlash_um": 3},
                       "Y": {"gain_per_s": 36, "backlash_um": 5, "spike_um": 3}}, f)
        m = ta.Machine.random(seed=1)
        trace, truth = ta.simulate_circular(m, feed=750, servo=servo, noise=0.1, sample_rate=rate)
    n = len(trace["angle_deg"])
    t_ta, r = best(lambda: ta.circular(trace, feed=750), most=30)
    J = design(trace, 100.0, 750.0, r["spike_decay_deg"],
               (r["reversal_delay_deg"]["X"], r["reversal_delay_deg"]["Y"]))
    y = np.asarray(trace["deviation_um"]) * 1e-3
    t_np, sol = best(lambda: np.linalg.lstsq(J, y, rcond=None), most=30)
    beta = sol[0]
    diff = max(abs(beta[8] * 1e3 - r["diagnosis"]["backlash.X"]["value"]),
               abs(beta[9] * 1e3 - r["diagnosis"]["backlash.Y"]["value"]))
    print(f"{n} samples: trueaxis.circular {t_ta * 1e3:.1f} ms (everything), numpy lstsq "
          f"{t_np * 1e3:.1f} ms (the final solve only): ratio {t_np / t_ta:.2f}; backlash "
          f"estimates {diff:.2e} µm apart")


if __name__ == "__main__":
    main()
