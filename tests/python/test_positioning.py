"""Positioning by ISO 230-2 and VDI 3441: the CLI's evaluation of simulated laser runs against an
independent numpy computation from the same runs.csv, and the Python binding."""
import json
import os
import subprocess

import numpy as np
import pytest

import trueaxis

TRUEAXIS = os.environ.get("TRUEAXIS", "trueaxis")  # ctest sets it; else the installed CLI


def iso_by_numpy(runs_csv):
    """ISO 230-2:2014 and VDI/DGQ 3441 parameters (µm) computed directly from the definitions."""
    rows = np.genfromtxt(runs_csv, delimiter=",", names=True, dtype=None, encoding="utf-8")
    targets = np.unique(rows["target_mm"])
    stats = {}
    for d in "+-":
        sel = rows["direction"] == d
        x = np.array([rows["deviation_um"][sel & (rows["target_mm"] == t)] for t in targets])
        stats[d] = (x.mean(axis=1), x.std(axis=1, ddof=1))
    (mu, su), (md, sd) = stats["+"], stats["-"]
    mean = (mu + md) / 2
    b = mu - md
    r_i = np.maximum(2 * su + 2 * sd + np.abs(b), np.maximum(4 * su, 4 * sd))
    u = np.abs(b)
    ps = 6 * (su + sd) / 2
    return {
        "A_up": (mu + 2 * su).max() - (mu - 2 * su).min(),
        "A_down": (md + 2 * sd).max() - (md - 2 * sd).min(),
        "A": max((mu + 2 * su).max(), (md + 2 * sd).max()) - min((mu - 2 * su).min(),
                                                                 (md - 2 * sd).min()),
        "E_up": mu.max() - mu.min(),
        "E_down": md.max() - md.min(),
        "E": max(mu.max(), md.max()) - min(mu.min(), md.min()),
        "M": mean.max() - mean.min(),
        "R_up": 4 * su.max(),
        "R_down": 4 * sd.max(),
        "R": r_i.max(),
        "B": np.abs(b).max(),
        "B_mean": b.mean(),
        "P": (mean + (u + ps) / 2).max() - (mean - (u + ps) / 2).min(),
        "Pa": mean.max() - mean.min(),
        "Ps": ps.max(),
        "U": u.max(),
    }


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_cli_agrees_with_numpy(tmp_path, seed):
    runs, out, vdi = (str(tmp_path / n) for n in ("runs.csv", "p.json", "v.json"))
    subprocess.run([TRUEAXIS, "simulate", "positioning", "--machine-seed", str(seed), "--axis",
                    "yxz"[seed - 1], "--targets", "0:37:480", "--cycles", "5", "--backlash", "2.5",
                    "--noise", "0.4", "--drift", "1", "--seed", str(seed), "-o", runs, "-q"],
                   check=True)
    subprocess.run([TRUEAXIS, "positioning", "-i", runs, "-o", out, "-q"], check=True)
    subprocess.run([TRUEAXIS, "positioning", "-i", runs, "-o", vdi, "--standard", "vdi3441", "-q"],
                   check=True)
    iso = json.load(open(out))
    ref = iso_by_numpy(runs)
    assert iso["standard"] == "ISO 230-2:2014" and iso["cycles"] == 5
    for k in ("A", "A_up", "A_down", "E", "E_up", "E_down", "M", "R", "R_up", "R_down", "B",
              "B_mean"):
        assert iso[k] == pytest.approx(ref[k], rel=1e-12, abs=1e-12), k
    v = json.load(open(vdi))
    for k in ("P", "Pa", "Ps", "U"):
        assert v[k] == pytest.approx(ref[k], rel=1e-12, abs=1e-12), k
    # The binding reads the same file and gives the same numbers.
    p = trueaxis.positioning(runs)
    for k in ref:
        assert p[k] == pytest.approx(ref[k], rel=1e-12, abs=1e-12), k


def test_tolerance_exit_status(tmp_path):
    runs, out = str(tmp_path / "runs.csv"), str(tmp_path / "p.json")
    subprocess.run([TRUEAXIS, "simulate", "positioning", "--targets", "0:100:800", "--backlash",
                    "4", "--noise", "0.3", "-o", runs, "-q"], check=True)
    ok = subprocess.run([TRUEAXIS, "positioning", "-i", runs, "-o", out, "--tolerance", "R=100",
                         "-q"])
    assert ok.returncode == 0 and json.load(open(out))["pass"] is True
    bad = subprocess.run([TRUEAXIS, "positioning", "-i", runs, "-o", out, "--tolerance", "B=1",
                          "-q"], capture_output=True, text=True)
    assert bad.returncode == 1 and "out of tolerance: B = " in bad.stderr
    assert json.load(open(out))["tolerances"]["B"]["pass"] is False
    usage = subprocess.run([TRUEAXIS, "positioning", "-i", runs, "--tolerance", "Q=1"],
                           capture_output=True, text=True)
    assert usage.returncode == 2 and "unknown parameter 'Q'" in usage.stderr


