"""python/py/cablevib/__init__.pyi (the stub editors read) names exactly what the module has: every
public function, class and attribute, and no more."""

import ast
import inspect

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
