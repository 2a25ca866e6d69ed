"""Design studies on a Dask cluster: every pose of every scene, cut into tasks that each
run ``cablevib.sweep`` on a worker, gathered as one pandas DataFrame.

Optional: ``pip install ./python[dask]`` (dask[distributed], pandas). The same code runs on
a ``LocalCluster`` and on any Dask cluster (SLURM/PBS through dask-jobqueue, Kubernetes):
pass its ``Client``. Dask schedules the tasks, moves the data and retries the tasks of a
worker that dies; this module only cuts the study into tasks and joins the results.

The result equals the single-process one (``frame`` of ``cablevib.sweep`` per scene) bit
for bit: a task's poses are whole chunks of the sweep (``poses_per_task`` is a multiple of
``chunk_poses``), and a chunk's numbers depend on its poses alone (see
``Estimator.sweep``).
"""

from __future__ import annotations

from typing import Any, Dict, List, Optional, Sequence, Union

import numpy as np

try:
    import pandas as pd
except ImportError as e:  # the extra is not installed
    raise ImportError(
        f"cablevib.dask needs the dask extra: pip install ./python[dask] "
        f"(dask[distributed], pandas); {e}"
    ) from e

import cablevib

#: Default chunks of ``chunk_poses`` poses per task: ~4000 poses, a second or so of work
#: for the paper robot, so that scheduling (~1 ms a task) is negligible.
DEFAULT_CHUNKS_PER_TASK = 16


def frame(result: Dict[str, Any], scene_index: int = 0, scene_name: str = "") -> pd.DataFrame:
    """A sweep's dict as a DataFrame with the CSVs' column names (units in the names):
    ``scene``, ``scene_name``, ``pose``, ``x_m``, ``y_m``, ``z_m``, ``qw`` .. ``qz``,
    ``t_min_n``, ``status``, ``status_code``, ``f1_hz``, ``ee_mode_hz``,
    ``f1_ee_participation``, ``ee_mode_participation``, ``tension1_n`` .. ``tensionN_n``,
    ``k1_n_m`` .. ``k3_n_m`` (principal stiffnesses, ascending) and ``stiffness_min_n_m``."""
    n = len(result["f1_hz"])
    p, q, t = result["positions_m"], result["orientations_wxyz"], result["tensions_n"]
    k = result["stiffness_principal_n_m"]
    cols: Dict[str, Any] = {
        "scene": np.full(n, scene_index, dtype=np.int64),
        "scene_name": np.full(n, scene_name, dtype=object),
        "pose": np.arange(n, dtype=np.int64),
        "x_m": p[:, 0], "y_m": p[:, 1], "z_m": p[:, 2],
        "qw": q[:, 0], "qx": q[:, 1], "qy": q[:, 2], "qz": q[:, 3],
        "t_min_n": result["t_min_n"],
        "status": result["status"].astype(object),
        "status_code": result["status_code"],
        "f1_hz": result["f1_hz"],
        "ee_mode_hz": result["ee_mode_hz"],
        "f1_ee_participation": result["f1_ee_participation"],
        "ee_mode_participation": result["ee_mode_participation"],
    }
    for i in range(t.shape[1]):
        cols[f"tension{i + 1}_n"] = t[:, i]
    for j in range(3):
        cols[f"k{j + 1}_n_m"] = k[:, j]
    cols["stiffness_min_n_m"] = result["k_min_n_m"]
    return pd.DataFrame(cols)


def _scenes(scenes) -> List[cablevib.Scene]:
    if isinstance(scenes, cablevib.Scene):
        return [scenes]
    out = list(scenes)
    if not out or not all(isinstance(s, cablevib.Scene) for s in out):
        raise TypeError("scenes: expected a Scene or a non-empty sequence of Scenes")
    return out


def _rows(a, n: int):
    """`a` per scene: None, one array for every scene, or a list of numpy arrays (ndim ≥ 1),
    one per scene."""
    if a is None:
        return [None] * n
    if isinstance(a, list) and a and all(isinstance(x, np.ndarray) and x.ndim >= 1 for x in a):
        if len(a) != n:
            raise ValueError(f"{len(a)} arrays for {n} scenes")
        return [np.asarray(x, dtype=np.float64) for x in a]
    return [np.asarray(a, dtype=np.float64)] * n


def _task(scene, scene_index, first_pose, positions, orientations, t_min, threads, chunk_poses):
    """One task on a worker: a sweep of whole chunks, as DataFrame rows."""
    r = cablevib.sweep(scene, positions, orientations, t_min, threads=threads,
                       chunk_poses=chunk_poses)
    df = frame(r, scene_index, scene.name)
    df["pose"] += first_pose
    return df


