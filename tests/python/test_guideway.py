"""Python binding of the five guideway errors against the virtual carriage's truth."""
import numpy as np
import pytest

import trueaxis

LAYOUT = [
    {"name": "a", "kind": "position", "position": [-60, 0, 0]},
    {"name": "b", "kind": "position", "position": [60, 0, 150]},
    {"name": "c", "kind": "position", "position": [0, 80, 300]},
]
NAMES = ("horizontal", "vertical", "pitch", "yaw", "roll")


def test_noise_free_carriage_is_recovered_to_round_off():
    m = trueaxis.Machine.random(seed=4)
    sim = trueaxis.simulate_guideway(m, LAYOUT, axis="x", positions=300)
    assert sim["readings"].shape == (300, 6)
    r = trueaxis.guideway(LAYOUT, sim["s"], sim["readings"])
    for name in NAMES:
        assert r["observable"][name]
        t = sim["truth"][name]
        np.testing.assert_allclose(r[name], t, atol=1e-12 * np.abs(t).max())


def test_coplanar_layout_reports_pitch_and_yaw_as_none():
    flat = [dict(d, position=[d["position"][0], d["position"][1], 50.0]) for d in LAYOUT]
    m = trueaxis.Machine.random(seed=2)
    sim = trueaxis.simulate_guideway(m, flat, positions=100)
    r = trueaxis.guideway(flat, sim["s"], sim["readings"])
    assert r["pitch"] is None and r["yaw"] is None
    assert not r["observable"]["pitch"] and r["observable"]["roll"]
    assert "pitch, yaw" in r["message"] and r["summary"]["pitch"] is None
    np.testing.assert_allclose(r["roll"], sim["truth"]["roll"], atol=1e-9)
    # Adding a lens (angle detector) restores them.
    lens = flat + [{"name": "f", "kind": "angle", "focal_length": 200}]
    sim = trueaxis.simulate_guideway(m, lens, positions=100)
    r = trueaxis.guideway(lens, sim["s"], sim["readings"])
    np.testing.assert_allclose(r["pitch"], sim["truth"]["pitch"], atol=1e-9)


def test_noisy_errors_within_their_uncertainty():
    m = trueaxis.Machine.random(seed=9)
    sim = trueaxis.simulate_guideway(m, LAYOUT, positions=3000, noise=0.2, seed=3)
    r = trueaxis.guideway(LAYOUT, sim["s"], sim["readings"], sigma=0.2)
    for name in NAMES:
        z = (r[name] - sim["truth"][name]) / r["uncertainty"][name]
        assert np.sqrt(np.mean(z**2)) == pytest.approx(1.0, abs=0.08), name
        pv = r["summary"][name]
        assert pv["resolved"] is (pv["U"] < pv["pv"]), name
    # Noise-free spots: no sigma and no uncertainty, with the reason (never 0).
    clean = trueaxis.simulate_guideway(m, LAYOUT, positions=100)
    q = trueaxis.guideway(LAYOUT, clean["s"], clean["readings"])
    assert q["sigma"] is None and q["uncertainty"]["roll"] is None
    assert q["summary"]["roll"]["U"] is None and q["summary"]["roll"]["resolved"] is None
    assert q["no_uncertainty"].startswith("noise-free input")


def test_bad_layouts_and_readings():
    dup = LAYOUT + [{"name": "a", "kind": "angle", "focal_length": 100}]
    with pytest.raises(trueaxis.Error, match="'a' is used twice"):
        trueaxis.guideway(dup, np.zeros(2), np.zeros((2, 8)))
    with pytest.raises(trueaxis.Error, match="unknown key 'colour'"):
        trueaxis.guideway([dict(LAYOUT[0], colour=1)] + LAYOUT[1:], np.zeros(2), np.zeros((2, 6)))
    with pytest.raises(trueaxis.Error, match="4 reading columns for 3 detectors"):
        trueaxis.guideway(LAYOUT, np.zeros(2), np.zeros((2, 4)))
    line = [dict(d, position=[0.0, 0.0, 100.0 * i]) for i, d in enumerate(LAYOUT)]
    with pytest.raises(trueaxis.Error, match="lie on one line"):
        trueaxis.guideway(line, np.zeros(2), np.zeros((2, 6)))
