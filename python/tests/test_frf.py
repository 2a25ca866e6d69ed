"""cablevib.frf against `cablevib frf --json`: the same library function (study::frf::frf)
behind two front ends, so every receptance entry must be equal to the last bit; with sag the command line's own
`--dense` comparison (the assembled sagged complex problem solved by LU at every frequency)
is checked too."""

import numpy as np
import pytest

import cablevib
from conftest import SCENES


@pytest.mark.parametrize(
    "kwargs,flags",
    [
        ({"loss_factor": 0.02, "points": 50}, ["--loss-factor", "0.02", "--points", "50"]),
        ({"rayleigh": (0.5, 2e-4), "points": 30, "elements": 10, "log": True, "from_hz": 1.0},
         ["--rayleigh", "0.5,2e-4", "--points", "30", "--elements", "10", "--log",
          "--from-hz", "1"]),
        ({"modal_ratio": 0.01, "points": 20, "element": "continuous"},
         ["--modal-ratio", "0.01", "--points", "20", "--element", "continuous"]),
    ],
)
def test_frf_equals_the_command_line(cli_json, kwargs, flags):
    py = cablevib.frf(cablevib.Scene.load("spatial-paper"), **kwargs)
    cli = cli_json("frf", "spatial-paper", *flags)
    np.testing.assert_array_equal(np.asarray(py["frequencies_hz"]), np.array(cli["frequencies_hz"]))
    np.testing.assert_array_equal(np.asarray(py["receptance_re"]), np.array(cli["receptance_re"]))
    np.testing.assert_array_equal(np.asarray(py["receptance_im"]), np.array(cli["receptance_im"]))
    # numpy arrays, as the stub says (they were lists of arrays)
    for key in ("frequencies_hz", "receptance_re", "receptance_im"):
        assert isinstance(py[key], np.ndarray) and py[key].dtype == np.float64, key
    assert py["receptance_re"].shape == (len(py["frequencies_hz"]), 3, 3)
    assert py["receptance_im"].shape == py["receptance_re"].shape


# suspended-8 has sag on: FEM chains on the catenary, N = 6 (small, so the dense solve is quick).
SAG = {"element": "fem", "elements": 6, "to_hz": 20.0, "points": 40}
SAG_FLAGS = ["--element", "fem", "--elements", "6", "--to-hz", "20", "--points", "40"]


# The bound on the command line's own dense comparison: 1e-8 on the even grid (it passes
# near resonances; η = 0.02 keeps the conditioning ≲ 1e2/η, as cli/tests/cli/frf.rs holds);
# the log grid packs its points at the low resonances, where the Rayleigh damping is near its
# least (ζ ≈ √(αβ) = 1 %): the on-resonance bound of tests/sag/frf.rs, 1e-7 (1.3e-8 measured).
@pytest.mark.parametrize(
    "kwargs,flags,dense_bound",
    [
        ({"loss_factor": 0.02}, ["--loss-factor", "0.02"], 1e-8),
        ({"rayleigh": (0.5, 2e-4), "log": True, "from_hz": 1.0},
         ["--rayleigh", "0.5,2e-4", "--log", "--from-hz", "1"], 1e-7),
    ],
)
def test_sagged_frf_equals_the_command_line(cli_json, kwargs, flags, dense_bound):
    scene = str(SCENES / "suspended_8.toml")
    py = cablevib.frf(cablevib.Scene.load(scene), **{**SAG, **kwargs})
    cli = cli_json("frf", scene, *SAG_FLAGS, *flags, "--dense")
    np.testing.assert_array_equal(np.asarray(py["frequencies_hz"]), np.array(cli["frequencies_hz"]))
    np.testing.assert_array_equal(np.asarray(py["receptance_re"]), np.array(cli["receptance_re"]))
    np.testing.assert_array_equal(np.asarray(py["receptance_im"]), np.array(cli["receptance_im"]))
    assert np.asarray(py["receptance_re"]).shape == (40, 3, 3)
    # The independent check: the command line's dense complex LU of the assembled sagged
    # c(K - λM) at every frequency.
    assert cli["dense_max_rel_diff"] <= dense_bound, cli["dense_max_rel_diff"]


