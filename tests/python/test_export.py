"""trueaxis.export writes the controller compensation tables `trueaxis export` writes, from a
positioning result or an error space, and refuses what is not one."""
import filecmp
import os
import subprocess

import numpy as np
import pytest

import trueaxis

TRUEAXIS = os.environ.get("TRUEAXIS", "trueaxis")
FORMATS = ("linuxcnc", "sinumerik", "heidenhain", "fanuc")


def same_file(tmp_path, name, python, command):
    """Writes `name` by Python and by the command line (each in a folder of its own: HEIDENHAIN
    tables carry their file name) and compares the two files byte for byte."""
    (tmp_path / "py").mkdir(exist_ok=True)
    (tmp_path / "cli").mkdir(exist_ok=True)
    said = python(tmp_path / "py" / name)
    cli(*command, "-o", tmp_path / "cli" / name, "-q")
    assert filecmp.cmp(tmp_path / "py" / name, tmp_path / "cli" / name, shallow=False), name
    return said


def cli(*args):
    r = subprocess.run([TRUEAXIS, *map(str, args)], capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, r.stderr
    return r


@pytest.fixture(scope="module")
def results(tmp_path_factory):
    d = tmp_path_factory.mktemp("export")
    m = trueaxis.Machine.random(seed=4)
    runs, _ = trueaxis.simulate_positioning(m, axis="x", targets=list(np.arange(0, 801, 50.0)),
                                            cycles=3, backlash=3.0, noise=0.3)
    p = trueaxis.positioning(runs)
    s = trueaxis.measure_space(m, spacing=100)
    trueaxis.save(p, d / "pos.json")
    trueaxis.save(s, d / "space.json")
    return d, p, s


@pytest.mark.parametrize("fmt", FORMATS)
def test_python_writes_the_table_the_command_line_writes(results, fmt, tmp_path):
    d, p, s = results
    # From a positioning result: the same file as `trueaxis export FORMAT --positioning`.
    said = same_file(tmp_path, "X.COM", lambda out: trueaxis.export(p, out, fmt),
                     ["export", fmt, "--positioning", d / "pos.json"])
    assert "points" in said
    # From an error space's grid line along y through a point, given as a file path.
    same_file(tmp_path, "Y.COM",
              lambda out: trueaxis.export(d / "space.json", out, fmt, axis="y", at=[100, 0, 100]),
              ["export", fmt, "--space", d / "space.json", "--axis", "y", "--at", "100,0,100"])


def test_options_are_the_command_lines_and_others_are_refused(results, tmp_path):
    d, p, s = results
    same_file(tmp_path, "X2.COM", lambda out: trueaxis.export(p, out, "heidenhain", axis_name="X2"),
              ["export", "heidenhain", "--positioning", d / "pos.json", "--axis-name", "X2"])
    same_file(tmp_path, "x.comp",
              lambda out: trueaxis.export(p, out, "linuxcnc", type=0, unidirectional=True),
              ["export", "linuxcnc", "--positioning", d / "pos.json", "--type", "0", "--unidirectional"])
    with pytest.raises(trueaxis.Error, match=r"export\(format='fanuc'\): no option 'encoder' \(it takes: "):
        trueaxis.export(p, tmp_path / "f.txt", "fanuc", encoder=1)
    with pytest.raises(trueaxis.Error, match="format must be linuxcnc, sinumerik, heidenhain or fanuc"):
        trueaxis.export(p, tmp_path / "f.txt", "haas")
    with pytest.raises(trueaxis.Error, match="at= belongs to an error space"):
        trueaxis.export(p, tmp_path / "f.txt", "fanuc", at=[0, 0, 0])
    with pytest.raises(trueaxis.Error, match="unidirectional= belongs to a positioning result"):
        trueaxis.export(s, tmp_path / "f.txt", "linuxcnc", unidirectional=True)
    with pytest.raises(trueaxis.Error, match="axis must be 'x', 'y' or 'z', not 'X'"):
        trueaxis.export(s, tmp_path / "f.txt", "linuxcnc", axis="X")
    fit = trueaxis.fit("line", np.c_[np.arange(5.0), np.zeros(5), np.zeros(5)])
    with pytest.raises(trueaxis.Error, match="not a 'fit'"):
        trueaxis.export(fit, tmp_path / "f.txt", "linuxcnc")
