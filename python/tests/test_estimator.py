"""cablevib.Estimator: the real-time estimator from Python.

References: the command line (`cablevib analyze --realtime --json`, the same library through
another front end) compared bit for bit; the statics of the answer (equilibrium and bounds)
and the static stiffness recomputed here in numpy from the anchors and tensions (an
independent formulation: no code shared with the library)."""

import json
import math

import numpy as np
import pytest

import cablevib
from conftest import SCENES

# Position and T_min overrides compared with the command line, per scene.
CASES = [
    ("spatial-paper", None, None),
    ("spatial-paper", (0.3, 0.1, 1.2), None),
    ("spatial-paper", (-0.5, 0.25, 1.0), 80.0),
    ("planar-paper", None, None),
    ("planar-paper", (0.4, -0.2, 0.0), 35.0),
]


def cli_realtime(run_cli, scene, position=None, t_min=None, *extra):
    args = ["analyze", scene, "--realtime", "--json", *extra]
    if position is not None:
        args += ["--position", ",".join(repr(float(x)) for x in position)]
    if t_min is not None:
        args += ["--t-min", repr(float(t_min))]
    p = run_cli(*args)
    return p.returncode, json.loads(p.stdout)


def nan_or(x):
    """The CLI writes non-finite numbers as null."""
    return math.nan if x is None else x


def assert_same_as_cli(e, j):
    assert e.status == j["status"]
    assert e.error == j["error"]
    # Exact: both sides hold the same f64 (JSON carries the shortest round-trip form).
    np.testing.assert_array_equal(e.tensions_n, [nan_or(x) for x in j["tensions_n"]])
    # The CLI publishes the full stiffness: 3 × 3 for a point mass, 6 × 6 for a rigid body.
    np.testing.assert_array_equal(
        e.stiffness, [[nan_or(x) for x in r] for r in j["stiffness_n_m"]]
    )
    for key in ("f1_hz", "f1_ee_participation", "ee_mode_hz", "ee_mode_participation",
                "eigen_residual"):
        got, want = getattr(e, key), nan_or(j[key])
        assert got == want or (math.isnan(got) and math.isnan(want)), (key, got, want)
    assert e.eigen_evaluations == j["eigen_evaluations"]


@pytest.mark.parametrize("scene,position,t_min", CASES)
def test_update_equals_the_cli_bit_for_bit(run_cli, scene, position, t_min):
    s = cablevib.Scene.load(scene)
    rc, j = cli_realtime(run_cli, scene, position, t_min)
    assert rc == 0
    # `analyze --realtime` is the service's cold cycle: the real-time preset.
    e = cablevib.Estimator(s, realtime=True).update(
        s.ee_position_m if position is None else position, t_min=t_min
    )
    assert e.ok and e.status_code == 0
    assert_same_as_cli(e, j)


def test_rigid_scene_equals_the_cli(run_cli):
    path = str(SCENES / "box_6dof.toml")
    s = cablevib.Scene.load(path)
    rc, j = cli_realtime(run_cli, path)
    assert rc == 0
    e = cablevib.Estimator(s, realtime=True).update(
        s.ee_position_m, orientation=[1.0, 0.0, 0.0, 0.0]
    )
    assert_same_as_cli(e, j)
    k = e.stiffness
    assert k.shape == (6, 6)
    np.testing.assert_array_equal(k[:3, :3], e.stiffness_n_m)


def test_refused_pose_has_the_clis_status_and_message(run_cli):
    s = cablevib.Scene.load("spatial-paper")
    rc, j = cli_realtime(run_cli, "spatial-paper", (9.0, 0.0, 1.2))
    assert rc == 1
    e = cablevib.Estimator(s, realtime=True).update([9.0, 0.0, 1.2])
    assert e.status == "tension_infeasible" and e.status_code == 1 and not e.ok
    assert math.isnan(e.f1_hz) and np.isnan(e.stiffness_n_m).all()
    assert_same_as_cli(e, j)


