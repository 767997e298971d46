"""trueaxis.save() writes each result as the command line writes it (so every command reads it:
`trueaxis report` draws it), and trueaxis.load() reads any result file back."""
import filecmp
import json
import os
import pathlib
import re
import subprocess

import numpy as np
import pytest

import trueaxis

TRUEAXIS = os.environ.get("TRUEAXIS", "trueaxis")
DATA = pathlib.Path(__file__).resolve().parents[1] / "data"
LAYOUT = [
    {"name": "a", "kind": "position", "position": [-60, 0, 0]},
    {"name": "b", "kind": "position", "position": [60, 0, 150]},
    {"name": "c", "kind": "position", "position": [0, 80, 300]},
]


def cli(*args):
    return subprocess.run([TRUEAXIS, *map(str, args)], capture_output=True, text=True, timeout=300)


@pytest.fixture(scope="module")
def gauge(tmp_path_factory):
    d = tmp_path_factory.mktemp("gauge")
    r = cli("simulate", "ballgauge", "--alignment", "ls", "--noise", "0.2", "--gauge", d / "g.json",
            "-o", d / "m.json", "--truth", d / "t.csv", "--lengths", d / "lengths.csv", "-q")
    assert r.returncode == 0, r.stderr
    return d


def results(gauge, tmp):
    """(name, result) for every kind of result the module returns."""
    m = trueaxis.Machine.random(seed=4)
    sim = trueaxis.simulate_straightness(stations=200, offsets=[0, 10, 20], noise=0.05)
    yield "separate", trueaxis.separate(sim["x"], sim["readings"], offsets=sim["offsets"],
                                        method="three-point", sigma=0.05)
    yield "moody", trueaxis.moody(DATA / "moody", method="lsq")
    yield "space", trueaxis.measure_space(m, spacing=200, verify=50)
    g = trueaxis.simulate_guideway(m, LAYOUT, axis="x", positions=100)
    yield "guideway", trueaxis.guideway(LAYOUT, g["s"], g["readings"])
    runs, _ = trueaxis.simulate_positioning(m, axis="x", targets=list(np.arange(0, 801, 100.0)),
                                            cycles=3, backlash=3.0, noise=0.3)
    yield "positioning", trueaxis.positioning(runs, tolerance={"A": 30})
    pts = np.random.default_rng(1).normal(size=(60, 3))
    pts = 10 * pts / np.linalg.norm(pts, axis=1)[:, None]
    yield "fit", trueaxis.fit("sphere", pts, point_u=0.5)
    bg = trueaxis.ballgauge(gauge / "g.json", gauge / "m.json")
    yield "ballgauge", bg
    yield "identify", trueaxis.identify(gauge / "g.json", gauge / "m.json", stylus_offset=[0, 0, -100])
    yield "verify_lengths", trueaxis.verify_lengths(gauge / "lengths.csv", map=bg["map"], mpe="1.5+L/300")[0]
    d = tmp / "scan"
    d.mkdir()
    assert cli("design", "--step", DATA / "ippdme" / "ipp_simple.stp", "--section",
               "origin=0,0,37.5;normal=0,0,1;name=mid", "-o", d / "design.json", "-q").returncode == 0
    assert cli("simulate", "part", "--design", d / "design.json", "--translate", "1.8,-1.1,0",
               "--seed", "3", "-o", d / "part.json", "-q").returncode == 0
    yield "scan", trueaxis.scan(str(d / "design.json"), str(d / "part.json"))


def test_every_result_saves_as_the_cli_file_and_loads_back(gauge, tmp_path):
    kinds = {}
    for name, r in results(gauge, tmp_path):
        assert isinstance(r, trueaxis.Result) and "__save__" not in r, name
        path = tmp_path / f"{name}.json"
        trueaxis.save(r, path)
        kind = json.loads(path.read_text())["kind"]
        kinds[name] = kind
        # Every command reads it: the report draws it (a parametric model is drawn with its map:
        # verify-lengths takes it instead).
        if kind == "parametric model":
            out = cli("verify-lengths", "--input", gauge / "lengths.csv", "--model", path, "-o",
                      tmp_path / "v.json", "-q")
        else:
            out = cli("report", path, "-o", tmp_path / f"{name}.html", "-q")
        assert out.returncode == 0, (name, out.stderr)
        # Read back, the same file is written again.
        back = trueaxis.load(path)
        assert back["kind"] == kind
        trueaxis.save(back, tmp_path / f"{name}-again.json")
        assert filecmp.cmp(path, tmp_path / f"{name}-again.json", shallow=False), name
    assert set(kinds.values()) == {"separation", "surface", "space", "guideway", "positioning", "fit",
                                   "ballgauge map", "parametric model", "length verification", "scan"}


