"""Poses per second of cablevib.sweep (1 thread, all cores) against a Python loop over
Estimator.update, on the paper's spatial robot, in one run; checks that the three give the
same numbers bit for bit (the loop is the sweep's definition: a fresh Estimator per chunk).

The poses are cut into rounds; each round runs the three methods in turn (in a rotating
order), so a change of the machine's load during the run hits all three alike. Printed per
method: the median over rounds of the wall-clock rate, and the process CPU time per pose
(summed over threads: the work, less sensitive to other processes than the wall clock).

    python python/examples/sweep_speed.py [--poses 100000] [--rounds 5] [--element massless]
"""

import argparse
import os
import statistics
import time

import numpy as np

import cablevib

ap = argparse.ArgumentParser()
ap.add_argument("--poses", type=int, default=100_000)
ap.add_argument("--rounds", type=int, default=5)
ap.add_argument("--element", default="fem",
                help="cable model: fem (the paper's, 40 elements), catenary, continuous, massless")
args = ap.parse_args()

scene = cablevib.Scene.load("spatial-paper")
if args.element != "fem":
    # The same robot (scenes/spatial_paper.toml) with another cable model.
    anchors = scene.anchors_m
    scene = cablevib.Scene.from_arrays(
        anchors, ee_mass_kg=30.0, ee_position_m=[0.0, 0.0, 1.25], name="spatial-paper",
        youngs_modulus_pa=2.01e10, area_m2=50.265e-6, weight_per_length_n_m=0.251,
        t_min_n=60.0, t_max_n=350.0, element=args.element, elements=40, sag=False)
# A grid over the central workspace, in the order a map walks it (x fastest).
side = max(2, int(np.ceil(args.poses ** (1 / 3) - 1e-9)))
xs = np.linspace(-0.9, 0.9, side)
zs = np.linspace(0.35, 2.15, side)
pos = np.array([(x, y, z) for z in zs for y in xs for x in xs])[: args.poses]
n = len(pos)
chunk = 256
cores = os.cpu_count()


def loop(p):
    f1 = np.empty(len(p))
    tens = np.empty((len(p), scene.n_cables))
    for a in range(0, len(p), chunk):
        est = cablevib.Estimator(scene)
        for i in range(a, min(a + chunk, len(p))):
            e = est.update(p[i])
            f1[i] = e.f1_hz
            tens[i] = e.tensions_n
    return f1, tens


def sweep(threads):
    def run(p):
        r = cablevib.sweep(scene, p, threads=threads, chunk_poses=chunk)
        return r["f1_hz"], r["tensions_n"]
    return run


methods = {"Python loop over update": loop, "sweep, 1 thread": sweep(1),
           f"sweep, all cores ({cores})": sweep(0)}
# Round boundaries on chunk boundaries, so every method sees the same chunks.
per_round = -(-n // args.rounds // chunk) * chunk
rates = {m: [] for m in methods}
cpu = {m: 0.0 for m in methods}
out = {m: [] for m in methods}
for k, a in enumerate(range(0, n, per_round)):
    p = pos[a:a + per_round]
    names = list(methods)
    names = names[k % 3:] + names[: k % 3]
    for m in names:
        w0, c0 = time.perf_counter(), time.process_time()
        out[m].append(methods[m](p))
        w, c = time.perf_counter() - w0, time.process_time() - c0
        rates[m].append(len(p) / w)
        cpu[m] += c

ref = [np.concatenate([o[j] for o in out["Python loop over update"]]) for j in (0, 1)]
for m in methods:
    got = [np.concatenate([o[j] for o in out[m]]) for j in (0, 1)]
    np.testing.assert_array_equal(got[0], ref[0])
    np.testing.assert_array_equal(got[1], ref[1])
ok = int(np.isfinite(ref[0]).sum())
print(f"{n} poses of {scene.name}, {scene.element} cables ({ok} ok), chunks of {chunk}, {len(rates[m])} rounds, "
      f"{cores} cores")
for m in methods:
    print(f"  {m:26s}: median {statistics.median(rates[m]):8.0f} poses/s "
          f"(rounds {min(rates[m]):.0f} .. {max(rates[m]):.0f}), "
          f"CPU {1e6 * cpu[m] / n:7.1f} us/pose")
print("  f1 and tensions of the three equal bit for bit")
