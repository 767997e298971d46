"""trueaxis.design and trueaxis.simulate_part make the scanning inputs `trueaxis design` and
`trueaxis simulate part` make (the same files), and refuse what cannot be one."""
import filecmp
import json
import os
import pathlib
import subprocess

import pytest

import trueaxis

TRUEAXIS = os.environ.get("TRUEAXIS", "trueaxis")
STEP = pathlib.Path(__file__).resolve().parents[1] / "data" / "ippdme" / "ipp_simple.stp"


def cli(*args):
    r = subprocess.run([TRUEAXIS, *map(str, args)], capture_output=True, text=True, timeout=300)
    return r


def test_design_and_part_are_the_files_the_command_line_makes(tmp_path):
    py, sh = tmp_path / "py", tmp_path / "sh"
    py.mkdir()
    sh.mkdir()
    d = trueaxis.design(STEP, [{"origin": (0, 0, 37.5), "normal": (0, 0, 1), "name": "mid"},
                               {"origin": (50, 50, 25), "normal": (1, 0, 0), "name": "x",
                                "probe": (90, -90)}], output=py / "design.json")
    assert [s["name"] for s in d["sections"]] == ["mid.1", "mid.2", "x"]
    assert d["failures"] == [] and d["solids"] == 1 and all(s["closed"] for s in d["sections"])
    assert d["sections"][0]["length_mm"] == pytest.approx(400, rel=1e-9)  # the 100 mm square
    r = cli("design", "--step", STEP, "--section", "origin=0,0,37.5;normal=0,0,1;name=mid",
            "--section", "origin=50,50,25;normal=1,0,0;name=x;probe=A90B-90", "-o",
            sh / "design.json", "-q")
    assert r.returncode == 0, r.stderr
    assert filecmp.cmp(py / "design.json", sh / "design.json", shallow=False)
    # A plane's probe orientation goes to its own sections only.
    probes = {s["name"]: s.get("probe") for s in json.loads((py / "design.json").read_text())["sections"]}
    assert probes == {"mid.1": None, "mid.2": None, "x": {"a_deg": 90.0, "b_deg": -90.0}}, probes
    p = trueaxis.simulate_part(py / "design.json", py / "part.json", translate=(1.8, -1.1, 0),
                               rotate=(0, 0, 0.3), bumps=[("mid.1", 150, 2, 30)], noise=2, seed=3)
    assert p["sections"] == 3 and p["bumps"] == 1 and p["centroid_shift_mm"] > 1.8
    r = cli("simulate", "part", "--design", sh / "design.json", "--translate", "1.8,-1.1,0",
            "--rotate", "0,0,0.3", "--bump", "mid.1,150,2,30", "--noise", "2", "--seed", "3", "-o",
            sh / "part.json", "-q")
    assert r.returncode == 0, r.stderr
    assert filecmp.cmp(py / "part.json", sh / "part.json", shallow=False)
    # And they are what trueaxis.scan takes: every section of the design is scanned or named.
    s = trueaxis.scan(py / "design.json", py / "part.json")
    assert len(s["sections"]) == 3 and "sections scanned" in s["summary"], s["summary"]


def test_what_is_not_a_section_or_a_part_is_refused_in_words(tmp_path):
    ok = {"origin": (0, 0, 37.5), "normal": (0, 0, 1), "name": "mid"}
    with pytest.raises(trueaxis.Error, match="section 1: no key 'centre'"):
        trueaxis.design(STEP, [{"centre": (0, 0, 0), "normal": (0, 0, 1)}])
    with pytest.raises(trueaxis.Error, match="section 1: give both origin and normal"):
        trueaxis.design(STEP, [{"origin": (0, 0, 0)}])
    with pytest.raises(trueaxis.Error, match="section 'S1': the normal is zero"):
        trueaxis.design(STEP, [{"origin": (0, 0, 0), "normal": (0, 0, 0)}])
    with pytest.raises(trueaxis.Error, match="section 'S1': origin needs three numbers"):
        trueaxis.design(STEP, [{"origin": (0, 0), "normal": (0, 0, 1)}])
    with pytest.raises(trueaxis.Error, match="the probe head cannot take"):
        trueaxis.design(STEP, [dict(ok, probe=(200, 0))])
    # A plane that misses the part is named with its reason; the others are still made.
    d = trueaxis.design(STEP, [ok, {"origin": (0, 0, 500), "normal": (0, 0, 1), "name": "above"}])
    assert [f["name"] for f in d["failures"]] == ["above"] and d["failures"][0]["reason"]
    assert len(d["sections"]) == 2
    with pytest.raises(trueaxis.Error, match="no section could be made"):
        trueaxis.design(STEP, [{"origin": (0, 0, 500), "normal": (0, 0, 1)}])
    trueaxis.design(STEP, [ok], output=tmp_path / "design.json")
    with pytest.raises(trueaxis.Error, match="a bump is"):
        trueaxis.simulate_part(tmp_path / "design.json", tmp_path / "p.json", bumps=[("mid.1", 1)])
    with pytest.raises(trueaxis.Error, match="scale_along is"):
        trueaxis.simulate_part(tmp_path / "design.json", tmp_path / "p.json", scale_along=(1, 0, 0))
    with pytest.raises(trueaxis.Error, match="nosuch"):
        trueaxis.simulate_part(tmp_path / "design.json", tmp_path / "p.json",
                               bumps=[("nosuch", 10, 1, 5)])
