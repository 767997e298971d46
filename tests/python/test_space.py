"""Python binding of the virtual machine, error surfaces, error spaces and maps.

Known truths: a machine with one polynomial error, exactly linear error fields (which trilinear
interpolation reproduces), a surface sampled from a known function, Moody's published tables,
and the virtual machine's own errors.
"""
import json
import os
import subprocess
from pathlib import Path

import numpy as np
import pytest

import trueaxis

TRUEAXIS = os.environ.get("TRUEAXIS", "trueaxis")  # ctest sets it; else the installed CLI

MOODY = Path(__file__).resolve().parent.parent / "data" / "moody"

# Named tolerances.
ROUND_OFF_UM = 1e-9  # µm: exact computations in double precision
SPACE_ROUND_OFF_UM = 1e-6  # µm: a whole noise-free campaign (separation + surfaces + stacking)
MOODY_PRINTED = 0.01  # tens of microinches: the precision of Moody's published tables


def write_machine(path, errors, offset=(0, 0, 0), chain="FYXZ"):
    path.write_text(json.dumps({
        "name": "test",
        "chain": chain,
        "ranges": {"x": [0, 1000], "y": [0, 500], "z": [0, 400]},
        "offset": list(offset),
        "errors": errors,
    }))
    return trueaxis.Machine.load(str(path))


def test_machine_translation_and_rotation_errors_are_exact(tmp_path):
    # EXX = 10 µm/m · x; EBX (pitch of X about Y) = 20 µrad; stylus 100 mm below Z's reference.
    m = write_machine(tmp_path / "m.json", {"EXX": {"polynomial": [0, 10]}, "EBX": {"polynomial": [20]}},
                      offset=(0, 0, -100))
    p = np.array([[500.0, 100.0, 50.0], [1000.0, 0.0, 0.0]])
    e = m.error(p)
    assert e.shape == (2, 3)
    # Chain FYXZ: X carries Z and the stylus, so X's rotation (exact, about Y) turns the arm from
    # X's reference point to the tool point, (0, 0, z − 100) mm; Y before it only translates.
    b = 20e-6
    for row, (x, _, z) in zip(e, p):
        arm = np.array([0.0, 0.0, z - 100.0])  # tool point relative to the X carriage's origin (mm)
        rot = np.array([[np.cos(b), 0, np.sin(b)], [0, 1, 0], [-np.sin(b), 0, np.cos(b)]])
        want = np.array([10e-3 * x / 1000, 0, 0]) + rot @ arm - arm
        np.testing.assert_allclose(row, want * 1e3, atol=ROUND_OFF_UM)
    # A single point keeps its shape; error functions by ISO name.
    assert m.error(p[0]).shape == (3,)
    np.testing.assert_allclose(m.error_function("EXX", np.array([0.0, 250.0, 1000.0])), [0, 2.5, 10],
                               atol=ROUND_OFF_UM)
    np.testing.assert_allclose(m.error_function("EBX", np.array([3.0])), [20.0])
    np.testing.assert_allclose(m.error_function("EC0Y", np.array([3.0])), [0.0])


def test_machine_refuses_bad_points_and_names(tmp_path):
    m = trueaxis.Machine.random(seed=2)
    np.testing.assert_array_equal(m.ranges, [[0, 800], [0, 600], [0, 500]])
    with pytest.raises(trueaxis.Error, match=r"point 1 \(900, 0, 0\) mm is outside"):
        m.error([[0, 0, 0], [900, 0, 0]])
    assert m.error([[900, 0, 0]], check_range=False).shape == (1, 3)
    with pytest.raises(trueaxis.Error, match=r"shape \(n, 3\) or \(3,\), not \(4, 2\)"):
        m.error(np.zeros((4, 2)))
    with pytest.raises(trueaxis.Error, match="NaN"):
        m.error([[np.nan, 0, 0]])
    with pytest.raises(trueaxis.Error, match="unknown error name 'EXQ'"):
        m.error_function("EXQ", np.zeros(1))
    with pytest.raises(trueaxis.Error, match="outside the axis range"):
        m.error_function("EYY", np.array([700.0]))
    with pytest.raises(trueaxis.Error, match="machine.json"):
        trueaxis.Machine.load("no/such/machine.json")


