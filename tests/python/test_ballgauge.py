"""Python binding of the ball-gauge map (spec 04), on files written by the CLI's simulator."""
import os
import subprocess

import numpy as np
import pytest

import trueaxis

TRUEAXIS = os.environ.get("TRUEAXIS", "trueaxis")  # ctest sets it; else the installed CLI


def test_ballgauge_map_and_correction(tmp_path):
    g, m, t = (str(tmp_path / n) for n in ("gauge.json", "meas.json", "truth.csv"))
    subprocess.run([TRUEAXIS, "simulate", "ballgauge", "--alignment", "ls", "--gauge", g,
                    "--measurements", m, "--truth", t, "-q"], check=True)
    r = trueaxis.ballgauge(g, m)
    assert r["error"].shape == (80, 3) and len(r["ball"]) == 80
    em = r["map"]
    assert em is not None and em.error.shape == (5, 4, 4, 3)
    # Noise-free: the first (least-squares aligned) placement's errors have zero mean.
    first = np.array([p == r["placement"][0] for p in r["placement"]])
    np.testing.assert_allclose(r["error"][first].mean(axis=0), 0, atol=1e-9)
    # Correction at a mapped node returns its nominal position (X = x − Δ(x)) up to the
    # interpolation between nearly coincident nodes.
    x = r["measured"][10]
    np.testing.assert_allclose(em.correct(x, clamp=True), r["nominal"][10], atol=2e-5)
    with pytest.raises(trueaxis.Error, match="meas.json"):
        trueaxis.ballgauge(g, m, min_points=50)