def test_sagged_modal_damping_equals_the_command_line(cli_json):
    """Modal damping with sag: the superposition of the sagged shapes with the static
    correction, as the command line answers it (the binding refused it while it orchestrated
    the response itself). Bit for bit the command line's numbers, from the same function;
    the superposition itself is checked against every dense mode of the assembled sagged
    (K, M) in tests/sag/frf_modal.rs."""
    scene = str(SCENES / "suspended_8.toml")
    py = cablevib.frf(cablevib.Scene.load(scene), **{**SAG, "modal_ratio": 0.02})
    cli = cli_json("frf", scene, *SAG_FLAGS, "--modal-ratio", "0.02")
    np.testing.assert_array_equal(py["receptance_re"], np.array(cli["receptance_re"]))
    np.testing.assert_array_equal(py["receptance_im"], np.array(cli["receptance_im"]))
    np.testing.assert_array_equal(py["natural_frequencies_hz"],
                                  np.array(cli["natural_frequencies_hz"]))
    assert py["damping"] == cli["damping"] == "modal_ratio"


def test_frf_returns_numpy_arrays_as_its_stub_says():
    r = cablevib.frf(cablevib.Scene.load("spatial-paper"), points=7, loss_factor=0.02)
    for k in ("frequencies_hz", "receptance_re", "receptance_im", "natural_frequencies_hz"):
        assert isinstance(r[k], np.ndarray) and r[k].dtype == np.float64, k
    assert r["receptance_re"].shape == r["receptance_im"].shape == (7, 3, 3)
    assert r["frequencies_hz"].shape == (7,)
    assert isinstance(r["damping"], str) and isinstance(r["dim"], int)


@pytest.mark.parametrize(
    "kwargs,needle",
    [({"element": "continuous", "loss_factor": 0.02}, "takes the fem element")],
)
def test_sagged_frf_refuses_what_the_command_line_refuses(kwargs, needle):
    scene = cablevib.Scene.load(str(SCENES / "suspended_8.toml"))
    with pytest.raises(cablevib.CablevibError, match=needle):
        cablevib.frf(scene, **kwargs)


@pytest.mark.parametrize(
    "kwargs,needle",
    [({"from_hz": 10.0, "to_hz": 5.0}, "to_hz 5 Hz"), ({"points": 0}, "points 0"),
     ({"modal_ratio": 1.0}, "modal_ratio 1"), ({"loss_factor": float("nan")}, "loss_factor NaN"),
     ({"loss_factor": 0.1, "modal_ratio": 0.1}, "give one of loss_factor, rayleigh, ")],
)
def test_frf_refuses_bad_input(kwargs, needle):
    """Refused with the parameter named as the Python argument (the command line names its
    option, --to-hz, --points, ...)."""
    with pytest.raises(cablevib.CablevibError, match=needle) as e:
        cablevib.frf(cablevib.Scene.load("spatial-paper"), **kwargs)
    assert "--" not in str(e.value), str(e.value)


def test_frf_refuses_a_basis_over_the_memory_budget():
    """10⁶ elements per cable with modal damping: the modal basis would hold the shapes of
    every mode below 4 × to_hz (40 GiB); refused before allocating with the command line's
    one-line message, and the interpreter lives on (it used to abort at ~4 GB)."""
    s = cablevib.Scene.load("spatial-paper")
    with pytest.raises(cablevib.CablevibError, match="over the budget of 2.000 GiB"):
        cablevib.frf(s, elements=10**6, modal_ratio=0.02, points=10)
    # Still alive, and the same call under the budget answers.
    h = cablevib.frf(s, elements=1000, modal_ratio=0.02, points=10)
    assert np.isfinite(np.asarray(h["receptance_re"])).all()