def test_machine_save_load_round_trip(tmp_path):
    m = trueaxis.Machine.random(seed=5, chain="FXYZ", ranges=[[0, 400], [0, 300], [0, 200]],
                                offset=[10, 0, -50])
    m.save(str(tmp_path / "m.json"))
    back = trueaxis.Machine.load(str(tmp_path / "m.json"))
    assert back.chain == "FXYZ"
    np.testing.assert_array_equal(back.offset, [10, 0, -50])
    pts = np.random.default_rng(1).uniform([0, 0, 0], [400, 300, 200], size=(50, 3))
    # The file stores µm/µrad with full precision: the same errors come back.
    np.testing.assert_allclose(back.error(pts), m.error(pts), atol=ROUND_OFF_UM)


def linear_map(A, b):
    x, y, z = np.linspace(0, 400, 5), np.array([0, 50, 120, 300.0]), np.linspace(-50, 150, 3)
    X, Y, Z = np.meshgrid(x, y, z, indexing="ij")
    P = np.stack([X, Y, Z], axis=-1)
    return trueaxis.ErrorMap(x, y, z, P @ A.T + b)


def test_error_map_interpolates_compensates_and_corrects_a_linear_field():
    rng = np.random.default_rng(3)
    A = rng.normal(scale=0.02, size=(3, 3))  # µm per mm
    b = rng.normal(scale=5, size=3)  # µm
    em = linear_map(A, b)
    assert em.error.shape == (5, 4, 3, 3) and em.uncertainty is None
    np.testing.assert_array_equal(em.y, [0, 50, 120, 300])
    p = rng.uniform([0, 0, -50], [400, 300, 150], size=(200, 3))
    want = p @ A.T + b
    for interpolation in ("linear", "cubic"):
        np.testing.assert_allclose(em.evaluate(p, interpolation=interpolation), want, atol=ROUND_OFF_UM)
    # Correction: x − e(x).
    np.testing.assert_allclose(em.correct(p), p - want * 1e-3, atol=1e-12)
    # Compensation: the command c' lands on the wanted point, c' + e(c') = c; the fixed point
    # converges like |∇e|^m, here (2e-5)^5, far below round-off.
    inner = rng.uniform([10, 10, -40], [390, 290, 140], size=(200, 3))
    c = em.compensate(inner, iterations=5)
    np.testing.assert_allclose(c + em.evaluate(c) * 1e-3, inner, atol=1e-12)
    assert c.shape == inner.shape and em.compensate(inner[0]).shape == (3,)
    # The input is not changed; a single point, a Fortran-ordered and an integer array are taken.
    before = p.copy()
    em.correct(p)
    np.testing.assert_array_equal(p, before)
    np.testing.assert_allclose(em.correct(p[7]), p[7] - want[7] * 1e-3, atol=1e-12)
    np.testing.assert_allclose(em.correct(np.asfortranarray(p)), p - want * 1e-3, atol=1e-12)
    q = np.array([[100, 50, 20], [300, 200, 100]])
    np.testing.assert_allclose(em.correct(q), q - (q @ A.T + b) * 1e-3, atol=1e-12)
    # out=: written and returned; the points themselves for an in-place correction.
    buf = np.empty_like(p)
    assert em.correct(p, out=buf) is buf
    np.testing.assert_allclose(buf, p - want * 1e-3, atol=1e-12)
    r = p.copy()
    em.correct(r, out=r)
    np.testing.assert_allclose(r, p - want * 1e-3, atol=1e-12)
    c2 = inner.copy()
    em.compensate(c2, iterations=5, out=c2)
    np.testing.assert_allclose(c2, c, atol=1e-15)
    with pytest.raises(trueaxis.Error, match="out must have the shape"):
        em.correct(p, out=np.empty((3, 3)))
    with pytest.raises(trueaxis.Error, match="C-ordered"):
        em.correct(p, out=np.empty_like(p, order="F"))
    with pytest.raises(trueaxis.Error, match="float64"):
        em.correct(p, out=np.empty(p.shape, dtype=np.float32))
    for bad in (np.nan, np.inf):
        with pytest.raises(trueaxis.Error, match="points contain NaN"):
            em.correct([[1.0, 2.0, bad]])
        with pytest.raises(trueaxis.Error, match="commands contain NaN"):
            em.compensate([[1.0, 2.0, bad]])


