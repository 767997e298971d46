"""CMM acceptance tests (ISO 10360-2 E0/R0, ISO 10360-5 probing) from Python, against the command
line and against the machine's own error field."""
import json
import os
import subprocess

import numpy as np
import pytest
import trueaxis

TRUEAXIS = os.environ.get("TRUEAXIS", "trueaxis")


def test_acceptance_from_python_and_from_the_command_line(tmp_path):
    m = trueaxis.Machine.random(seed=3)
    setup = str(tmp_path / "acceptance.json")
    assert trueaxis.acceptance_setup(m, setup) == setup
    r = trueaxis.acceptance_e0(m, setup, mpe="2.5+L/250")
    assert len(r["lengths"]) == 105 and r["complete"]
    assert r["E0_max_um"] == pytest.approx(max(abs(l["error_um"]) for l in r["lengths"]))
    assert r["verdict"] == "does not conform" and r["pass"] is False
    # The measured length is the end points' distance along the placement's line: they lie on
    # it but for the machine's errors across it (micrometres over 780 mm: below 1e-6 mm apart).
    l = r["lengths"][0]
    a, b = np.array(l["endpoints"][0]), np.array(l["endpoints"][1])
    assert np.linalg.norm(b - a) == pytest.approx(l["measured_mm"], abs=1e-6)
    assert l["error_um"] == pytest.approx((l["measured_mm"] - l["nominal_mm"]) * 1e3, abs=1e-9)
    # The same test through the command line: the same numbers.
    machine = tmp_path / "m.json"
    m.save(str(machine))
    out = tmp_path / "e0.json"
    run = subprocess.run([TRUEAXIS, "acceptance", "e0", "--machine", str(machine), "--artefacts", setup,
                          "--mpe", "2.5+L/250", "-o", str(out)], capture_output=True, text=True)
    assert run.returncode == 1, run.stderr
    cli = json.load(open(out))
    assert cli["E0_max_um"] == pytest.approx(r["E0_max_um"], abs=1e-9)
    trueaxis.save(r, str(tmp_path / "e0-py.json"))
    assert json.load(open(tmp_path / "e0-py.json"))["lengths"][7] == cli["lengths"][7]

    p = trueaxis.acceptance_probing(m, setup, mpe_form=1.8, mpe_size=1.5, lobing=0.5, noise=0.05)
    assert p["points"].shape == (25, 3) and len(p["radial_um"]) == 25
    assert p["PForm_um"] == pytest.approx(np.ptp(p["radial_um"]))
    assert p["form_verdict"] == "conforms"
    with pytest.raises(trueaxis.Error, match="MPE 'fast'"):
        trueaxis.acceptance_e0(m, setup, mpe="fast")
    bad = tmp_path / "bad.json"
    bad.write_text('{"sphere": {"centre": [0, 0], "diameter_mm": 25}}')
    with pytest.raises(trueaxis.Error, match=r"bad.json:1:\d+: .*three numbers"):
        trueaxis.acceptance_probing(m, str(bad))


def test_e150_in_process_and_over_ipp_from_python(tmp_path):
    """E150 with a 150 mm stylus offset along X, on a set-up for that stylus's volume: in process,
    then over I++ DME on a served CMM whose stylus is offset the same way (cmm=): the same lengths."""
    import re
    m = trueaxis.Machine.random(seed=3)
    setup = str(tmp_path / "acc150.json")
    trueaxis.acceptance_setup(m, setup, stylus_offset=150)
    kw = dict(mpe="1.5+L/300", stylus_offset=[150, 0, 0], positions=["along X", "along Z"])
    r = trueaxis.acceptance_e0(m, setup, **kw)
    assert r["test"] == "E150" and len(r["lengths"]) == 30 and r["complete"]
    assert {l["position"] for l in r["lengths"]} == {"along X", "along Z"}
    machine = tmp_path / "m.json"
    m.save(str(machine))
    server = subprocess.Popen(
        [TRUEAXIS, "serve", "--port", "0", "--time-scale", "0", "--sessions", "1", "--machine",
         str(machine), "--stylus-offset", "150", "--artefacts", setup],
        stdout=subprocess.PIPE, text=True)
    try:
        port = int(re.search(r"127\.0\.0\.1:(\d+)", server.stdout.readline()).group(1))
        remote = trueaxis.acceptance_e0(m, setup, **kw, cmm=f"ipp://127.0.0.1:{port}")
    finally:
        server.wait(timeout=60)
    assert remote["complete"] and len(remote["lengths"]) == 30
    assert max(abs(a["error_um"] - b["error_um"])
               for a, b in zip(r["lengths"], remote["lengths"])) < 0.05
    with pytest.raises(trueaxis.Error, match="across the ram"):
        trueaxis.acceptance_e0(m, setup, mpe="3", stylus_offset=[0, 0, 150])
    with pytest.raises(trueaxis.Error, match="travel"):
        trueaxis.acceptance_e0(None, setup, mpe="3", cmm="ipp://127.0.0.1:1")
    with pytest.raises(trueaxis.Error, match="not an I\\+\\+ DME server address"):
        trueaxis.acceptance_e0(None, setup, mpe="3", cmm="127.0.0.1:1", travel=[0, 0, 0, 1, 1, 1])
