import numpy as np

import cablevib

scene = cablevib.Scene.load("spatial-paper")  # or a path to a scene .toml
print(scene.name, scene.n_cables, "cables,", scene.element, "x", scene.elements)

# One pose, as `cablevib analyze spatial-paper --position 0.3,0.1,1.2 --t-min 80 --json`.
r = cablevib.analyze(scene, position=[0.3, 0.1, 1.2], t_min=80.0, modes=5)
print("tensions (N):", np.round(r["tensions_n"], 2))
print("f (Hz):", np.round(r["frequencies_hz"], 4))

# A sweep with the real-time estimator: f1 (Hz) along a line through the workspace.
est = cablevib.Estimator(scene)
xs = np.linspace(-0.5, 0.5, 101)  # m
f1 = np.array([est.update([x, 0.0, 1.25]).f1_hz for x in xs])
print(f"f1 from {f1.min():.4f} to {f1.max():.4f} Hz")

# The smallest T_min (N) that lifts f1 to 12 Hz at the centre.
ans = est.t_min_for_f1([0.0, 0.0, 1.25], 12.0)
print(f"T_min {ans.t_min_n:.3f} N gives f1 {ans.f1_hz:.4f} Hz")