def test_error_map_refuses_outside_and_bad_shapes():
    em = linear_map(np.zeros((3, 3)), np.array([1.0, 2.0, 3.0]))
    with pytest.raises(trueaxis.Error, match="outside"):
        em.evaluate([[500.0, 0, 0]])
    np.testing.assert_allclose(em.evaluate([[500.0, 0, 0]], clamp=True), [[1, 2, 3]])
    with pytest.raises(trueaxis.Error, match=r"shape \(len\(x\), len\(y\), len\(z\), 3\) = \(2, 2, 2, 3\)"):
        trueaxis.ErrorMap([0, 1.0], [0, 1.0], [0, 1.0], np.zeros((2, 2, 3, 3)))
    with pytest.raises(trueaxis.Error, match="at least 2 nodes"):
        trueaxis.ErrorMap([0.0], [0, 1.0], [0, 1.0], np.zeros((1, 2, 2, 3)))
    with pytest.raises(trueaxis.Error):
        trueaxis.ErrorMap([1.0, 0], [0, 1.0], [0, 1.0], np.zeros((2, 2, 2, 3)))
    with pytest.raises(ValueError):
        em.evaluate([[1.0, 1.0, 1.0]], interpolation="quintic")


def plate(x, y):
    """A smooth 'true' plate, µm over mm."""
    return 2 * np.sin(x / 180) + 1.5 * np.cos(y / 130 + 0.4) + 0.8 * np.sin((x + y) / 95) + 3e-3 * x * y / 1000


def line(name, start, end, n, rng, slopes=False):
    start, end = np.asarray(start, float), np.asarray(end, float)
    length = np.linalg.norm(end - start)
    t = np.linspace(0, length, n)
    d = (end - start) / length
    h = plate(start[0] + t * d[0], start[1] + t * d[1]) + rng.uniform(-3, 3) + rng.uniform(-1e-2, 1e-2) * t
    out = {"name": name, "start": list(start), "direction": list(d), "spacing": length / (n - 1)}
    if slopes:
        out["slopes"] = np.diff(h) / out["spacing"] * 1e3  # µm/mm = 1e3 µrad
    else:
        out["heights"] = h
    return out


def network(rng, diagonal=True, slopes=False, y_lines=(0, 300, 600)):
    lines = [line(f"x{k}", (0, y), (600, y), 13, rng) for k, y in enumerate((0, 200, 400))]
    lines += [line(f"y{k}", (x, 0), (x, 400), 9, rng, slopes) for k, x in enumerate(y_lines)]
    if diagonal:
        lines.append(line("d", (0, 0), (600, 400), 11, rng))
    return lines


def residual_from_plane(x, y, h, twist=False):
    cols = [np.ones_like(x), x, y] + ([x * y] if twist else [])
    M = np.stack(cols, axis=1)
    return h - M @ np.linalg.lstsq(M, h, rcond=None)[0]


