"""Python binding of the ball-gauge map, on files written by the CLI's simulator."""
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


def test_gauge_blocks_grid_and_parametric(tmp_path):
    g, m, t, lengths, model = (str(tmp_path / n) for n in (
        "gauge.json", "meas.json", "truth.csv", "lengths.csv", "model.json"))
    subprocess.run([TRUEAXIS, "simulate", "ballgauge", "--alignment", "ls", "--noise", "0.2",
                    "--gauge", g, "--measurements", m, "--truth", t, "--lengths", lengths, "-q"],
                   check=True)
    em = trueaxis.ballgauge(g, m)["map"]
    p = trueaxis.identify(g, m, stylus_offset=[0, 0, -100], output=model)
    assert "ECZ" in p["unobservable"] and p["rank"] < p["unknowns"]
    assert 0.05 < p["sigma"] < 0.3  # centre noise from 0.2 µm probing
    assert isinstance(p["machine"], trueaxis.Machine)
    # ISO 230-1 squareness with its expanded uncertainty, for every pair of axes.
    assert set(p["squareness_urad"]) == {"EC0Y", "EB0Z", "EA0Z"}
    assert all(u > 0 for u in p["squareness_U_urad"].values())
    assert set(p["straightness_um"]) == {"EYX", "EZX", "EXY", "EZY", "EXZ", "EYZ"}
    grid, par = trueaxis.verify_lengths(lengths, map=em, model=model)
    assert grid["correction"] == "grid" and par["correction"] == "parametric"
    # Independent numpy check of the numbers: before = |b − a| − nominal; after with the grid =
    # the same for the corrected end points.
    a = np.loadtxt(lengths, delimiter=",", skiprows=1)
    before = (np.linalg.norm(a[:, 3:6] - a[:, 0:3], axis=1) - a[:, 6]) * 1e3
    np.testing.assert_allclose(grid["before"], before, atol=1e-9)
    ca, cb = em.correct(a[:, 0:3]), em.correct(a[:, 3:6])
    after = (np.linalg.norm(cb - ca, axis=1) - a[:, 6]) * 1e3
    np.testing.assert_allclose(grid["after"], after, atol=1e-9)
    for r in (grid, par):
        assert r["after_stats"]["rms"] < 0.5 * r["before_stats"]["rms"]
        assert 0.5 < r["after_stats"]["rms"] / np.hypot(r["expected_after"], 0.25) < 1.5
    # The same lengths as an array; refusals.
    again = trueaxis.verify_lengths(a, map=em)[0]
    np.testing.assert_array_equal(again["after"], grid["after"])
    with pytest.raises(trueaxis.Error, match=r"shape \(105, 6\)"):
        trueaxis.verify_lengths(a[:, :6], map=em)
    with pytest.raises(trueaxis.Error, match="needs map= or model="):
        trueaxis.verify_lengths(a)
    with pytest.raises(trueaxis.Error, match="not a parametric model"):
        trueaxis.verify_lengths(a, model=g)
    with pytest.raises(trueaxis.Error, match="degree"):
        trueaxis.identify(g, m, stylus_offset=[0, 0, -100], degree=9)


def test_plate_campaign_with_a_horizontal_stylus(tmp_path):
    import json
    g, m, t = (str(tmp_path / n) for n in ("gauge.json", "meas.json", "truth.csv"))
    subprocess.run([TRUEAXIS, "simulate", "ballgauge", "--plate", "5x5", "--pitch", "100",
                    "--gauge", g, "--measurements", m, "--truth", t, "-q"], check=True)
    p = trueaxis.identify(g, m, stylus_offset=[0, 0, -100])
    # The upright plates, probed from both sides with the stylus turned horizontal, show the rolls
    # that the vertical stylus cannot.
    assert p["unobservable"] == []
    assert [s["placements"] for s in p["styli"]][:2] == [["XY low", "XY high"], ["XZ from -Y"]]
    np.testing.assert_array_equal(p["styli"][1]["offset"], [0, 100, 0])
    # From one side only, the Z scale and the ram's pitch and yaw cannot be told apart.
    d = json.load(open(m))
    d["placements"] = [q for q in d["placements"] if q["name"] not in ("XZ from +Y", "YZ from -X")]
    one = str(tmp_path / "one-side.json")
    json.dump(d, open(one, "w"))
    with pytest.raises(trueaxis.Error, match="cannot tell EZZ"):
        trueaxis.identify(g, one, stylus_offset=[0, 0, -100])


