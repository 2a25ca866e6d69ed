"""cablevib.simulate and cablevib.shape against `cablevib simulate` and `cablevib shape`:
the same study-layer functions (study::simulate::PathSpec, simulate_shaped, shape) behind two
front ends, so every number of the command line's CSV (written with 9 significant digits,
`{:.8e}`) must be the Python array's value written the same way, digit for digit."""

import csv
import re

import numpy as np
import pytest

import cablevib
from conftest import cli_error


def cli_text(x: float) -> str:
    """x as the command line's CSV writes it (Rust's `{:.8e}`: no exponent padding or +)."""
    m, e = f"{x:.8e}".split("e")
    return f"{m}e{int(e)}"


def read_csv(path):
    with open(path, newline="") as f:
        rows = [r for r in csv.reader(f) if r and not r[0].startswith("#")]
    return rows[0], rows[1:]


def assert_column(rows, col, values):
    got = [r[col] for r in rows]
    want = [cli_text(v) for v in values]
    assert len(got) == len(want)
    bad = [i for i, (g, w) in enumerate(zip(got, want)) if g != w]
    assert not bad, f"column {col}: {len(bad)} differ, first at row {bad[0]}: {got[bad[0]]} vs {want[bad[0]]}"


@pytest.mark.parametrize(
    "kwargs,flags",
    [
        # A move with the defaults (K and the update interval chosen for the tolerance).
        ({"move": (0.1, 0.2, -0.15), "duration": 0.3, "settle": 0.2, "modal_ratio": 0.02,
          "elements": 10},
         ["--move", "0.1,0.2,-0.15", "--duration", "0.3", "--settle", "0.2",
          "--modal-ratio", "0.02", "--elements", "10"]),
        # Shaped by ZV following the first mode, given K and interval, a trapezoid.
        ({"move": (0.2, 0.0, 0.0), "duration": 0.4, "profile": "trapezoid", "settle": 0.3,
          "modes": 30, "update_every": 20, "shaper": "zv", "mode": "f1", "elements": 6},
         ["--move", "0.2,0,0", "--duration", "0.4", "--profile", "trapezoid", "--settle", "0.3",
          "--modes", "30", "--update-every", "20", "--shaper", "zv", "--mode", "f1",
          "--elements", "6"]),
        # The circle (already moving at its ends), 0.1 s.
        ({"circle_s": 0.1, "modes": 12, "update_every": 10, "elements": 6},
         ["--circle-s", "0.1", "--modes", "12", "--update-every", "10", "--elements", "6"]),
    ],
)
def test_simulate_equals_the_command_line(run_cli, tmp_path, kwargs, flags):
    py = cablevib.simulate(cablevib.Scene.load("spatial-paper"), **kwargs)
    out = tmp_path / "sim"
    p = run_cli("simulate", "spatial-paper", *flags, "--out", str(out))
    assert p.returncode == 0, p.stderr
    header, rows = read_csv(out.with_suffix(".csv"))
    name = kwargs.get("shaper", "none")
    name = "unshaped" if name == "none" else name
    assert header[:4] == ["t_s", f"{name}_dev_x_mm", f"{name}_dev_y_mm", f"{name}_dev_z_mm"], header
    t, dev = py["t_s"], py["deviation_m"]
    assert isinstance(t, np.ndarray) and t.dtype == np.float64 and t.shape == (len(rows),)
    assert dev.dtype == np.float64 and dev.shape == (len(rows), 3)
    assert py["command_m"].shape == (len(rows), 3)
    assert_column(rows, 0, t)
    for axis in range(3):
        assert_column(rows, 1 + axis, dev[:, axis] * 1e3)
    assert np.abs(dev).max() > 0.0
    # The run's summary as the command line prints it.
    m = re.search(r"(\d+) mode updates, (\d+) modes", p.stdout)
    assert m and int(m.group(1)) == py["updates"] and int(m.group(2)) == py["modes"], p.stdout


@pytest.mark.parametrize(
    "kwargs,flags",
    [
        ({"move": (0.3, 0.0, 0.1), "duration": 0.5},
         ["--move", "0.3,0,0.1", "--duration", "0.5"]),
        ({"move": (0.1, -0.2, 0.0), "duration": 0.4, "shaper": "zvd", "mode": "f1",
          "modal_ratio": 0.05, "profile": "trapezoid"},
         ["--move", "0.1,-0.2,0", "--duration", "0.4", "--shaper", "zvd", "--mode", "f1",
          "--modal-ratio", "0.05", "--profile", "trapezoid"]),
    ],
)
def test_shape_equals_the_command_line(run_cli, tmp_path, kwargs, flags):
    py = cablevib.shape(cablevib.Scene.load("spatial-paper"), **kwargs)
    out = tmp_path / "shaped.csv"
    p = run_cli("shape", *flags, "-o", str(out))
    assert p.returncode == 0, p.stderr
    header, rows = read_csv(out)
    assert header == ["t", "x", "y", "z"], header
    assert py["path_m"].shape == (len(rows), 3) and py["path_m"].dtype == np.float64
    assert_column(rows, 0, py["t_s"])
    for axis in range(3):
        assert_column(rows, 1 + axis, py["path_m"][:, axis])
    assert py["time_added_s"] > 0.0
    assert py["design_hz"].shape == (len(rows),)


def test_bad_arguments_raise_the_command_lines_messages(run_cli, tmp_path):
    scene = cablevib.Scene.load("spatial-paper")
    with pytest.raises(cablevib.CablevibError, match="sample period"):
        cablevib.simulate(scene, move=(0.1, 0, 0), dt=0.5)
    with pytest.raises(cablevib.CablevibError, match="modal_ratio"):
        cablevib.simulate(scene, move=(0.1, 0, 0), modal_ratio=1.5)
    with pytest.raises(cablevib.CablevibError, match="shaper"):
        cablevib.simulate(scene, move=(0.1, 0, 0), shaper="zz")
    with pytest.raises(cablevib.CablevibError, match="nothing to shape"):
        cablevib.shape(scene, move=(0.1, 0, 0), shaper="none")
    with pytest.raises(cablevib.CablevibError, match="tolerance"):
        cablevib.simulate(scene, move=(0.1, 0, 0), tolerance=0.9)
    # The same refusal on the command line.
    p = run_cli("simulate", "spatial-paper", "--move", "0.1,0,0", "--tolerance", "0.9",
                "--out", str(tmp_path / "x"))
    assert "tolerance" in cli_error(p)
