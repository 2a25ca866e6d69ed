"""examples/design_study.py (docs/studies.md) on a coarse grid: in this process and through
cablevib.dask on a LocalCluster of 2 worker processes, the same table and the same figure
byte for byte; the best design it names is the one with the highest worst f1 in its table
(recomputed here from the printed rows)."""

import re
import subprocess
import sys

from conftest import REPO

SCRIPT = REPO / "python" / "examples" / "design_study.py"


def run(tmp_path, name, *extra):
    svg = tmp_path / f"{name}.svg"
    p = subprocess.run([sys.executable, str(SCRIPT), "--side", "3", "--out", str(svg), *extra],
                       capture_output=True, text=True, check=False, cwd=tmp_path, timeout=600)
    assert p.returncode == 0, p.stderr
    table = [ln for ln in p.stdout.splitlines() if "poses/s" not in ln and "wrote" not in ln]
    return table, svg.read_bytes()


def test_design_study_local_and_on_dask_agree(tmp_path):
    local, svg = run(tmp_path, "local")
    dask, svg_dask = run(tmp_path, "dask", "--local-cluster", "2")
    assert local == dask
    assert svg == svg_dask and svg.startswith(b"<svg") and svg.rstrip().endswith(b"</svg>")
    rows = [r.split() for r in local[1:] if re.match(r"\s*H[0-9.]+-A", r)]
    assert len(rows) == 36
    f1 = {r[0]: float(r[2]) for r in rows if r[2] != "nan"}
    best = max(f1, key=f1.get)
    h, a = best[1:].split("-A")
    line = next(r for r in local if r.startswith("best design"))
    assert f"H = {h} m, A = {a} m" in line.replace(".0 m", " m"), (line, best)
