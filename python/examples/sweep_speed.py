"""Poses per second of cablevib.sweep (1 thread, all cores) against a Python loop over
Estimator.update, on the paper's spatial robot, in one run; checks that the three give the
same numbers bit for bit (the loop is the sweep's definition: a fresh Estimator per chunk).

    python python/examples/sweep_speed.py [--poses 100000]
"""

import argparse
import os
import time

import numpy as np

import cablevib

ap = argparse.ArgumentParser()
ap.add_argument("--poses", type=int, default=100_000)
args = ap.parse_args()

scene = cablevib.Scene.load("spatial-paper")
# A grid over the central workspace, in the order a map walks it (x fastest).
side = max(2, int(np.ceil(args.poses ** (1 / 3) - 1e-9)))
xs = np.linspace(-0.9, 0.9, side)
zs = np.linspace(0.35, 2.15, side)
pos = np.array([(x, y, z) for z in zs for y in xs for x in xs])[: args.poses]
n = len(pos)
chunk = 256
cores = os.cpu_count()


def timed(f):
    t0 = time.perf_counter()
    r = f()
    return r, time.perf_counter() - t0


one, t_one = timed(lambda: cablevib.sweep(scene, pos, threads=1, chunk_poses=chunk))
allc, t_all = timed(lambda: cablevib.sweep(scene, pos, threads=0, chunk_poses=chunk))


def loop():
    f1 = np.empty(n)
    tens = np.empty((n, scene.n_cables))
    for a in range(0, n, chunk):
        est = cablevib.Estimator(scene)
        for i in range(a, min(a + chunk, n)):
            e = est.update(pos[i])
            f1[i] = e.f1_hz
            tens[i] = e.tensions_n
    return f1, tens


(f1_loop, tens_loop), t_loop = timed(loop)

for r in (one, allc):
    np.testing.assert_array_equal(r["f1_hz"], f1_loop)
    np.testing.assert_array_equal(r["tensions_n"], tens_loop)
ok = int(one["ok"].sum())
print(f"{n} poses of {scene.name} ({ok} ok), chunks of {chunk}, {cores} cores")
print(f"  Python loop over update : {n / t_loop:10.0f} poses/s  ({t_loop:.2f} s)")
print(f"  sweep, 1 thread         : {n / t_one:10.0f} poses/s  ({t_one:.2f} s)")
print(f"  sweep, all cores ({allc['threads']:2d})   : {n / t_all:10.0f} poses/s  ({t_all:.2f} s)")
print("  f1 and tensions of the three equal bit for bit")