def statics_reference(s, position, tensions):
    """Net force of cables and gravity (N) and the static stiffness (N/m) of straight
    cables: Σ EA/L s sᵀ + T/L (I − s sᵀ) (the series of N equal FEM elements of a cable has
    the stiffness of one element of length L)."""
    text = (SCENES / {"spatial-paper": "spatial_paper.toml",
                      "planar-paper": "planar_paper.toml"}[s.name]).read_text()
    import tomllib

    c = tomllib.loads(text)["cable"]
    ea = c["youngs_modulus"] * c["area"]
    p = np.asarray(position, dtype=float)
    force = s.ee_mass_kg * s.gravity_m_s2 if s.weight_carried else np.zeros(3)
    k = np.zeros((3, 3))
    for a, t in zip(s.anchors_m, tensions):
        d = a - p
        length = np.linalg.norm(d)
        u = d / length
        force = force + t * u
        k += ea / length * np.outer(u, u) + t / length * (np.eye(3) - np.outer(u, u))
    return force, k


@pytest.mark.parametrize("scene,position,t_min", CASES)
def test_statics_against_an_independent_formulation(scene, position, t_min):
    s = cablevib.Scene.load(scene)
    pos = s.ee_position_m if position is None else np.asarray(position)
    t_min = s.t_min_n if t_min is None else t_min
    e = cablevib.Estimator(s).update(pos, t_min=t_min)
    t = e.tensions_n
    force, k = statics_reference(s, pos, t)
    # Equilibrium and bounds: the active-set solver's residual is at rounding level, so
    # 1e-9 of the tension scale is a generous bound on a ~1e-13 residual.
    assert np.linalg.norm(force) <= 1e-9 * np.abs(t).sum()
    assert (t >= t_min * (1 - 1e-12)).all() and (t <= s.t_max_n * (1 + 1e-12)).all()
    # Same formula, different summation order: differences are rounding (~1e-16 relative);
    # 1e-12 of the matrix norm leaves room without hiding a wrong term (T/L is ~1e-4 of it).
    np.testing.assert_allclose(e.stiffness_n_m, k, rtol=0, atol=1e-12 * np.linalg.norm(k))


def test_status_codes_of_bad_input():
    s = cablevib.Scene.load("spatial-paper")
    est = cablevib.Estimator(s)
    p = s.ee_position_m
    cases = [
        (dict(position=[math.nan, 0.0, 1.25]), "invalid_input", 2),
        (dict(position=p, orientation=[2.0, 0.0, 0.0, 0.0]), "non_unit_quaternion", 7),
        (dict(position=p, t_min=1000.0), "t_min_out_of_range", 8),
        (dict(position=p, t_min=-1.0), "t_min_out_of_range", 8),
    ]
    for kwargs, status, code in cases:
        e = est.update(**kwargs)
        assert (e.status, e.status_code, e.ok) == (status, code, False), kwargs
        assert math.isnan(e.f1_hz) and e.error
    assert est.update(p).ok


def test_a_rotation_on_a_point_mass_is_refused_as_by_the_estimator_and_the_service():
    """One rule (the estimator's input check, `Pose::has_identity_orientation`): on a point
    mass an orientation whose vector part exceeds 1e-3 of its norm is `invalid_input`, the
    identity (either sign, or within that tolerance) is estimated; a rigid scene takes the
    rotation. tests/hard_cases/inputs.rs and service/tests/ipc/hostile_client.rs check the same rule in
    the library and through the service."""
    s = cablevib.Scene.load("spatial-paper")
    est = cablevib.Estimator(s)
    p = s.ee_position_m
    half = math.sqrt(0.5)
    for q in ([half, 0.0, 0.0, half], [math.sqrt(1 - 0.0011**2), 0.0011, 0.0, 0.0]):
        e = est.update(p, orientation=q)
        assert (e.status, e.status_code, e.ok) == ("invalid_input", 2, False), q
        assert "point-mass" in e.error
        with pytest.raises(cablevib.CablevibError, match="point-mass"):
            est.t_min_for_f1(p, 5.0, orientation=q)
    plain = est.update(p)
    for q in ([1.0, 0.0, 0.0, 0.0], [-1.0, 0.0, 0.0, 0.0], [math.sqrt(1 - 0.0009**2), 0.0, 0.0009, 0.0]):
        e = est.update(p, orientation=q)
        assert e.ok and e.f1_hz == plain.f1_hz, q
    rigid = cablevib.Estimator(cablevib.Scene.load(str(SCENES / "box_6dof.toml")))
    r = rigid.update(rigid.scene.ee_position_m, orientation=[math.cos(0.05), 0.0, 0.0, math.sin(0.05)])
    assert r.status != "invalid_input", r.error


