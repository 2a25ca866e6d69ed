"""cablevib.analyze against `cablevib analyze --json`: the same library function
(study::analysis::analyze) behind two front ends, so every number must be equal to the last
bit (JSON carries each f64 in its shortest round-trip form, which json.loads reads back
exactly). Timings are the only fields that differ between two runs."""

import math

import numpy as np
import pytest

import cablevib
from conftest import SCENES, cli_error

# Seconds measured in each run: compared for type only.
TIMING = {"solve_seconds", "dense_seconds", "structured_seconds", "speedup"}

# (scene, python keyword arguments); the CLI gets the same as flags.
CASES = [
    ("spatial-paper", {}),
    ("spatial-paper", {"position": (0.3, 0.1, 1.2), "t_min": 80.0, "modes": 12}),
    ("spatial-paper", {"solver": "dense"}),
    ("spatial-paper", {"element": "continuous", "modes": 6}),
    ("spatial-paper", {"element": "massless"}),
    ("spatial-paper", {"element": "catenary", "elements": 16, "compare_dense": True}),
    ("planar-paper", {}),
    ("planar-paper", {"position": (0.4, -0.2, 0.0), "t_min": 35.0, "solver": "dense"}),
    ("planar-paper", {"element": "fem", "elements": 25, "modes": 4}),
    (str(SCENES / "box_6dof.toml"), {"modes": 8}),
    # A rigid end-effector: 6 × 6 stiffness, and a 1° turn about x (normalised alike).
    (str(SCENES / "box_6dof.toml"), {"orientation": (0.99996, 0.00873, 0.0, 0.0)}),
    (str(SCENES / "box_6dof.toml"), {"orientation": (0.99996, 0.00873, 0.0, 0.0),
                                     "solver": "dense"}),
    # Sagging cables: the sagged fields (anchor and smallest tensions, sag, λ², L0).
    ("suspended-8", {"modes": 6}),
    ("suspended-8", {"element": "continuous", "modes": 4}),
    ("fast-like", {"sag": False, "modes": 4}),
    ("spatial-paper", {"sag": True, "modes": 6}),
]

FLAGS = {"position": "--position", "t_min": "--t-min", "element": "--element",
         "elements": "--elements", "modes": "--modes", "solver": "--solver",
         "orientation": "--orientation", "sag": "--sag"}


def cli_args(scene, kwargs):
    args = ["analyze", scene]
    for k, v in kwargs.items():
        if k == "compare_dense":
            args.append("--compare-dense")
        elif k in ("position", "orientation"):
            args += [FLAGS[k], ",".join(repr(float(x)) for x in v)]
        elif k == "sag":
            args += [FLAGS[k], "true" if v else "false"]
        else:
            args += [FLAGS[k], str(v)]
    return args


def assert_equal(got, want, path="report"):
    """`got` (the binding's value) equals `want` (json.loads of the CLI's output)."""
    if isinstance(want, dict):
        assert isinstance(got, dict) and list(got) == list(want), path
        for k in want:
            if k in TIMING:
                assert (want[k] is None) == (got[k] is None), f"{path}.{k}"
                if got[k] is not None:
                    assert isinstance(got[k], float) and got[k] >= 0.0, f"{path}.{k}"
            else:
                assert_equal(got[k], want[k], f"{path}.{k}")
    elif isinstance(want, list):
        assert isinstance(got, np.ndarray), path
        ints = all(isinstance(x, int) for x in np.ravel(np.array(want, dtype=object)))
        assert got.dtype == (np.int64 if ints and want else np.float64), path
        expect = np.array([math.nan if x is None else x for x in np.ravel(
            np.array(want, dtype=object))], dtype=got.dtype).reshape(got.shape)
        assert got.shape == np.shape(want), path
        np.testing.assert_array_equal(got, expect, err_msg=path)
    elif isinstance(want, float):
        assert isinstance(got, float) and got == want, (path, got, want)
    else:
        assert type(got) is type(want) and got == want, (path, got, want)


@pytest.mark.parametrize("scene,kwargs", CASES, ids=[f"{s.split('/')[-1]}-{k}" for s, k in CASES])
def test_analyze_equals_the_cli_to_the_last_bit(cli_json, scene, kwargs):
    want = cli_json(*cli_args(scene, kwargs))
    got = cablevib.analyze(cablevib.Scene.load(scene), **kwargs)
    assert_equal(got, want)
    assert got["solver"] == kwargs.get("solver", "structured")


