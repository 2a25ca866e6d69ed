"""Estimator.sweep / cablevib.sweep (many poses in one call, numpy in and out, worker
threads) and Scene.from_arrays (a scene from arrays, pickled through its TOML text).

References: the per-pose `Estimator.update` loop (the same estimator driven pose by pose
from Python: the sweep's definition) compared bit for bit; the principal stiffnesses against
numpy's own symmetric eigensolver on `Estimate.stiffness_n_m` (an independent eigensolver);
Scene.from_arrays' errors against the command line's on a scene file written by hand."""

import math
import pickle
import subprocess
import sys

import numpy as np
import pytest

import cablevib
from conftest import REPO, SCENES, cli_error

KEYS = ("f1_hz", "f1_ee_participation", "ee_mode_hz", "ee_mode_participation")


def grid(n_side=6, z=(0.6, 1.9)):
    """A workspace grid of the paper robot plus poses it refuses (outside the frame, NaN)."""
    xs = np.linspace(-1.0, 1.0, n_side)
    zs = np.linspace(*z, 3)
    p = np.array([(x, y, zz) for zz in zs for y in xs for x in xs], dtype=float)
    bad = np.array([[5.0, 0.0, 1.0], [np.nan, 0.0, 1.0], [1.25, 1.25, 2.5]])
    return np.vstack([p[: len(p) // 2], bad, p[len(p) // 2 :]])


def loop(scene, positions, orientations=None, t_min=None, chunk=256):
    """The definition: each chunk of `chunk` poses by a fresh Estimator, pose by pose."""
    rows = []
    for a in range(0, len(positions), chunk):
        est = cablevib.Estimator(scene)
        for i in range(a, min(a + chunk, len(positions))):
            q = None if orientations is None else orientations[i]
            t = None if t_min is None else t_min[i]
            rows.append(est.update(positions[i], orientation=q, t_min=t))
    return rows


def assert_equal_to_loop(r, rows):
    n = len(rows)
    assert r["status"].tolist() == [e.status for e in rows]
    assert r["status_code"].tolist() == [e.status_code for e in rows]
    assert r["ok"].tolist() == [e.ok for e in rows]
    np.testing.assert_array_equal(r["tensions_n"], np.array([e.tensions_n for e in rows]))
    for k in KEYS:
        np.testing.assert_array_equal(r[k], np.array([getattr(e, k) for e in rows]), err_msg=k)
    assert r["tensions_n"].shape[0] == n and r["stiffness_principal_n_m"].shape == (n, 3)


@pytest.mark.parametrize("chunk", [1, 7, 256])
def test_sweep_equals_the_update_loop_bit_for_bit_for_any_thread_count(chunk):
    s = cablevib.Scene.load("spatial-paper")
    p = grid()
    rows = loop(s, p, chunk=chunk)
    est = cablevib.Estimator(s)
    est.update([0.3, 0.2, 1.0])  # the estimator's own warm state is not the sweep's
    for threads in (1, 2, 3, 0):
        r = est.sweep(p, threads=threads, chunk_poses=chunk)
        assert_equal_to_loop(r, rows)
    assert set(r["status"]) >= {"ok", "invalid_input"}, set(r["status"])
    r2 = cablevib.sweep(s, p, chunk_poses=chunk)
    for k in KEYS + ("tensions_n", "stiffness_principal_n_m", "status_code"):
        np.testing.assert_array_equal(r2[k], r[k])


def test_principal_stiffness_against_numpy_eigvalsh():
    s = cablevib.Scene.load("spatial-paper")
    p = grid(4)
    r = cablevib.sweep(s, p, chunk_poses=5)
    for i, e in enumerate(loop(s, p, chunk=5)):
        if not e.ok:
            assert np.isnan(r["stiffness_principal_n_m"][i]).all()
            continue
        k = np.asarray(e.stiffness_n_m)
        want = np.linalg.eigvalsh((k + k.T) / 2)
        # Two eigensolvers on the same symmetric matrix agree to a few ulps of its norm.
        np.testing.assert_allclose(
            r["stiffness_principal_n_m"][i], want, rtol=0, atol=1e-9 * np.abs(want).max()
        )
        assert r["k_min_n_m"][i] == r["stiffness_principal_n_m"][i, 0]


def test_orientations_and_t_min_per_pose_and_per_cable():
    s = cablevib.Scene.load(SCENES / "box_6dof.toml")
    rng = np.random.default_rng(1)
    n = 40
    p = np.column_stack([rng.uniform(-0.6, 0.6, (n, 2)), rng.uniform(0.8, 1.7, n)])
    axis = rng.normal(size=(n, 3))
    axis /= np.linalg.norm(axis, axis=1)[:, None]
    ang = rng.uniform(-0.2, 0.2, n)
    q = np.column_stack([np.cos(ang / 2), np.sin(ang / 2)[:, None] * axis])
    t1 = rng.uniform(40.0, 120.0, n)
    tc = rng.uniform(40.0, 120.0, (n, s.n_cables))
    for t in (None, t1, tc):
        r = cablevib.sweep(s, p, q, t, threads=2, chunk_poses=9)
        assert_equal_to_loop(r, loop(s, p, q, t, chunk=9))
        np.testing.assert_array_equal(r["orientations_wxyz"], q)
    np.testing.assert_array_equal(r["t_min_n"], tc.min(axis=1))


def test_bad_shapes_are_value_errors():
    s = cablevib.Scene.load("spatial-paper")
    est = cablevib.Estimator(s)
    p = np.zeros((4, 3))
    for args, msg in [
        ((np.zeros((4, 2)),), r"positions: expected shape \(n, 3\) \(m\), got \(4, 2\)"),
        ((np.zeros(3),), r"positions: expected shape \(n, 3\) \(m\), got \(3,\)"),
        ((p, np.zeros((3, 4))), r"orientations: expected shape \(4, 4\)"),
        ((p, None, np.zeros(5)), r"t_min: expected shape \(4,\) or \(4, 8\) \(N\), got \(5,\)"),
    ]:
        with pytest.raises(ValueError, match=msg):
            est.sweep(*args)
    with pytest.raises(ValueError, match="chunk_poses 0"):
        est.sweep(p, chunk_poses=0)
    with pytest.raises(TypeError):
        est.sweep(b"\0" * 24)
    assert cablevib.sweep(s, np.zeros((0, 3)))["f1_hz"].shape == (0,)


def paper_arrays(**over):
    """The paper's spatial robot as arrays (scenes/spatial_paper.toml's values)."""
    a = np.array([[x, y, z] for z in (2.5, 0.0)
                  for (x, y) in ((1.25, 1.25), (-1.25, 1.25), (-1.25, -1.25), (1.25, -1.25))])
    kw = dict(anchors_m=a, ee_mass_kg=30.0, ee_position_m=[0.0, 0.0, 1.25],
              name="spatial-paper", youngs_modulus_pa=2.01e10, area_m2=50.265e-6,
              weight_per_length_n_m=0.251, t_min_n=60.0, t_max_n=350.0, element="fem",
              elements=40, sag=False)
    kw.update(over)
    return kw


def test_scene_from_arrays_is_the_scene_file():
    s = cablevib.Scene.from_arrays(**paper_arrays())
    ref = cablevib.Scene.load("spatial-paper")
    assert repr(s) == repr(ref)
    np.testing.assert_array_equal(s.anchors_m, ref.anchors_m)
    p = grid(3)
    a, b = cablevib.sweep(s, p), cablevib.sweep(ref, p)
    for k in KEYS + ("tensions_n",):
        np.testing.assert_array_equal(a[k], b[k])
    # Per-cable material and bounds go to each [[cables]] entry.
    s2 = cablevib.Scene.from_arrays(**paper_arrays(area_m2=np.full(8, 50.265e-6),
                                                   cable_t_min_n=np.full(8, 70.0)))
    assert "area = 5.0265e-5" in s2.toml
    # numpy scalars and 0-d arrays are one number (every cable's), as a float is.
    for e in (np.float64(2.01e10), np.array(2.01e10), 20100000000):
        s3 = cablevib.Scene.from_arrays(**paper_arrays(youngs_modulus_pa=e))
        assert "[cable]\nyoungs_modulus = " in s3.toml and repr(s3) == repr(ref)
    np.testing.assert_array_equal(s2.cable_t_min_n, np.full(8, 70.0))


def test_scenes_pickle_through_their_toml_text(tmp_path):
    f = tmp_path / "moved.toml"
    f.write_text((SCENES / "box_6dof.toml").read_text())
    scenes = [cablevib.Scene.load("spatial-paper"), cablevib.Scene.load(f),
              cablevib.Scene.from_arrays(**paper_arrays(elements=12))]
    blobs = [pickle.dumps(s) for s in scenes]
    f.unlink()  # the pickled scene no longer needs its file
    p = np.array([[0.1, 0.2, 1.1], [0.0, 0.0, 1.25]])
    for s, b in zip(scenes, blobs):
        t = pickle.loads(b)
        assert repr(t) == repr(s)
        for k in KEYS:
            np.testing.assert_array_equal(cablevib.sweep(t, p)[k], cablevib.sweep(s, p)[k])
    # And in another interpreter.
    code = "import pickle, sys; s = pickle.loads(sys.stdin.buffer.read()); print(repr(s))"
    out = subprocess.run([sys.executable, "-c", code], input=blobs[2], capture_output=True,
                         check=True).stdout.decode().strip()
    assert out == repr(scenes[2])


PAPER_TOML = (SCENES / "spatial_paper.toml").read_text()
FIRST_ANCHOR = "anchor = [1.25, 1.25, 2.5]"
# (from_arrays overrides, the same change written by hand into the scene file)
BAD = [
    ("nan anchor",
     dict(anchors_m=np.vstack([[np.nan, 1.25, 2.5], paper_arrays()["anchors_m"][1:]])),
     lambda t: t.replace(FIRST_ANCHOR, "anchor = [nan, 1.25, 2.5]")),
    ("one cable",
     dict(anchors_m=paper_arrays()["anchors_m"][:1]),
     lambda t: t[: t.index("[[cables]]", t.index("[[cables]]") + 1)]),
    ("anchor of two numbers",
     dict(anchors_m=[[1.25, 1.25]] + paper_arrays()["anchors_m"][1:].tolist()),
     lambda t: t.replace(FIRST_ANCHOR, "anchor = [1.25, 1.25]")),
    ("negative mass", dict(ee_mass_kg=-30.0),
     lambda t: t.replace("mass = 30.0", "mass = -30.0")),
    ("infinite area", dict(area_m2=math.inf),
     lambda t: t.replace("area = 50.265e-6", "area = inf")),
]


@pytest.mark.parametrize("what,over,edit", BAD, ids=[b[0] for b in BAD])
def test_bad_arrays_raise_the_scene_files_error(run_cli, tmp_path, what, over, edit):
    path = tmp_path / "bad.toml"
    path.write_text(edit(PAPER_TOML))
    want = cli_error(run_cli("analyze", str(path)))
    with pytest.raises(cablevib.CablevibError) as e:
        cablevib.Scene.from_arrays(**paper_arrays(**over), source=str(path))
    assert str(e.value) == want
    assert "\n" not in want
    with pytest.raises(cablevib.CablevibError) as e2:
        cablevib.Scene.load(path)
    assert str(e2.value) == want


def test_from_arrays_errors_name_the_argument():
    """A required argument left out or of the wrong type names the argument, not a line of
    the TOML text from_arrays writes (before: `<arrays>: TOML parse error at line 13` and a
    snippet of that text)."""
    kw = paper_arrays()
    del kw["t_min_n"]
    for over, want in [
        (kw, "<arrays>: argument `t_min_n` is required"),
        (paper_arrays(element="bogus"),
         "<arrays>: argument `element`: unknown variant `bogus`, expected one of"),
        (paper_arrays(ee_mass_kg="heavy"),
         "<arrays>: argument `ee_mass_kg`: invalid type: string \"heavy\", expected f64"),
    ]:
        with pytest.raises(cablevib.CablevibError) as e:
            cablevib.Scene.from_arrays(**over)
        msg = str(e.value)
        assert msg.startswith(want) and "line" not in msg and "\n" not in msg, msg
    with pytest.raises(ValueError, match=r"^anchors_m: 0 rows"):
        cablevib.Scene.from_arrays(**paper_arrays(anchors_m=np.zeros((0, 3))))


def test_from_arrays_row_count_mismatch_is_a_value_error():
    with pytest.raises(ValueError, match="attachments_m: 3 values for 8 cables"):
        cablevib.Scene.from_arrays(**paper_arrays(attachments_m=np.zeros((3, 3))))
    with pytest.raises(ValueError, match="area_m2: 2 values for 8 cables"):
        cablevib.Scene.from_arrays(**paper_arrays(area_m2=[1e-5, 1e-5]))


def test_speed_script_runs_and_agrees():
    """examples/sweep_speed.py (the measuring script of docs/studies.md) on a few poses: it
    checks that sweep on 1 thread and on all cores equals the Python loop, and prints poses/s
    (printed, not asserted)."""
    p = subprocess.run([sys.executable, str(REPO / "python" / "examples" / "sweep_speed.py"),
                        "--poses", "600"], capture_output=True, text=True, check=False)
    assert p.returncode == 0, p.stderr
    assert "equal bit for bit" in p.stdout, p.stdout


def test_sweep_releases_the_gil():
    """Another Python thread runs while a sweep computes (it would be stopped for the whole
    sweep if the GIL were held)."""
    import threading

    s = cablevib.Scene.load("spatial-paper")
    p = np.tile(grid(6), (8, 1))
    done = threading.Event()
    t = threading.Thread(target=lambda: (cablevib.sweep(s, p, threads=1), done.set()))
    ticks = 0
    t.start()
    while not done.is_set():
        ticks += 1
        done.wait(0.001)
    t.join()
    assert ticks > 10, ticks
