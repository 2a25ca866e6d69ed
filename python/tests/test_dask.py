"""cablevib.dask: a study over a Dask LocalCluster of 2 worker processes.

Reference: the same study in this process (`cablevib.dask.local`: `cablevib.sweep` per
scene, the numbers `test_sweep.py` checks against the `update` loop), compared bit for bit
(every float column as its 64-bit pattern). One test kills a worker process in the middle
of a study: Dask reschedules its tasks and the result is still complete and equal."""

import os
import signal
import time

import numpy as np
import pandas as pd
import pytest
from dask.distributed import Client, LocalCluster, wait

import cablevib
import cablevib.dask as cd
from conftest import SCENES


@pytest.fixture(scope="module")
def client():
    cluster = LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                           dashboard_address=None)
    c = Client(cluster)
    yield c
    c.close()
    cluster.close()


def poses(n_side, z=(0.4, 2.1)):
    xs = np.linspace(-1.0, 1.0, n_side)
    zs = np.linspace(*z, n_side)
    return np.array([(x, y, zz) for zz in zs for y in xs for x in xs])


def assert_bitwise_equal(a: pd.DataFrame, b: pd.DataFrame):
    assert list(a.columns) == list(b.columns)
    assert len(a) == len(b)
    for c in a.columns:
        x, y = a[c].to_numpy(), b[c].to_numpy()
        if x.dtype == np.float64:
            assert y.dtype == np.float64, c
            assert np.array_equal(x.view(np.uint64), y.view(np.uint64)), c
        else:
            assert x.tolist() == y.tolist(), c


def test_study_on_two_worker_processes_equals_one_process(client):
    scenes = [cablevib.Scene.load("spatial-paper"),
              cablevib.Scene.load(SCENES / "box_6dof.toml"),
              cablevib.Scene.from_arrays(
                  anchors_m=[[x, y, z] for z in (3.0, 0.0)
                             for (x, y) in ((1.5, 1.5), (-1.5, 1.5), (-1.5, -1.5), (1.5, -1.5))],
                  ee_mass_kg=30.0, ee_position_m=[0, 0, 1.5], youngs_modulus_pa=2.01e10,
                  area_m2=50.265e-6, weight_per_length_n_m=0.251, t_min_n=60.0,
                  t_max_n=350.0, elements=10, name="wide")]
    p = poses(11)  # 1331 poses per scene, some outside each frame
    t0 = time.perf_counter()
    df = cd.study(client, scenes, p, chunk_poses=32, poses_per_task=128)
    t_dask = time.perf_counter() - t0
    t0 = time.perf_counter()
    ref = cd.local(scenes, p, chunk_poses=32, threads=1)
    t_one = time.perf_counter() - t0
    print(f"dask (2 worker processes) {t_dask:.2f} s, one process (1 thread) {t_one:.2f} s")
    assert_bitwise_equal(df, ref)
    assert df["scene_name"].unique().tolist() == ["spatial-paper", "box-6dof", "wide"]
    assert (df["status"] == "ok").sum() > 1000
    assert "tension8_n" in df.columns and "stiffness_min_n_m" in df.columns
    # The task size does not change the numbers (it is a multiple of the chunk).
    assert_bitwise_equal(cd.study(client, scenes, p, chunk_poses=32, poses_per_task=320), ref)
    with pytest.raises(ValueError, match="multiple of chunk_poses"):
        cd.study(client, scenes, p, chunk_poses=32, poses_per_task=100)


def test_a_killed_worker_is_retried_and_the_study_is_complete(client):
    scene = cablevib.Scene.load("spatial-paper")
    p = poses(30)  # 27000 poses, 27 tasks of 1024
    futures = cd.submit(client, scene, p, chunk_poses=64, poses_per_task=1024)
    wait(futures, return_when="FIRST_COMPLETED")
    processing = client.processing()
    addr = max(processing, key=lambda a: len(processing[a]))
    assert processing[addr], "no task in flight to kill"
    pids = client.run(os.getpid)
    os.kill(pids[addr], signal.SIGKILL)
    df = cd.gather(client, futures)
    assert all(f.status == "finished" for f in futures)
    # The killed worker was replaced (its nanny started a new process).
    assert pids[addr] not in client.run(os.getpid).values()
    assert_bitwise_equal(df, cd.local(scene, p, chunk_poses=64))
    assert df["pose"].tolist() == list(range(len(p)))


def test_without_the_extra_the_import_names_it():
    """Without pandas (the dask extra) `import cablevib.dask` raises an ImportError naming
    `pip install ./python[dask]` (before: a bare `ModuleNotFoundError: No module named
    'pandas'`). pandas is hidden in a fresh interpreter (None in sys.modules)."""
    import subprocess
    import sys

    code = ("import sys; sys.modules['pandas'] = None\n"
            "try:\n    import cablevib.dask\n"
            "except ImportError as e:\n    print(type(e).__name__, e)\n")
    p = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                       check=True)
    assert p.stdout.startswith("ImportError cablevib.dask needs the dask extra: "
                               "pip install ./python[dask]"), p.stdout
