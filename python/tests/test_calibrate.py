"""cablevib.calibrate against `cablevib calibrate --json`: the same library function
(calibration::calibrate) behind two front ends, so every estimate, standard error and χ² must
be equal to the last bit; and the Python argument errors are the command line's one-line
messages."""

import numpy as np
import pytest

import cablevib
from conftest import SCENES

POSITIONS = [
    (0.2, -0.1, 1.1), (-0.25, 0.15, 1.3), (0.1, 0.3, 1.0), (-0.3, -0.2, 1.5),
    (0.35, 0.05, 1.25), (0.0, -0.35, 1.2), (-0.1, 0.1, 0.9), (0.25, 0.25, 1.6),
]


@pytest.fixture(scope="module")
def data(tmp_path_factory):
    """The end-effector modes of the paper's robot with a 32 kg end-effector (fem × 10) at
    eight poses, with σ = 0.3 %: the file the two front ends read."""
    d = tmp_path_factory.mktemp("calibrate")
    text = (SCENES / "spatial_paper.toml").read_text()
    assert "elements_per_cable = 40" in text and "mass = 30.0" in text
    text = text.replace("elements_per_cable = 40", "elements_per_cable = 10")
    (d / "nominal.toml").write_text(text)
    heavy = d / "heavy.toml"
    heavy.write_text(text.replace("mass = 30.0", "mass = 32.0"))
    scene = cablevib.Scene.load(str(heavy))
    rows = ["x_m,y_m,z_m,frequency_hz,sigma_hz,mode"]
    for p in POSITIONS:
        r = cablevib.analyze(scene, position=list(p), modes=40)
        ee = [float(f) for f, q in zip(r["frequencies_hz"], r["ee_participation"]) if q >= 0.5][:3]
        for k, f in enumerate(ee):
            rows.append(f"{p[0]},{p[1]},{p[2]},{f!r},{0.003 * f!r},ee{k + 1}")
    modes = d / "modes.csv"
    modes.write_text("\n".join(rows) + "\n")
    return modes


def test_calibrate_equals_the_command_line(cli_json, data):
    nominal = str(data.parent / "nominal.toml")
    py = cablevib.calibrate(cablevib.Scene.load(nominal), data, ["ee_mass", "ea_factor_all"],
                            bounds={"ee_mass": (20.0, 40.0)})
    cli = cli_json("calibrate", nominal, "--data", str(data), "--fit", "ee_mass,ea_factor_all",
                   "--bounds", "ee_mass=20:40")
    assert [p["name"] for p in py["parameters"]] == ["ee_mass", "ea_factor_all"]
    for a, b in zip(py["parameters"], cli["parameters"]):
        assert (a["value"], a["std_error"], a["determined"]) == (b["value"], b["std_error"], b["determined"])
    assert py["chi2_per_dof"] == cli["chi2_per_dof"] and py["fits"] == cli["fits"]
    after = np.array([r["model_after_hz"] for r in py["residuals"]])
    np.testing.assert_array_equal(after, np.array([r["model_after_hz"] for r in cli["residuals"]]))


def test_errors_are_the_command_lines(data):
    scene = cablevib.Scene.load("spatial-paper")
    with pytest.raises(cablevib.CablevibError, match=r"^parameter `ee_mas`: unknown parameter"):
        cablevib.calibrate(scene, data, ["ee_mas"])
    with pytest.raises(cablevib.CablevibError, match=r"exclude the nominal value 30"):
        cablevib.calibrate(scene, data, ["ee_mass"], bounds={"ee_mass": (31.0, 40.0)})
    with pytest.raises(cablevib.CablevibError, match=r"no-such.csv"):
        cablevib.calibrate(scene, data.parent / "no-such.csv", ["ee_mass"])