def test_per_cable_t_min_equal_values_is_the_uniform_update():
    s = cablevib.Scene.load("spatial-paper")
    a = cablevib.Estimator(s).update([0.2, 0.1, 1.3], t_min=70.0)
    b = cablevib.Estimator(s).update([0.2, 0.1, 1.3], t_min=np.full(s.n_cables, 70.0))
    assert a.f1_hz == b.f1_hz
    np.testing.assert_array_equal(a.tensions_n, b.tensions_n)
    raised = cablevib.Estimator(s).update([0.2, 0.1, 1.3], t_min=[70.0] * 7 + [120.0])
    assert raised.ok and raised.tensions_n[-1] >= 120.0 * (1 - 1e-12)


def test_wrong_shapes_raise():
    est = cablevib.Estimator(cablevib.Scene.load("spatial-paper"))
    with pytest.raises(ValueError, match=r"position .* expected 3 numbers, got 2"):
        est.update([0.0, 1.0])
    with pytest.raises(TypeError, match=r"position"):
        est.update("0,0,1")
    with pytest.raises(ValueError, match=r"t_min: expected 8 numbers"):
        est.update([0.0, 0.0, 1.25], t_min=[60.0, 60.0])
    with pytest.raises(ValueError, match=r"orientation"):
        est.update([0.0, 0.0, 1.25], orientation=[1.0, 0.0, 0.0])


def test_bytes_and_text_are_not_numbers():
    # bytearray(b'\0\0\1') iterates as 0, 0, 1: it was taken as a position in m.
    est = cablevib.Estimator(cablevib.Scene.load("spatial-paper"))
    for bad in (bytearray(b"\0\0\1"), b"\0\0\1", memoryview(b"\0\0\1"), "001"):
        with pytest.raises(TypeError, match=r"position .*expected numbers"):
            est.update(bad)
        with pytest.raises(TypeError, match=r"orientation .*expected numbers"):
            est.update([0.0, 0.0, 1.25], orientation=bytes(4) if not isinstance(bad, str) else "1000")
    with pytest.raises(TypeError, match=r"t_min: expected numbers"):
        est.update([0.0, 0.0, 1.25], t_min=bytes(8))


def test_unbuildable_scene_has_the_clis_message(run_cli, tmp_path):
    path = tmp_path / "away.toml"
    text = (SCENES / "spatial_paper.toml").read_text()
    # The auto model with every cable at t_max: no pose to choose the model at.
    text = text.replace("t_min = 60.0", "t_min = 350.0").replace('element = "fem"', 'element = "auto"')
    path.write_text(text)
    s = cablevib.Scene.load(str(path))
    with pytest.raises(cablevib.CablevibError) as e:
        cablevib.Estimator(s)
    p = run_cli("analyze", str(path), "--realtime")
    assert p.returncode == 1
    assert f"cablevib: {e.value}" == p.stderr.strip()
    assert str(e.value).startswith("scene `spatial-paper` at (0, 0, 1.25) m:")


def circle(n, step_m):
    """n poses on the paper's 0.75 m circle at z = 1.25 m, `step_m` apart."""
    phi = np.arange(n) * step_m / 0.75
    return np.column_stack([0.75 * np.cos(phi), 0.75 * np.sin(phi), np.full(n, 1.25)])