def plan(scenes, positions, orientations=None, t_min=None, chunk_poses: int = 256,
         poses_per_task: Optional[int] = None):
    """The tasks of a study: (scene, scene index, first pose, positions, orientations, t_min)
    for every run of ``poses_per_task`` consecutive poses of every scene, in the result's
    order. ``positions`` is one (n, 3) array for every scene, or a list of one per scene
    (likewise ``orientations`` (n, 4) and ``t_min`` (n,) or (n, n_cables))."""
    ss = _scenes(scenes)
    if poses_per_task is None:
        poses_per_task = DEFAULT_CHUNKS_PER_TASK * chunk_poses
    if chunk_poses < 1 or poses_per_task < 1 or poses_per_task % chunk_poses:
        raise ValueError(
            f"poses_per_task {poses_per_task}: must be a positive multiple of chunk_poses "
            f"{chunk_poses} (a task holds whole chunks, so the numbers do not depend on it)")
    ps = _rows(positions, len(ss))
    qs = _rows(orientations, len(ss))
    ts = _rows(t_min, len(ss))
    tasks = []
    for i, s in enumerate(ss):
        n = len(ps[i])
        for a in range(0, n, poses_per_task):
            b = min(a + poses_per_task, n)
            sl = slice(a, b)
            tasks.append((s, i, a, ps[i][sl],
                          None if qs[i] is None else qs[i][sl],
                          None if ts[i] is None else ts[i][sl]))
    return tasks


def submit(client, scenes, positions, orientations=None, t_min=None, *, chunk_poses: int = 256,
           poses_per_task: Optional[int] = None, threads_per_task: int = 1,
           retries: int = 2) -> list:
    """Submit a study's tasks to the Dask ``client``; returns their futures, in the result's
    order (see ``study``). ``retries``: how often Dask reruns a task that raised; a task
    whose worker died is rescheduled by Dask itself (up to its
    ``distributed.scheduler.allowed-failures``)."""
    futures = []
    for s, i, a, p, q, t in plan(scenes, positions, orientations, t_min, chunk_poses,
                                 poses_per_task):
        futures.append(client.submit(_task, s, i, a, p, q, t, threads_per_task, chunk_poses,
                                     retries=retries, pure=False))
    return futures


def gather(client, futures) -> pd.DataFrame:
    """The DataFrame of a submitted study: its tasks' rows, in order."""
    return pd.concat(client.gather(futures), ignore_index=True)


def study(client, scenes, positions, orientations=None, t_min=None, *, chunk_poses: int = 256,
          poses_per_task: Optional[int] = None, threads_per_task: int = 1,
          retries: int = 2) -> pd.DataFrame:
    """Every pose of every scene on the Dask cluster of ``client``: one row per (scene,
    pose), scenes in order, poses in order, with ``frame``'s columns. The numbers are those
    of ``local(scenes, ...)`` bit for bit, for any cluster, task size or worker count.

    ``scenes``: a Scene or a sequence of them (they pickle by their TOML text, so workers
    need no scene files). ``positions``: (n, 3) m for every scene, or a list of numpy arrays,
    one per scene; ``orientations`` (n, 4) and ``t_min`` (n,) or (n, n_cables) N likewise.
    ``poses_per_task``: a multiple of ``chunk_poses`` (default 16 chunks);
    ``threads_per_task``: the sweep's worker threads inside a task (1: Dask's worker
    threads are the parallelism)."""
    return gather(client, submit(client, scenes, positions, orientations, t_min,
                                 chunk_poses=chunk_poses, poses_per_task=poses_per_task,
                                 threads_per_task=threads_per_task, retries=retries))


def local(scenes, positions, orientations=None, t_min=None, *, chunk_poses: int = 256,
          threads: int = 0) -> pd.DataFrame:
    """The same study in this process (``cablevib.sweep`` per scene, ``threads`` worker
    threads): the single-process reference of ``study``."""
    ss = _scenes(scenes)
    ps = _rows(positions, len(ss))
    qs = _rows(orientations, len(ss))
    ts = _rows(t_min, len(ss))
    parts = [frame(cablevib.sweep(s, ps[i], qs[i], ts[i], threads=threads,
                                  chunk_poses=chunk_poses), i, s.name)
             for i, s in enumerate(ss)]
    return pd.concat(parts, ignore_index=True)
