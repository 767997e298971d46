"""Python binding of the circular test (ISO 230-4): the same numbers as the command line, the
truth given back, save -> report round trip, refusals."""
import json
import os
import subprocess

import numpy as np
import pytest

import trueaxis

TRUEAXIS = os.environ.get("TRUEAXIS", "trueaxis")


def test_circular_from_python_and_from_the_command_line(tmp_path):
    servo = tmp_path / "servo.json"
    servo.write_text(json.dumps({"X": {"backlash_um": 4, "gain_per_s": 40},
                                 "Y": {"backlash_um": 2, "spike_um": 3, "spike_decay_deg": 6,
                                       "gain_per_s": 36}}))
    m = trueaxis.Machine.random(seed=5)
    trace, truth = trueaxis.simulate_circular(m, plane="XY", radius=100, feed=1000, servo=str(servo),
                                              noise=0.1, pivot_offset=[6, -4, 0], seed=2)
    assert len(trace["direction"]) == len(trace["angle_deg"]) == len(trace["deviation_um"]) > 7000
    assert truth["backlash_um"] == {"X": 4, "Y": 2}
    r = trueaxis.circular(trace, plane="XY", radius=100, feed=1000)
    d = r["diagnosis"]
    assert d["backlash.X"]["value"] == pytest.approx(4, abs=0.4)
    assert d["backlash.Y"]["value"] == pytest.approx(2, abs=0.4)
    assert d["lag_mismatch"]["value"] == pytest.approx(truth["lag_mismatch_ms"], rel=0.02)
    assert d["lag_mismatch"]["unit"] == "ms" and d["lag_mismatch"]["u"] > 0
    assert r["G_um"]["ccw"] > 0 and r["H_um"] > 0 and len(r["residual_um"]) == len(trace["angle_deg"])
    assert r["spike_decay_u_deg"] > 0 and "spike_decay_note" not in r  # Y's 3 µm spike over 6°
    assert r["spike_decay_deg"] == pytest.approx(6, abs=1.5)
    assert 0 < r["reversal_delay_resolution_deg"] < 0.2
    # The directions as a tuple or a numpy array of str: the same diagnosis.
    for directions in (tuple(trace["direction"]), np.array(trace["direction"])):
        again = trueaxis.circular(dict(trace, direction=directions), plane="XY", radius=100, feed=1000)
        assert again["diagnosis"]["backlash.X"]["value"] == d["backlash.X"]["value"]
    # The same trace as a file through the command line: the same figures.
    csv = tmp_path / "trace.csv"
    with open(csv, "w") as f:
        f.write("direction,angle_deg,deviation_um\n")
        for a, b, c in zip(trace["direction"], trace["angle_deg"], trace["deviation_um"]):
            f.write(f"{a},{repr(float(b))},{repr(float(c))}\n")
    out = tmp_path / "c.json"
    subprocess.run([TRUEAXIS, "circular", "-i", str(csv), "-o", str(out), "-q"], check=True)
    cli = json.load(open(out))
    assert cli["G_um"]["cw"] == pytest.approx(r["G_um"]["cw"], abs=1e-9)
    assert cli["diagnosis"]["backlash_um"]["X"]["value"] == pytest.approx(d["backlash.X"]["value"], abs=1e-6)
    # Saved from Python, drawn by the command line's report.
    saved = tmp_path / "py.json"
    trueaxis.save(r, saved)
    assert trueaxis.load(saved)["kind"] == "circular"
    page = tmp_path / "py.html"
    assert trueaxis.report(saved, page) == "circular"
    assert "polar plot" in page.read_text(encoding="utf-8")


def test_circular_refuses_what_is_not_a_test(tmp_path):
    with pytest.raises(trueaxis.Error, match="XY, YZ or ZX"):
        trueaxis.circular({"direction": ["ccw"], "angle_deg": [0], "deviation_um": [0]}, plane="XZ")
    with pytest.raises(trueaxis.Error, match="use 'ccw' or 'cw'"):
        trueaxis.circular({"direction": ["up"], "angle_deg": [0], "deviation_um": [0]})
    for bad in (b"ccw", "ccw ", "cẃ", 1):  # bytes, a trailing space, not ASCII, not text
        with pytest.raises(trueaxis.Error, match=r"direction\[1\] = .*use 'ccw' or 'cw'"):
            trueaxis.circular({"direction": ["cw", bad], "angle_deg": [0, 1], "deviation_um": [0, 0]})
    with pytest.raises(TypeError, match="sequence"):
        trueaxis.circular({"direction": 5, "angle_deg": [0], "deviation_um": [0]})
    with pytest.raises(trueaxis.Error, match="at least 36"):
        trueaxis.circular({"direction": ["ccw"] * 5, "angle_deg": list(range(5)), "deviation_um": [0] * 5})
    with pytest.raises(trueaxis.Error, match="directions"):
        trueaxis.simulate_circular(trueaxis.Machine.random(seed=1), directions="up")
    with pytest.raises(TypeError, match="did you mean 'radius'"):
        trueaxis.circular({}, radiuss=100)


def test_compensation_from_python_closes_the_loop(tmp_path):
    servo = tmp_path / "servo.json"
    servo.write_text(json.dumps({"X": {"backlash_um": 5}, "Y": {"backlash_um": 3}}))
    m = trueaxis.Machine.random(seed=7)
    trace, truth = trueaxis.simulate_circular(m, servo=str(servo), noise=0.05, sample_rate=25)
    r = trueaxis.circular(trace, compensation=str(tmp_path / "comp"), travel=(0, 600))
    c = r["compensation"]
    assert c["backlash_um"]["X"] == pytest.approx(r["diagnosis"]["backlash.X"]["value"])
    assert c["squareness_um_per_m"] == pytest.approx(r["diagnosis"]["squareness"]["value"])
    assert len(c["files"]) == 6 and os.path.exists(c["json"])
    after, left = trueaxis.simulate_circular(m, servo=str(servo), noise=0.05, sample_rate=25,
                                             compensation=c["json"])
    assert left["backlash_um"]["X"] == pytest.approx(5 - c["backlash_um"]["X"])
    assert left["backlash_um"]["Y"] == pytest.approx(3 - c["backlash_um"]["Y"])
    ra = trueaxis.circular(after)
    assert max(ra["G_um"].values()) < max(r["G_um"].values())
    with pytest.raises(trueaxis.Error, match="this test runs in YZ"):
        trueaxis.simulate_circular(m, plane="YZ", compensation=c["json"])
