"""Machine records from Python: trueaxis.records.open(db), add, list, machines and trend, the
same database as 'trueaxis record'."""
import json
import os
import subprocess

import numpy as np
import pytest
import trueaxis

TRUEAXIS = os.environ.get("TRUEAXIS", "trueaxis")


def test_records_from_python_and_the_command_line(tmp_path):
    m = trueaxis.Machine.random(seed=1)
    setup = str(tmp_path / "acceptance.json")
    trueaxis.acceptance_setup(m, setup)
    files = []
    for k in range(3):
        r = trueaxis.acceptance_probing(m, setup, mpe_form=1.8, lobing=0.5, noise=0.1, seed=k + 1)
        files.append(str(tmp_path / f"probing{k}.json"))
        trueaxis.save(r, files[-1])
    db = trueaxis.records.open(str(tmp_path / "r.db"))
    first = db.add(files[0], machine="CMM 1", date="2024-05-01", state="as-found", new_machine=True)
    assert first[0]["figures"]["PForm"]["value"] == pytest.approx(
        json.load(open(files[0]))["PForm_um"])
    db.add(files[1:], machine="CMM 1", date="2025-05-01", state="as-left", operator="J. O'Brien")
    with pytest.raises(trueaxis.Error, match="already stored"):
        db.add(files[0], machine="CMM 1")
    with pytest.raises(trueaxis.Error, match="--new-machine"):
        db.add(files[0], machine="CMM 2")
    with pytest.raises(trueaxis.Error, match="'as-found', 'as-left'"):
        db.add(files[0], machine="CMM 1", state="found")
    rows = db.list(machine="CMM 1")
    assert [r["state"] for r in rows] == ["as-found", "as-left", "as-left"]
    assert db.machines() == [{"machine": "CMM 1", "records": 3, "first": "2024-05-01",
                              "last": "2025-05-01"}]
    t = db.trend(machine="CMM 1", figure="PForm", tolerance=5, points="all")
    assert t["dates"] == ["2024-05-01", "2025-05-01", "2025-05-01"] and t["unit"] == "µm"
    assert isinstance(t["values"], np.ndarray) and not np.isnan(t["u"]).any()
    assert t["u_drift"] is None or t["u_drift"] > 0
    # By default, with as-found and as-left points, the drift is the as-found values'.
    auto = db.trend(machine="CMM 1", figure="PForm")
    assert auto["fitted_on"] == "as found" and auto["dates"] == ["2024-05-01"]
    assert "at least two dates" in auto["not_resolved"]
    with pytest.raises(trueaxis.Error, match="'auto', 'as-found'"):
        db.trend(machine="CMM 1", figure="PForm", points="found")
    # The command line reads the same database.
    out = subprocess.run([TRUEAXIS, "record", "list", "--db", str(tmp_path / "r.db")],
                         capture_output=True, text=True)
    assert out.returncode == 0 and out.stdout.count("CMM 1") == 3, out.stderr
    pd = pytest.importorskip("pandas")
    frame = pd.DataFrame(rows)
    assert list(frame["date"]) == ["2024-05-01", "2025-05-01", "2025-05-01"]
    # When it is due: a year after the last visit unless PForm's trend reaches its limit sooner.
    due = db.due(interval_months=12, limits={"PForm": 1e6}, today="2025-06-01")
    assert len(due) == 1 and due[0]["machine"] == "CMM 1" and due[0]["due"] == "2026-05-01"
    assert due[0]["because"] == "12 months after the last visit" and not due[0]["overdue"]
    assert len(due[0]["notes"]) == 1 and due[0]["notes"][0].startswith("PForm: ")
    with pytest.raises(trueaxis.Error, match="the value after '=' must be a number"):
        db.due(limits={"PForm": float("nan")})
    # Opened read-only: read, never written.
    ro = trueaxis.records.open(str(tmp_path / "r.db"), read_only=True)
    assert len(ro.list()) == 3
    with pytest.raises(trueaxis.Error, match="read-only"):
        ro.add(files[0], machine="CMM 3", new_machine=True)
    with pytest.raises(trueaxis.Error, match="no records database"):
        trueaxis.records.open(str(tmp_path / "absent.db"), read_only=True)
    # The certificate of the second visit: both probing results as left, U from their files.
    cert = db.certificate(machine="CMM 1", date="2025-05-01", output=str(tmp_path / "cert.html"))
    assert cert["title"] == "Calibration certificate CMM 1-2025-05-01"
    assert sorted({ln["figure"] for ln in cert["lines"]}) == ["PForm", "PSize"]
    assert all(ln["U"] is not None and ln["state"] == "as-left" for ln in cert["lines"])
    assert all(ln["decision"] == ("conforms (the test's own rule)" if ln["figure"] == "PForm"
                                  else "no limit stated") for ln in cert["lines"])  # no MPE_size
    assert any("does not describe machine 'CMM 1'" in w for w in cert["warnings"])
    assert "Results as left" in open(tmp_path / "cert.html").read()
