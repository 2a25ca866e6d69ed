"""The Python controller's f1 hold (examples/python/hold_f1.py) does what the Rust one
(service/src/hold.rs, `F1Hold`) does: the same set-point and action, bit for bit, on the fixed
sequence of margin answers in examples/python/hold_f1_cases.json, which the Rust tests write
from their own implementation and check; and the same bad parameters are refused."""

import importlib.util
import json
import math

import pytest

from conftest import REPO

CASES = REPO / "examples" / "python" / "hold_f1_cases.json"


def hold_module():
    spec = importlib.util.spec_from_file_location("hold_f1", REPO / "examples" / "python" / "hold_f1.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def number(x):
    return float(x) if isinstance(x, str) else x


def test_the_python_hold_reproduces_the_rust_cases():
    h = hold_module()
    doc = json.loads(CASES.read_text())
    hold = h.F1Hold(h.HoldParams(**doc["params"]))
    actions = set()
    for k, s in enumerate(doc["steps"]):
        action = hold.on_answer(s["ok"], number(s["f1_hz"]), number(s["t_min_required_n"]),
                                s["t_min_required_age_cycles"], s["timestamp_ns"],
                                s["pose_sequence"], s["tension_infeasible"])
        # Exact: the same operations in the same order on the same doubles.
        assert (action, hold.setpoint_n) == (s["action"], s["setpoint_n"]), "step %d: %r" % (k, s)
        actions.add(action)
    assert actions == {"no_answer", "held", "raised", "relaxed", "ceiling", "unreachable",
                       "infeasible"}


@pytest.mark.parametrize("kwargs, what", [
    (dict(required_hz=-1.0), "hold-f1"),
    (dict(required_hz=math.nan), "hold-f1"),
    (dict(guard_hz=-0.1), "guard"),
    (dict(relax_band_hz=0.05), "relax band"),
    (dict(relax_rate_n_per_s=0.0), "relax rate"),
    (dict(relax_rate_n_per_s=math.inf), "relax rate"),
    (dict(floor_n=400.0), "floor"),
    (dict(ceiling_n=math.nan), "ceiling"),
])
def test_bad_parameters_are_one_line_errors(kwargs, what):
    h = hold_module()
    args = dict(required_hz=9.5, floor_n=60.0, ceiling_n=350.0)
    args.update(kwargs)
    with pytest.raises(h.HoldError) as e:
        h.HoldParams(**args)
    assert what in str(e.value) and "\n" not in str(e.value)