def test_paper_table_8_column():
    # docs/cli.md: `analyze scenes/spatial_paper.toml` gives the Table 8 (60 N) FEM column
    # of the faithful model, printed to 6 decimals: 11.185488 (×3), 11.186243 (×5),
    # 19.765427 (×2) Hz. Tolerance: half a unit of the last printed digit.
    table = [11.185488] * 3 + [11.186243] * 5 + [19.765427] * 2
    scene = cablevib.Scene.load(str(SCENES / "spatial_paper.toml"))
    for solver in ("structured", "dense"):
        r = cablevib.analyze(scene, solver=solver)
        np.testing.assert_allclose(r["frequencies_hz"], table, rtol=0, atol=5e-7)
    # The count gives each cluster's full size, also of a cluster cut by `modes`: the cube's
    # third cluster is triple (modes 9-11 agree to the solver's ~1e-12 resolution).
    r = cablevib.analyze(scene, modes=11)
    np.testing.assert_array_equal(r["multiplicity"], [3] * 3 + [5] * 5 + [3] * 3)
    np.testing.assert_array_equal(r["cluster_start"], [0] * 3 + [3] * 5 + [8] * 3)
    f = r["frequencies_hz"]
    assert abs(f[10] / f[8] - 1) <= 1e-10
    assert r["tensions_n"].shape == (8,) and r["stiffness_n_m"].shape == (3, 3)
    # A rigid end-effector publishes its 6 × 6 stiffness, symmetric to rounding.
    k = cablevib.analyze(cablevib.Scene.load(str(SCENES / "box_6dof.toml")))["stiffness_n_m"]
    assert k.shape == (6, 6)
    np.testing.assert_allclose(k, k.T, rtol=0, atol=1e-12 * np.abs(k).max())
    assert r["position_m"].tolist() == [0.0, 0.0, 1.25] and r["dof"] == 3 + 3 * 8 * 39


def test_analyze_leaves_the_scene_alone():
    scene = cablevib.Scene.load("spatial-paper")
    cablevib.analyze(scene, position=[0.2, 0.0, 1.0], t_min=90.0, element="catenary")
    assert scene.t_min_n == 60.0 and scene.element == "fem"
    assert scene.ee_position_m.tolist() == [0.0, 0.0, 1.25]


# (python keyword arguments, the CLI flags' name → the Python argument's name).
ERRORS = [
    ({"position": (9.0, 0.0, 1.2)}, None),
    ({"t_min": 340.0, "position": (0.9, 0.9, 2.0)}, None),
    ({"element": "continuous", "solver": "dense"}, ("--solver", "solver")),
    ({"solver": "dense", "compare_dense": True},
     [("--compare-dense", "compare_dense"), ("--solver", "solver")]),
    ({"t_min": 400.0}, ("--t-min", "t_min")),
    ({"t_min": 0.0}, ("--t-min", "t_min")),
    ({"elements": 0}, ("--elements", "elements")),
    ({"elements": 10**9}, ("--elements", "elements")),
    ({"orientation": (1.0, 0.0, 0.0, 0.0)}, ("--orientation", "orientation")),
]


@pytest.mark.parametrize("kwargs,rename", ERRORS)
def test_errors_have_the_clis_message(run_cli, kwargs, rename):
    want = cli_error(run_cli(*cli_args("spatial-paper", kwargs)))
    # The library names the parameter, each front end in its own words.
    for flag, name in [rename] if isinstance(rename, tuple) else rename or []:
        assert flag in want, (flag, want)
        want = want.replace(flag, name)
    with pytest.raises(cablevib.CablevibError) as e:
        cablevib.analyze(cablevib.Scene.load("spatial-paper"), **kwargs)
    assert str(e.value) == want


def test_unknown_element_names_the_choices():
    # The command line rejects `--element bogus` in its parser (clap lists the values); the
    # binding says the same in one line.
    with pytest.raises(cablevib.CablevibError) as e:
        cablevib.analyze(cablevib.Scene.load("spatial-paper"), element="bogus")
    assert str(e.value) == "element `bogus`: expected fem, catenary, continuous, massless or auto"


def test_bad_python_arguments():
    scene = cablevib.Scene.load("spatial-paper")
    with pytest.raises(ValueError, match="finite"):
        cablevib.analyze(scene, position=[math.inf, 0.0, 1.0])
    with pytest.raises(ValueError, match="expected 3 numbers"):
        cablevib.analyze(scene, position=[0.0, 1.0])
    with pytest.raises(cablevib.CablevibError, match="solver `fast`: expected structured or dense"):
        cablevib.analyze(scene, solver="fast")