def test_a_wrong_touch_is_refused_or_left_out(tmp_path):
    import json
    g, m, t = (str(tmp_path / n) for n in ("gauge.json", "meas.json", "truth.csv"))
    subprocess.run([TRUEAXIS, "simulate", "ballgauge", "--noise", "0.5", "--gauge", g,
                    "--measurements", m, "--truth", t, "-q"], check=True)
    d = json.load(open(m))
    d["placements"][1]["balls"][7]["points"][3][0] += 11000  # one point 11 m off
    bad = str(tmp_path / "bad.json")
    json.dump(d, open(bad, "w"))
    with pytest.raises(trueaxis.Error, match="point 4 is .* mm off the sphere"):
        trueaxis.ballgauge(g, bad)
    r = trueaxis.ballgauge(g, bad, drop_outliers=True)
    assert len(r["dropped"]) == 1 and "point 4" in r["dropped"][0]
    clean = trueaxis.ballgauge(g, m)
    assert np.abs(r["error"] - clean["error"]).max() < 1.5  # um: one point fewer on one ball


def test_python_simulates_the_campaign_the_command_line_does(tmp_path):
    # The same campaign from Python and from the CLI: the same files, byte for byte.
    machine = trueaxis.Machine.random(seed=7)
    machine_file = str(tmp_path / "machine.json")
    subprocess.run([TRUEAXIS, "simulate", "machine", "--seed", "7", "-o", machine_file, "-q"],
                   check=True)
    py_files = {n: str(tmp_path / f"py-{n}") for n in ("gauge.json", "meas.json", "lengths.csv")}
    s = trueaxis.simulate_ballgauge(trueaxis.Machine.load(machine_file), gauge=py_files["gauge.json"],
                                    measurements=py_files["meas.json"], alignment="ls", noise=0.3,
                                    seed=4, lengths=py_files["lengths.csv"])
    cli_files = {n: str(tmp_path / f"cli-{n}") for n in ("gauge.json", "meas.json", "lengths.csv")}
    subprocess.run([TRUEAXIS, "simulate", "ballgauge", "--machine", machine_file, "--alignment", "ls",
                    "--noise", "0.3", "--seed", "4", "--gauge", cli_files["gauge.json"],
                    "--measurements", cli_files["meas.json"], "--lengths", cli_files["lengths.csv"],
                    "--truth", str(tmp_path / "t.csv"), "-q"], check=True)
    for n in py_files:
        assert open(py_files[n]).read() == open(cli_files[n]).read(), n
    assert s["lengths"] == py_files["lengths.csv"] and "40-ball frame gauge" in s["description"]
    # The truth: where each probed ball stood and the machine's error there, as the CLI's CSV.
    t = np.loadtxt(tmp_path / "t.csv", delimiter=",", skiprows=1)
    np.testing.assert_allclose(s["truth"]["centre"], t[:, 2:5], atol=1e-9)
    np.testing.assert_allclose(s["truth"]["error"], t[:, 5:8], atol=1e-9)
    assert s["truth"]["error"].shape == (120, 3)
    # What Python simulated, Python maps.
    r = trueaxis.ballgauge(s["gauge"], s["measurements"])
    assert r["map"] is not None and r["error"].shape == (80, 3)
    assert machine.summary() == trueaxis.Machine.random(seed=7).summary()
    # A plate; refusals.
    p = trueaxis.simulate_ballgauge(machine, gauge=str(tmp_path / "pg.json"),
                                    measurements=str(tmp_path / "pm.json"), plate="4x4", pitch=120)
    assert "4x4 ball plate at 120 mm pitch" in p["summary"]
    with pytest.raises(trueaxis.Error, match="ROWSxCOLUMNS"):
        trueaxis.simulate_ballgauge(machine, plate="four", gauge=str(tmp_path / "x.json"))
    with pytest.raises(trueaxis.Error, match="alignment"):
        trueaxis.simulate_ballgauge(machine, alignment="best", gauge=str(tmp_path / "x.json"))
    with pytest.raises(TypeError, match="did you mean 'noise'"):
        trueaxis.simulate_ballgauge(machine, nois=1)