def test_surface_recovers_a_known_plate():
    rng = np.random.default_rng(7)
    s = trueaxis.surface(network(rng, slopes=True))
    p = s["points"]
    assert s["unobservable"] == ["plane"] and s["closure"]["rms"] < ROUND_OFF_UM
    want = residual_from_plane(p["x"], p["y"], plate(p["x"], p["y"]))
    np.testing.assert_allclose(p["height"], want, atol=ROUND_OFF_UM)
    # Without a diagonal, lsq and seed agree with the truth up to plane and twist.
    for method in ("lsq", "boundary"):
        # The two-point patent's construction hangs the x lines on the two boundary y lines.
        y_lines = (0, 600) if method == "boundary" else (0, 300, 600)
        s = trueaxis.surface(network(rng, diagonal=False, y_lines=y_lines), method=method)
        assert "twist" in s["unobservable"]
        p = s["points"]
        np.testing.assert_allclose(residual_from_plane(p["x"], p["y"], p["height"], True),
                                   residual_from_plane(p["x"], p["y"], plate(p["x"], p["y"]), True),
                                   atol=ROUND_OFF_UM)
    assert s["grid"] is None  # the seed layout's stations do not fill a lattice
    assert s["flatness"]["min_zone"] <= s["flatness"]["ls"]
    # A layout whose stations fill a lattice also gives the heights as a grid.
    lattice = [line(f"x{k}", (0, y), (600, y), 4, rng) for k, y in enumerate((0, 200, 400))]
    lattice += [line(f"y{k}", (x, 0), (x, 400), 3, rng) for k, x in enumerate((0, 200, 400, 600))]
    g = trueaxis.surface(lattice)["grid"]
    np.testing.assert_array_equal(g["x"], [0, 200, 400, 600])
    np.testing.assert_array_equal(g["y"], [0, 200, 400])
    X, Y = np.meshgrid(g["x"], g["y"])
    np.testing.assert_allclose(residual_from_plane(X.ravel(), Y.ravel(), g["height"].ravel(), True),
                               residual_from_plane(X.ravel(), Y.ravel(), plate(X, Y).ravel(), True),
                               atol=ROUND_OFF_UM)


def test_surface_bad_lines():
    rng = np.random.default_rng(1)
    lines = network(rng)
    del lines[0]["heights"]
    with pytest.raises(trueaxis.Error, match=r"lines\[0\] needs exactly one of 'heights'"):
        trueaxis.surface(lines)
    lines = network(rng)
    lines[1]["colour"] = "red"
    with pytest.raises(trueaxis.Error, match="unknown key 'colour'"):
        trueaxis.surface(lines)
    apart = [line("a", (0, 0), (100, 0), 5, rng), line("b", (0, 50), (100, 50), 5, rng)]
    with pytest.raises(trueaxis.Error, match="cross"):
        trueaxis.surface(apart)
    with pytest.raises(trueaxis.Error, match="method"):
        trueaxis.surface(network(rng), method="magic")


def read_gnuplot():
    out, current = {}, None
    for row in (MOODY / "gnuplot.dat").read_text().splitlines():
        if row.startswith("# ") and row.endswith(".txt"):
            current = row[2:-4]
            out[current] = []
        elif current and row.strip() and not row.startswith("#"):
            out[current].append([float(v) for v in row.split()])
    return out


def test_moody_reproduces_the_published_tables():
    s = trueaxis.moody(str(MOODY))
    pub = read_gnuplot()
    p = s["points"]
    foot = 4.0 * 25.4  # Config.txt: "I 4.0", a 4-inch foot; the tables count in feet
    compared = 0
    for k in range(len(p["height"])):
        want = pub[s["lines"][p["line"][k]]][int(p["station"][k])]
        assert p["x"][k] / foot == pytest.approx(want[0], abs=1e-9)
        h = p["height"][k] / 25.4 * 1e2  # µm → tens of microinches
        assert h == pytest.approx(want[2], abs=MOODY_PRINTED)
        compared += 1
    assert compared == sum(len(v) for v in pub.values())
    lsq = trueaxis.moody(str(MOODY), method="lsq")
    assert 0 < lsq["closure"]["rms"] < lsq["closure"]["max"]


def small_machine(seed=4):
    return trueaxis.Machine.random(seed=seed, ranges=[[0, 300], [0, 200], [0, 150]])


