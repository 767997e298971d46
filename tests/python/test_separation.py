"""Python binding: numpy in and out, same numbers as the library, errors as trueaxis.Error."""
import numpy as np
import pytest

import trueaxis


def test_separate_recovers_truth_noise_free():
    sim = trueaxis.simulate_straightness(stations=150, offsets=[0, 10, 20], seed=4, angle=True)
    r = trueaxis.separate(sim["x"], sim["readings"], offsets=sim["offsets"], angle=sim["angle"])
    assert r["method"] == "lsq"
    assert "parabola" not in r["unobservable"]
    t = sim["truth"]
    # Workpiece truth on the result grid, residual from its LS line.
    idx = np.rint((r["workpiece"]["x"] - t["x"][0]) / 10).astype(int)
    w = t["workpiece"][idx]
    xw = r["workpiece"]["x"]
    w = w - np.polyval(np.polyfit(xw, w, 1), xw)
    assert isinstance(r["workpiece"]["value"], np.ndarray)
    assert np.max(np.abs(r["workpiece"]["value"] - w)) < 1e-9  # µm


def test_methods_and_straightness_values():
    sim = trueaxis.simulate_straightness(stations=80, offsets=[0, 10, 20], seed=2)
    b = trueaxis.separate(sim["x"], sim["readings"], method="three-point", sigma=0.1)
    assert b["pitch"] is not None and len(b["pitch"]["value"]) == 79
    assert b["workpiece"]["uncertainty"] is not None
    s = trueaxis.straightness(b["workpiece"]["x"], b["workpiece"]["value"])
    assert s["ls"] == pytest.approx(b["straightness"]["workpiece"]["ls"], rel=1e-12)
    assert s["min_zone"] <= s["ls"] + 1e-12
    # Three probes at 0.1 um noise over 80 stations do not resolve the profile: said, with U.
    w = b["straightness"]["workpiece"]
    # U = 2 z max u, z = inverse normal at 1 - 0.025/n (Bonferroni over the n points).
    from statistics import NormalDist
    z = NormalDist().inv_cdf(1 - 0.025 / len(b["workpiece"]["x"]))
    assert w["U_um"] == pytest.approx(2 * z * np.max(b["workpiece"]["uncertainty"]), rel=1e-6)
    assert w["resolved"] is (w["U_um"] < w["min_zone"])
    # No offsets given: taken as the step, and the result says so.
    assert b["offsets"] == [0, 10, 20] and b["offsets_assumed"] is True
    assert any("offsets were not stated" in m for m in b["warnings"])
    # Noise-free redundant readings: no uncertainty, and the reason, never a zero.
    q = trueaxis.simulate_straightness(stations=80, offsets=[0, 10, 30, 60], seed=2)
    r = trueaxis.separate(q["x"], q["readings"], offsets=q["offsets"])
    assert r["sigma"] is None
    assert r["straightness"]["workpiece"]["U_um"] is None
    assert r["straightness"]["workpiece"]["resolved"] is None
    assert r["no_uncertainty"].startswith("noise-free input")


def test_errors_are_trueaxis_errors():
    x = np.arange(5) * 10.0
    with pytest.raises(trueaxis.Error, match="uneven step"):
        trueaxis.separate(np.array([0, 10, 25, 30, 40.0]), np.zeros((5, 3)))
    with pytest.raises(trueaxis.Error, match="chain offsets"):
        trueaxis.separate(np.arange(60) * 10.0, np.random.default_rng(1).normal(size=(60, 3)), offsets=[0, 20, 40])
    with pytest.raises(ValueError):
        trueaxis.separate(x, np.zeros((5, 2)), method="four-point")


def test_analyze_layout_names_what_a_layout_cannot_see():
    ok = trueaxis.analyze_layout([0, 2, 3, 5])
    assert ok["observable"] and ok["extra_null_modes"] == 0
    assert "line" in ok["unobservable"] and "parabola" in ok["unobservable"]
    chains = trueaxis.analyze_layout([0, 2, 4])
    assert not chains["observable"]
    assert "chain offsets (2 chains)" in chains["unobservable"]
    assert "no common factor" in chains["message"]
    # A level removes the parabola from the undetermined modes.
    assert "parabola" not in trueaxis.analyze_layout([0, 1, 2], angle=True)["unobservable"]