def without_date_and_source(page):
    page = re.sub(r"<th>date</th><td>[^<]*</td>", "", page)
    return re.sub(r'<p class="source">Data: [^<]*</p>\n?', "", page)


def test_python_writes_the_report_the_command_line_writes(gauge, tmp_path):
    for name, r in results(gauge, tmp_path):
        html = tmp_path / f"{name}-py.html"
        if name == "identify":  # a parametric model is drawn with its map
            with pytest.raises(trueaxis.Error, match="drawn with its map"):
                trueaxis.report(r, html)
            continue
        kind = trueaxis.report(r, html, meta={"machine": "M <1>", "operator": "K. Tanaka"})
        trueaxis.save(r, tmp_path / f"{name}.json")
        out = cli("report", tmp_path / f"{name}.json", "-o", tmp_path / f"{name}-cli.html",
                  "--meta", "machine=M <1>", "--meta", "operator=K. Tanaka", "-q")
        assert out.returncode == 0, out.stderr
        py, cl = html.read_text(encoding="utf-8"), (tmp_path / f"{name}-cli.html").read_text(encoding="utf-8")
        assert without_date_and_source(py) == without_date_and_source(cl), (name, kind)
        assert '<p class="source">' not in py  # no file behind it: no data file named
        # From a file, the page names it as the command line does.
        trueaxis.report(tmp_path / f"{name}.json", html, title="Acceptance of M1")
        page = html.read_text(encoding="utf-8")
        assert f'<p class="source">Data: {name}.json</p>' in page and "<h1>Acceptance of M1</h1>" in page
    with pytest.raises(trueaxis.Error, match=r"ipp_simple.stp:1:1: invalid JSON"):
        trueaxis.report(DATA / "ippdme" / "ipp_simple.stp", tmp_path / "x.html")
    with pytest.raises(TypeError, match="not a dict"):
        trueaxis.report({"kind": "fit"}, tmp_path / "x.html")


def test_load_gives_arrays_and_refuses_what_is_not_a_result(tmp_path):
    sim = trueaxis.simulate_straightness(stations=100, offsets=[0, 10, 20])
    r = trueaxis.separate(sim["x"], sim["readings"], offsets=sim["offsets"], method="three-point")
    trueaxis.save(r, tmp_path / "r.json")
    back = trueaxis.load(str(tmp_path / "r.json"))
    assert isinstance(back["workpiece"]["value"], np.ndarray)
    assert back["workpiece"]["value"].shape == r["workpiece"]["value"].shape
    np.testing.assert_allclose(back["workpiece"]["value"], r["workpiece"]["value"], atol=1e-6)
    with pytest.raises(TypeError, match="not a dict"):
        trueaxis.save({"kind": "separation"}, tmp_path / "x.json")
    with pytest.raises(trueaxis.Error, match=r"ipp_simple.stp:1:1: invalid JSON"):
        trueaxis.load(DATA / "ippdme" / "ipp_simple.stp")
    bad = tmp_path / "bad.json"
    bad.write_text('{"kind": "fit", "element": "sphere"}')
    with pytest.raises(trueaxis.Error, match="bad.json"):
        trueaxis.load(bad)
    bad.write_text('{"x": [1, 2]}')
    with pytest.raises(trueaxis.Error, match=r"bad.json:1:1: not a trueaxis result file \(no 'kind'\)"):
        trueaxis.load(bad)
    bad.write_text('{"kind": "spline"}')
    with pytest.raises(trueaxis.Error, match=r"bad.json: a 'spline' file is not a result"):
        trueaxis.load(bad)
