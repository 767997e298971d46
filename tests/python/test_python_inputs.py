"""What Python users hold goes in as it is: pathlib paths, pandas tables and columns; a misspelt
keyword is named in one line."""
import pathlib

import numpy as np
import pytest

import trueaxis

pd = pytest.importorskip("pandas")


def test_paths_are_taken_as_pathlib_paths(tmp_path):
    m = trueaxis.Machine.random(seed=3)
    path = tmp_path / "machine.json"
    m.save(path)
    back = trueaxis.Machine.load(path)
    assert repr(back) == repr(m)
    runs, _ = trueaxis.simulate_positioning(m, axis="x", targets=list(np.arange(0, 401, 50.0)),
                                            cycles=3, noise=0.5)
    csv = tmp_path / "runs.csv"
    pd.DataFrame(runs).to_csv(csv, index=False)
    by_path = trueaxis.positioning(csv, output=tmp_path / "positioning.json")
    assert by_path["A"] == pytest.approx(trueaxis.positioning(str(csv))["A"], rel=1e-15)
    assert (tmp_path / "positioning.json").exists()
    # A missing file is named as the user gave it, not refused as a wrong type.
    with pytest.raises(trueaxis.Error, match="no-such.csv"):
        trueaxis.positioning(tmp_path / "no-such.csv")


def test_dataframes_go_where_tables_go():
    m = trueaxis.Machine.random(seed=4)
    runs, _ = trueaxis.simulate_positioning(m, axis="x", targets=list(np.arange(0, 801, 50.0)),
                                            cycles=5, backlash=3.0, noise=0.3)
    frame = pd.DataFrame(runs)
    from_frame = trueaxis.positioning(frame)
    from_dict = trueaxis.positioning(runs)
    assert from_frame["A"] == from_dict["A"] and from_frame["B"] == from_dict["B"]
    # A probe table: x and the probe columns as a DataFrame and Series.
    sim = trueaxis.simulate_straightness(stations=120, offsets=[0, 10, 20], seed=2, noise=0.05)
    table = pd.DataFrame(sim["readings"], columns=["a", "b", "c"])
    table.insert(0, "x", sim["x"])
    r = trueaxis.separate(table["x"], table[["a", "b", "c"]], sigma=0.05)
    plain = trueaxis.separate(sim["x"], sim["readings"], sigma=0.05)
    np.testing.assert_array_equal(r["workpiece"]["value"], plain["workpiece"]["value"])


def test_a_misspelt_keyword_is_named_in_one_line():
    with pytest.raises(TypeError) as e:
        trueaxis.simulate_straightness(stationz=100)
    assert str(e.value) == "simulate_straightness(): no keyword 'stationz' (did you mean 'stations'?)"
    with pytest.raises(TypeError, match="no keyword 'toleranse'.*'tolerance'"):
        trueaxis.positioning({}, toleranse={"A": 1})
    # One keyword per idea, named as the command line names it (--tolerance, --probe-noise).
    with pytest.raises(TypeError, match=r"no keyword 'tolerances' \(did you mean 'tolerance'\?\)"):
        trueaxis.positioning({}, tolerances={"A": 1})
    with pytest.raises(TypeError, match=r"no keyword 'probe_noise_um' \(did you mean 'probe_noise'\?\)"):
        trueaxis.scan("design.json", "part.json", probe_noise_um=0.5)
    # The wrapped functions keep their documentation.
    assert "runs" in trueaxis.positioning.__doc__
