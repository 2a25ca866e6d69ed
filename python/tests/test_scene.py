"""Scene.load and its read-only properties, checked against the scene files read by Python's
own TOML parser (tomllib: an independent reading of the same file), and its errors against
the command line's."""

import math
import pathlib
import tomllib

import numpy as np
import pytest

import cablevib
from conftest import SCENES, cli_error

PAPER = {"spatial-paper": "spatial_paper.toml", "planar-paper": "planar_paper.toml"}


def toml(name: str) -> dict:
    return tomllib.loads((SCENES / name).read_text())


@pytest.mark.parametrize("name", sorted(PAPER))
def test_embedded_name_and_path_load_the_same_scene(name):
    by_name = cablevib.Scene.load(name)
    by_path = cablevib.Scene.load(str(SCENES / PAPER[name]))
    by_pathlike = cablevib.Scene.load(SCENES / PAPER[name])
    for s in (by_path, by_pathlike):
        assert repr(s) == repr(by_name)
        np.testing.assert_array_equal(s.anchors_m, by_name.anchors_m)


@pytest.mark.parametrize("name", sorted(PAPER))
def test_properties_are_the_files_values(name):
    t = toml(PAPER[name])
    s = cablevib.Scene.load(name)
    assert s.name == t["name"] == name
    assert s.n_cables == len(t["cables"])
    assert s.element == t["model"]["element"]
    assert s.elements == t["model"]["elements_per_cable"]
    assert s.t_min_n == t["tension"]["t_min"]
    assert s.t_max_n == t["tension"]["t_max"]
    assert s.ee_mass_kg == t["end_effector"]["mass"]
    assert s.weight_carried == t["end_effector"]["weight_carried"]
    assert not s.rigid
    np.testing.assert_array_equal(s.ee_position_m, t["end_effector"]["position"])
    np.testing.assert_array_equal(s.gravity_m_s2, t["gravity"])
    np.testing.assert_array_equal(s.anchors_m, [c["anchor"] for c in t["cables"]])
    np.testing.assert_array_equal(s.cable_t_min_n, [t["tension"]["t_min"]] * s.n_cables)
    np.testing.assert_array_equal(s.cable_t_max_n, [t["tension"]["t_max"]] * s.n_cables)
    np.testing.assert_array_equal(s.ee_orientation_wxyz, [1.0, 0.0, 0.0, 0.0])
    assert s.anchors_m.dtype == np.float64 and s.anchors_m.shape == (s.n_cables, 3)


def test_rigid_scene_file():
    t = toml("box_6dof.toml")
    s = cablevib.Scene.load(str(SCENES / "box_6dof.toml"))
    assert s.rigid and s.n_cables == len(t["cables"]) == 8
    np.testing.assert_array_equal(s.ee_orientation_wxyz, t["end_effector"]["orientation"])


def test_from_toml_names_its_source_in_errors():
    text = (SCENES / "spatial_paper.toml").read_text()
    assert cablevib.Scene.from_toml(text).name == "spatial-paper"
    bad = text.replace("t_min = 60.0", "t_min = 400.0")
    with pytest.raises(cablevib.CablevibError, match=r"^mine\.toml: key `tension\.t_min`"):
        cablevib.Scene.from_toml(bad, "mine.toml")


def test_properties_are_read_only():
    s = cablevib.Scene.load("spatial-paper")
    with pytest.raises(AttributeError):
        s.t_min_n = 1.0


def test_error_class_is_a_value_error():
    assert issubclass(cablevib.CablevibError, ValueError)


def test_missing_scene_has_the_clis_message(run_cli):
    with pytest.raises(cablevib.CablevibError) as e:
        cablevib.Scene.load("no-such-scene.toml")
    assert str(e.value) == cli_error(run_cli("analyze", "no-such-scene.toml"))


def test_invalid_scene_file_has_the_clis_message(run_cli, tmp_path: pathlib.Path):
    bad = tmp_path / "bad.toml"
    text = (SCENES / "spatial_paper.toml").read_text()
    bad.write_text(text.replace("area = 50.265e-6", "area = -1.0"))
    with pytest.raises(cablevib.CablevibError) as e:
        cablevib.Scene.load(str(bad))
    msg = str(e.value)
    assert msg == cli_error(run_cli("analyze", str(bad)))
    assert "area" in msg and "\n" not in msg


def test_cable_count_matches_a_hand_built_scene():
    text = (SCENES / "planar_paper.toml").read_text()
    extra = '\n[[cables]]\nanchor = [0.0, 1.5, 0.0]\nt_min = 30.0\n'
    s = cablevib.Scene.from_toml(text + extra)
    assert s.n_cables == 5
    assert s.cable_t_min_n[-1] == 30.0 and s.cable_t_min_n[0] == 20.0
    assert math.isclose(s.anchors_m[-1, 1], 1.5)