def test_binding_simulation_and_one_direction():
    m = trueaxis.Machine.random(seed=4)
    runs, truth = trueaxis.simulate_positioning(m, axis="x", targets=list(np.arange(0, 801, 50.0)),
                                                cycles=5, backlash=3.0)
    r = trueaxis.positioning(runs)
    # Noise-free: the means are the truth, and B̄ is minus the backlash.
    np.testing.assert_allclose(r["targets"]["mean_up"], truth["up_um"], atol=1e-9)
    np.testing.assert_allclose(r["targets"]["mean_down"], truth["down_um"], atol=1e-9)
    assert r["B_mean"] == pytest.approx(-3.0, abs=1e-9)
    up = {k: [v for v, d in zip(runs[k], runs["direction"]) if d == "+"] for k in runs}
    u = trueaxis.positioning(up)
    assert u["E_up"] == pytest.approx(r["E_up"], abs=1e-12)
    assert u["E"] is None and u["B"] is None and u["A"] is None
    assert any("only '+' approaches" in w for w in u["warnings"])
    with pytest.raises(trueaxis.Error, match="direction 'x'"):
        trueaxis.positioning(dict(runs, direction=["x"] * len(runs["direction"])))


def rtl_as_csv(rtl_path, csv_path):
    """An independent reading of a Renishaw .rtl file: targets from TARGET DATA, each run's
    direction from the order it visits its targets, the k-th run of a direction is cycle k."""
    section, targets, collecting, data, rows = None, [], False, False, []
    for line in open(rtl_path, encoding="utf-8").read().splitlines():
        s = line.strip()
        if s.endswith("::"):
            section, collecting, data = s[:-2], False, False
        elif section == "TARGET DATA":
            if s.lower().startswith("targets"):
                collecting = True
            elif collecting and s and (s[0].isdigit() or s[0] in "+-."):
                targets += [float(v) for v in s.split()]
            else:
                collecting = False
        elif section == "DEVIATIONS":
            if s.lower().startswith("run target data"):
                data = True
            elif data and s:
                run, target, dev = s.split()
                rows.append((int(run), targets[int(target) - 1], float(dev)))
    cycles = {"+": 0, "-": 0}
    out = ["target_mm,cycle,direction,deviation_um"]
    for run in sorted({r for r, _, _ in rows}):
        pos = [t for r, t, _ in rows if r == run]
        d = "+" if pos[1] > pos[0] else "-"
        cycles[d] += 1
        out += [f"{t},{cycles[d]},{d},{v}" for r, t, v in rows if r == run]
    open(csv_path, "w").write("\n".join(out) + "\n")


def test_renishaw_rtl_agrees_with_numpy(tmp_path):
    rtl, csv, out = (str(tmp_path / n) for n in ("runs.rtl", "runs.csv", "p.json"))
    subprocess.run([TRUEAXIS, "simulate", "positioning", "--machine-seed", "5", "--axis", "x",
                    "--targets", "0:45:720", "--cycles", "5", "--backlash", "2", "--noise", "0.5",
                    "--seed", "4", "-o", rtl, "-q"], check=True)
    assert open(rtl, encoding="utf-8").readline().strip() == "HEADER::"
    subprocess.run([TRUEAXIS, "positioning", "-i", rtl, "-o", out, "-q"], check=True)
    rtl_as_csv(rtl, csv)
    expected = iso_by_numpy(csv)
    got = json.load(open(out))
    for k in ("A", "E", "M", "R", "B", "B_mean", "A_up", "R_down"):
        assert got[k] == pytest.approx(expected[k], abs=1e-9), k
    # The binding reads the same file; a sorted file's runs can be given their directions.
    p = trueaxis.positioning(rtl)
    assert p["A"] == pytest.approx(got["A"], abs=1e-12) and p["warnings"] == got["warnings"]
    lines = open(rtl, encoding="utf-8").read().splitlines()
    start = lines.index("Run Target Data:") + 1
    data = sorted(lines[start:], key=lambda l: tuple(int(v) for v in l.split()[:2]))
    sorted_rtl = str(tmp_path / "sorted.rtl")
    open(sorted_rtl, "w").write("\n".join(lines[:start] + data) + "\n")
    one_way = trueaxis.positioning(sorted_rtl)
    assert one_way["B"] is None
    assert any("every run lists its targets in increasing order" in w for w in one_way["warnings"])
    both = trueaxis.positioning(sorted_rtl, run_directions="+-")
    assert both["A"] == pytest.approx(got["A"], abs=1e-12)
    with pytest.raises(trueaxis.Error, match="run_directions belongs"):
        trueaxis.positioning(csv, run_directions="+-")
