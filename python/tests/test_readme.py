"""The snippet of docs/python.md (the Python package's page, linked from the README) is
python/examples/quickstart.py, verbatim, and it runs; the package declares numpy as a
dependency."""

import importlib.metadata
import re
import subprocess
import sys

from conftest import REPO

EXAMPLE = REPO / "python" / "examples" / "quickstart.py"


def readme_snippet() -> str:
    text = (REPO / "docs" / "python.md").read_text()
    blocks = re.findall(r"```python\n(.*?)```", text, flags=re.S)
    assert len(blocks) == 1, "one python block in docs/python.md"
    return blocks[0]


def test_readme_shows_the_example_verbatim():
    assert readme_snippet() == EXAMPLE.read_text()


def test_the_example_runs(tmp_path):
    # From another directory: the embedded scene name needs no file.
    p = subprocess.run([sys.executable, str(EXAMPLE)], cwd=tmp_path, capture_output=True,
                       text=True, timeout=600, check=False)
    assert p.returncode == 0, p.stderr
    assert p.stdout.startswith("spatial-paper 8 cables, fem x 40\n")
    assert re.search(r"^T_min [0-9.]+ N gives f1 12\.0000 Hz$", p.stdout, flags=re.M)


def test_numpy_is_a_runtime_dependency():
    requires = importlib.metadata.requires("cablevib") or []
    assert any(r.split(">")[0].split("=")[0].strip() == "numpy" for r in requires), requires
