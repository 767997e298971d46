"""Python binding of the geometric fits against NIST's reference pairs."""
from pathlib import Path

import numpy as np
import pytest

import trueaxis

NIST = Path(__file__).resolve().parent.parent / "data" / "nist-l2"


def read_ds(path):
    lines = path.read_text().split()
    n = int(lines[0])
    return np.array(lines[1:], dtype=float).reshape(n, 3)


@pytest.mark.parametrize("name", ["sph1", "sph11", "sph21"])
def test_sphere_matches_nist(name):
    ref = np.array((NIST / "Sphere" / f"{name}.fit").read_text().split(), dtype=float)
    f = trueaxis.fit("sphere", read_ds(NIST / "Sphere" / f"{name}.ds"))
    np.testing.assert_allclose(f["center"], ref[:3], rtol=0, atol=1e-9 * 1000)
    assert f["diameter"] == pytest.approx(ref[3], rel=1e-9)
    assert f["rms"] == pytest.approx(np.sqrt(np.mean(f["residuals"] ** 2)), rel=1e-12)


def test_cylinder_axis_up_to_sign_and_errors():
    ref = np.array((NIST / "Cylinder" / "cyl1.fit").read_text().split(), dtype=float)
    f = trueaxis.fit("cylinder", read_ds(NIST / "Cylinder" / "cyl1.ds"))
    assert min(np.linalg.norm(f["direction"] - ref[3:6]), np.linalg.norm(f["direction"] + ref[3:6])) < 1e-9
    assert f["diameter"] == pytest.approx(ref[6], rel=1e-9)
    with pytest.raises(trueaxis.Error, match="collinear"):
        trueaxis.fit("plane", np.outer(np.arange(5.0), [1, 2, 3]))
    with pytest.raises(trueaxis.Error, match="unknown element 'torus'"):
        trueaxis.fit("torus", np.zeros((5, 3)))
    with pytest.raises(trueaxis.Error, match=r"shape \(n, 3\)"):
        trueaxis.fit("sphere", np.zeros((5, 2)))


def test_min_zone_plane_of_alternating_points():
    h = 2e-3
    x, y = np.meshgrid(np.arange(8) * 40.0, np.arange(6) * 30.0)
    z = np.where((np.arange(8)[None, :] + np.arange(6)[:, None]) % 2 == 1, h, -h) + 1e-4 * x
    f = trueaxis.fit("plane", np.stack([x.ravel(), y.ravel(), z.ravel()], axis=1), zone=True)
    # Perpendicular to the tilted plane: 2h·cos(atan(1e-4)).
    assert f["zone"] == pytest.approx(2 * h / np.sqrt(1 + 1e-8), abs=1e-14)
    with pytest.raises(trueaxis.Error, match="available for line, plane and circle"):
        trueaxis.fit("sphere", np.random.default_rng(1).normal(size=(10, 3)), zone=True)


def test_python_speaks_the_words_of_fit_json(tmp_path):
    # One grammar: the dictionary's keys are fit.json's (center/point, normal/direction).
    import json
    import os
    import subprocess
    rng = np.random.default_rng(3)
    t = rng.uniform(0, 2 * np.pi, 30)
    pts = {"plane": np.stack([rng.uniform(0, 50, 30), rng.uniform(0, 50, 30), rng.normal(0, 1e-3, 30)], 1),
           "circle": np.stack([20 * np.cos(t), 20 * np.sin(t), rng.normal(0, 1e-3, 30)], 1),
           "sphere": np.stack([20 * np.cos(t) * np.sin(t + 1), 20 * np.sin(t) * np.sin(t + 1), 20 * np.cos(t + 1)], 1),
           "line": np.stack([np.arange(30.0), 2 * np.arange(30.0), rng.normal(0, 1e-3, 30)], 1)}
    cli = os.environ.get("TRUEAXIS", "trueaxis")
    for element, p in pts.items():
        csv = tmp_path / f"{element}.csv"
        np.savetxt(csv, p, delimiter=",", header="x,y,z", comments="")
        out = tmp_path / f"{element}.json"
        subprocess.run([cli, "fit", element, "-q", "--input", str(csv), "--output", str(out)], check=True)
        from_file = json.loads(out.read_text())
        f = trueaxis.fit(element, p)
        for key in ("center", "point", "normal", "direction", "diameter"):
            assert (key in f) == (key in from_file), (element, key)
            if key in f:
                np.testing.assert_allclose(f[key], from_file[key], rtol=1e-12, atol=1e-12)
        assert set(f["uncertainty"]) == set(from_file["uncertainty"]), element
        # The form figure, the same in both; without the points' uncertainty no U (None/null).
        assert f["form"]["name"] == from_file["form"]["name"]
        np.testing.assert_allclose(f["form"]["value_um"], from_file["form"]["value"] * 1e3, rtol=1e-12)
        assert f["form"]["U_um"] is None and from_file["form"]["U"] is None
    # With it: U beside the value, and whether the form is resolved (1 µm noise on a flat
    # plate: the flatness is all noise).
    f = trueaxis.fit("plane", pts["plane"], point_u=1.0)
    assert f["form"]["U_um"] > f["form"]["value_um"] and f["form"]["resolved"] is False
    assert "not resolved" in f["form"]["summary"]
