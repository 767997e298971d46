"""Python binding of error-tolerant scanning: numpy points on the simulated part's surface, the
event log as arrays, and the corrected design for the next part."""
import json
import os
import subprocess
from pathlib import Path

import numpy as np
import pytest

import trueaxis

DATA = Path(__file__).resolve().parent.parent / "data"
TRUEAXIS = os.environ.get("TRUEAXIS", "trueaxis")


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    d = tmp_path_factory.mktemp("scan")
    subprocess.run([TRUEAXIS, "design", "--step", str(DATA / "ippdme" / "ipp_simple.stp"),
                    "--section", "origin=0,0,37.5;normal=0,0,1;name=mid", "-o", str(d / "design.json"),
                    "-q"], check=True)
    subprocess.run([TRUEAXIS, "simulate", "part", "--design", str(d / "design.json"),
                    "--translate", "1.8,-1.1,0", "--bump", "mid.1,150,2,30", "--seed", "3",
                    "-o", str(d / "part.json"), "-q"], check=True)
    return d


def test_scan_returns_points_on_the_part_and_the_log(files):
    r = trueaxis.scan(str(files / "design.json"), str(files / "part.json"),
                      corrected_design=str(files / "design2.json"))
    assert r["ok"], r["summary"]
    outer, hole = r["sections"]
    assert outer["points"].shape[1] == 3 and outer["points"].shape == outer["normals"].shape
    assert np.max(np.abs(outer["truth_um"])) < 1e-6  # noise-free: on the true surface to round-off
    assert outer["autonomous_count"] == 1 and hole["autonomous_count"] == 0
    ev = r["events"]
    assert len(ev["t"]) == len(ev["event"]) == len(ev["decision"])
    assert np.all(np.diff(ev["t"]) >= 0)
    assert "design_spliced" in ev["event"]  # the bump's stretch, not the whole outline
    assert r["machine_time_s"]["total"] == pytest.approx(
        sum(s["machine_time_s"]["total"] for s in r["sections"]))
    # The next part of the batch, with the corrected design: no trajectory error.
    r2 = trueaxis.scan(str(files / "design2.json"), str(files / "part.json"))
    assert r2["ok"] and "trajectory_error" not in r2["events"]["event"]
    assert r2["machine_time_s"]["total"] < r["machine_time_s"]["total"] / 3


def test_scan_refuses_bad_options(files):
    with pytest.raises(trueaxis.Error, match="strategy 'fast'"):
        trueaxis.scan(str(files / "design.json"), str(files / "part.json"), strategy="fast")
    with pytest.raises(trueaxis.Error, match="pushing amount"):
        trueaxis.scan(str(files / "design.json"), str(files / "part.json"), pushing=2)
    bad = files / "bad.json"
    bad.write_text(json.dumps({"sections": []}))
    with pytest.raises(trueaxis.Error, match="no sections"):
        trueaxis.scan(str(bad), str(files / "part.json"))


def test_scan_on_a_cmm_with_geometric_errors(files):
    subprocess.run([TRUEAXIS, "simulate", "machine", "--seed", "4", "--positioning", "50",
                    "-o", str(files / "machine.json"), "-q"], check=True)
    r = trueaxis.scan(str(files / "design.json"), str(files / "part.json"),
                      machine=str(files / "machine.json"))
    assert r["ok"], r["summary"]
    # The points carry the machine's errors: microns off the true part, not round-off.
    worst = max(np.max(np.abs(s["truth_um"])) for s in r["sections"])
    assert 1 < worst < 100
