"""python/py/cablevib/__init__.pyi (the stub editors read) names exactly what the module has: every
public function, class and attribute, and no more; and the values are of the types it says."""

import ast
import inspect

import numpy as np

import cablevib
from conftest import REPO

STUB = ast.parse((REPO / "python" / "py" / "cablevib" / "__init__.pyi").read_text())


def public(names):
    return {n for n in names if not n.startswith("_")}


def stub_members(node):
    return public(
        n.name for n in node.body if isinstance(n, (ast.FunctionDef, ast.AsyncFunctionDef))
    )


def test_module_names():
    stub = public(n.name for n in STUB.body if isinstance(n, (ast.ClassDef, ast.FunctionDef)))
    # Submodules (cablevib.dask, once imported) are not the extension's names.
    module = public(n for n in dir(cablevib)
                    if n != "cablevib" and not inspect.ismodule(getattr(cablevib, n)))
    assert stub == module


def test_class_members():
    for node in (n for n in STUB.body if isinstance(n, ast.ClassDef)):
        cls = getattr(cablevib, node.name)
        if issubclass(cls, Exception):
            continue
        own = public(n for n, _ in inspect.getmembers(cls) if n in cls.__dict__)
        assert stub_members(node) == own, node.name


def test_every_public_member_has_a_docstring():
    for name in public(dir(cablevib)):
        obj = getattr(cablevib, name)
        if inspect.ismodule(obj):
            continue
        if inspect.isclass(obj) or callable(obj):
            assert obj.__doc__, name
        if inspect.isclass(obj):
            for m in public(obj.__dict__):
                assert getattr(obj, m).__doc__, f"{name}.{m}"


# What a property's annotation in the stub promises, checked on a live value.
def _conforms(ann, v):
    if ann.startswith("Optional[") and ann.endswith("]"):
        return v is None or _conforms(ann[len("Optional["):-1], v)
    checks = {
        "_F64": lambda x: isinstance(x, np.ndarray) and x.dtype == np.float64,
        "float": lambda x: isinstance(x, float),
        "int": lambda x: isinstance(x, int) and not isinstance(x, bool),
        "bool": lambda x: isinstance(x, bool),
        "str": lambda x: isinstance(x, str),
    }
    return checks[ann](v) if ann in checks else True


def test_property_values_have_the_stubs_types():
    """Every property the stub annotates with an array, number, flag or text returns that
    (a numpy float64 array where the stub says ``_F64``), on a live scene, estimate (ok and
    refused) and inverse answer."""
    scene = cablevib.Scene.load("spatial-paper")
    est = cablevib.Estimator(scene)
    objs = {
        "Scene": [scene],
        "Estimate": [est.update([0.1, 0.0, 1.25]), est.update([50.0, 0.0, 1.25])],
        "TminAnswer": [est.t_min_for_f1([0.0, 0.0, 1.25], 12.0)],
    }
    checked = 0
    for node in (n for n in STUB.body if isinstance(n, ast.ClassDef) and n.name in objs):
        for f in node.body:
            if not (isinstance(f, ast.FunctionDef) and f.returns is not None and any(
                    ast.unparse(d) == "property" for d in f.decorator_list)):
                continue
            ann = ast.unparse(f.returns)
            for obj in objs[node.name]:
                v = getattr(obj, f.name)
                assert _conforms(ann, v), f"{node.name}.{f.name}: {type(v).__name__} is not {ann}"
                checked += 1
    assert checked > 40, checked