def test_measure_space_noise_free_equals_the_truth():
    m = small_machine()
    s = trueaxis.measure_space(m, spacing=50)
    em = s["map"]
    assert em.error.shape == (7, 5, 4, 3)
    assert s["truth"]["max"] < SPACE_ROUND_OFF_UM
    assert s["unobservable"] == ["rigid-body motion (6)"]
    # Independent check: the machine's own errors at the nodes, with the least-squares rigid-body
    # motion t + ω × p removed (the map's stated reference).
    X, Y, Z = np.meshgrid(em.x, em.y, em.z, indexing="ij")
    P = np.stack([X, Y, Z], axis=-1).reshape(-1, 3)
    E = m.error(P)
    c = P - P.mean(axis=0)
    # Columns: translation (3) and rotation (3), e ≈ t + ω × c.
    rows = []
    for p in c:
        rows.append(np.hstack([np.eye(3), -np.array([[0, -p[2], p[1]], [p[2], 0, -p[0]], [-p[1], p[0], 0]])]))
    M = np.vstack(rows)
    sol = np.linalg.lstsq(M, E.reshape(-1), rcond=None)[0]
    truth = (E.reshape(-1) - M @ sol).reshape(-1, 3)
    np.testing.assert_allclose(em.error.reshape(-1, 3), truth, atol=SPACE_ROUND_OFF_UM)
    # Without diagonals the squareness errors are named unobservable.
    s2 = trueaxis.measure_space(m, spacing=50, diagonals=False)
    assert any("squareness" in u for u in s2["unobservable"])


def test_measure_space_with_noise_compensates_to_the_predicted_level():
    m = small_machine(seed=6)
    s = trueaxis.measure_space(m, spacing=50, probe_noise=0.05, laser_noise=0.05, monte_carlo=12,
                               seed=3, verify=500)
    v = s["verification"]
    assert s["map"].uncertainty is not None
    assert v["points"] == 500 and v["improvement"] > 3
    assert 0.5 * v["predicted_rms"] < v["after_rms"] < 1.5 * v["predicted_rms"]
    again = trueaxis.verify_compensation(m, s["map"], points=500, seed=3)
    assert again["after_rms"] == pytest.approx(v["after_rms"], rel=1e-12)


def test_space_json_from_the_cli_loads_and_exports(tmp_path):
    m = small_machine(seed=8)
    m.save(str(tmp_path / "m.json"))
    (tmp_path / "plan.json").write_text(json.dumps({"spacing": 50, "seed": 2}))
    subprocess.run([TRUEAXIS, "space", "--machine", str(tmp_path / "m.json"), "--plan",
                    str(tmp_path / "plan.json"), "-o", str(tmp_path / "space.json"), "--quiet"], check=True)
    em = trueaxis.ErrorMap.load(str(tmp_path / "space.json"))
    direct = trueaxis.measure_space(m, plan=str(tmp_path / "plan.json"))["map"]
    # space.json stores µm with round-trip precision.
    np.testing.assert_allclose(em.error, direct.error, atol=ROUND_OFF_UM)
    n = em.export_linuxcnc(str(tmp_path / "x.comp"), "x", type=0)
    rows = np.loadtxt(tmp_path / "x.comp")
    assert rows.shape == (n, 3) and np.all(np.diff(rows[:, 0]) > 0)
    em.to_csv(str(tmp_path / "map.csv"))
    assert (tmp_path / "map.csv").read_text().startswith("x,y,z,ex_um,ey_um,ez_um")
    with pytest.raises(trueaxis.Error, match="axis must be"):
        em.export_linuxcnc(str(tmp_path / "w.comp"), "w")


def test_measure_space_without_monte_carlo_states_no_uncertainty():
    # No figure that was not computed: the map's uncertainty is None, the prediction a bound.
    m = trueaxis.Machine.random(seed=2, ranges=[[0, 400], [0, 300], [0, 200]])
    s = trueaxis.measure_space(m, spacing=100, probe_noise=0.05, verify=200)
    v = s["verification"]
    assert v["uncertainty_rms"] is None
    assert v["predicted_is_lower_bound"]
    assert v["predicted_rms"] == pytest.approx(v["interpolation_rms"])