def test_warm_sweep_matches_cold_estimates():
    s = cablevib.Scene.load("spatial-paper")
    warm = cablevib.Estimator(s)
    path = circle(120, 0.002)
    estimates = [warm.update(p) for p in path]
    assert all(e.ok for e in estimates)
    assert estimates[0].cold_start and not any(e.cold_start for e in estimates[1:])
    for i in range(0, len(path), 17):
        cold = cablevib.Estimator(s).update(path[i])
        assert cold.cold_start
        # The warm path converges to the same root: the warm-vs-cold bounds of
        # docs/accuracy.md (f1 ≤ 1e-11, end-effector mode ≤ 1e-10 relative).
        assert abs(estimates[i].f1_hz / cold.f1_hz - 1) <= 1e-11
        assert abs(estimates[i].ee_mode_hz / cold.ee_mode_hz - 1) <= 1e-10
    f1 = np.array([e.f1_hz for e in estimates])
    assert np.isfinite(f1).all() and f1.min() > 0


def test_t_min_for_f1_is_the_smallest_t_min_reaching_f1():
    s = cablevib.Scene.load("spatial-paper")
    est = cablevib.Estimator(s)
    p = [0.3, -0.2, 1.2]
    before = est.update(p)
    required = before.f1_hz * 1.05
    ans = est.t_min_for_f1(p, required)
    # The query stops within 1e-10 relative of the requirement (F1_TOL_REL), at or above it.
    assert required <= ans.f1_hz <= required * (1 + 1e-9)
    assert ans.evaluations > 0 and ans.t_min_n > s.t_min_n
    assert 0 < ans.resolution_n < ans.t_min_n
    # The forward path agrees at the answer (the same model, the cycle's solver).
    at = cablevib.Estimator(s).update(p, t_min=ans.t_min_n)
    assert abs(at.f1_hz / ans.f1_hz - 1) <= 1e-9
    # And a slightly smaller T_min does not reach the requirement (f1 ∝ √T_min, so 1e-6
    # less T_min is ~5e-7 less f1, well beyond the 1e-9 resolution).
    below = cablevib.Estimator(s).update(p, t_min=ans.t_min_n * (1 - 1e-6))
    assert below.f1_hz < required
    # The cycle's warm state is untouched.
    assert not est.update(p).cold_start


def test_t_min_for_f1_errors():
    est = cablevib.Estimator(cablevib.Scene.load("spatial-paper"))
    with pytest.raises(cablevib.CablevibError, match=r"^f1 ≥ 1000\.0000 Hz is unreachable: "
                       r"the most any feasible T_min gives is [0-9.]+ Hz \(at [0-9.]+ N\)$"):
        est.t_min_for_f1([0.0, 0.0, 1.25], 1000.0)
    with pytest.raises(cablevib.CablevibError, match=r"^required f1 -1 Hz must be finite"):
        est.t_min_for_f1([0.0, 0.0, 1.25], -1.0)
    # A pose infeasible at every T_min (the query checks feasibility, not the frame).
    with pytest.raises(cablevib.CablevibError, match=r"^tension infeasible: "):
        est.t_min_for_f1([9.0, 0.0, 1.25], 10.0)


def test_estimator_scene_and_repr():
    s = cablevib.Scene.load("planar-paper")
    est = cablevib.Estimator(s)
    assert est.scene.name == "planar-paper" and est.auto_choice is None
    assert "planar-paper" in repr(est)
    e = est.update(s.ee_position_m)
    assert "ok" in repr(e)
    est.reset()
    assert est.update(s.ee_position_m).cold_start


def test_to_dict_has_every_attribute():
    s = cablevib.Scene.load("spatial-paper")
    est = cablevib.Estimator(s)
    for e in (est.update([0.1, 0.2, 1.1]), est.update([9.0, 0.0, 1.0])):
        d = e.to_dict()
        names = {n for n in dir(type(e)) if not n.startswith("_") and n != "to_dict"}
        assert set(d) == names
        for k, v in d.items():
            np.testing.assert_array_equal(v, getattr(e, k), err_msg=k)
