"""A design study: the paper's spatial robot (8 cables, 30 kg point mass, 4 mm cables) on a
family of cube-like frames — frame height H and anchor spread (half width) A — and, for
each design, the worst f1 and the worst k_min (the softest static stiffness) over one
workspace grid. Prints the table and the best design, writes an SVG figure.

    python python/examples/design_study.py [--out design_study.svg] [--side 11]
        [--scheduler tcp://HOST:8786 | --local-cluster 2]

By default the study runs in this process (``cablevib.sweep``, every core). With
``--scheduler`` (a running Dask cluster) or ``--local-cluster N`` (N worker processes here)
it runs through ``cablevib.dask`` (``pip install ./python[dask]``) with the same numbers,
bit for bit. No plotting library: the figure is written as SVG text.
"""

import argparse
import time

import numpy as np

import cablevib

HEIGHTS_M = [2.0, 2.25, 2.5, 2.75, 3.0, 3.5]
SPREADS_M = [1.0, 1.125, 1.25, 1.5, 1.75, 2.0]
# The workspace every design must serve: a 1.0 × 1.0 × 0.8 m box around (0, 0, 1.0) m.
WORKSPACE = dict(x=(-0.5, 0.5), y=(-0.5, 0.5), z=(0.6, 1.4))


def design(height_m, spread_m):
    """The paper's robot (scenes/spatial_paper.toml) on a frame of this height and spread."""
    anchors = [[sx * spread_m, sy * spread_m, z] for z in (height_m, 0.0)
               for (sx, sy) in ((1, 1), (-1, 1), (-1, -1), (1, -1))]
    return cablevib.Scene.from_arrays(
        anchors, ee_mass_kg=30.0, ee_position_m=[0.0, 0.0, 1.0],
        name=f"H{height_m:g}-A{spread_m:g}", youngs_modulus_pa=2.01e10, area_m2=50.265e-6,
        weight_per_length_n_m=0.251, t_min_n=60.0, t_max_n=350.0, element="fem",
        elements=40, sag=False)


def grid(side):
    axes = [np.linspace(*WORKSPACE[k], side) for k in "xyz"]
    return np.array([(x, y, z) for z in axes[2] for y in axes[1] for x in axes[0]])


def run(scenes, poses, args):
    if args.scheduler or args.local_cluster:
        from dask.distributed import Client, LocalCluster

        import cablevib.dask as cd

        if args.scheduler:
            client = Client(args.scheduler)
        else:
            client = Client(LocalCluster(n_workers=args.local_cluster, threads_per_worker=1,
                                         dashboard_address=None))
        with client:
            df = cd.study(client, scenes, poses)
        return [df[df["scene"] == i] for i in range(len(scenes))]
    out = []
    for s in scenes:
        r = cablevib.sweep(s, poses)
        out.append({"status": r["status"], "f1_hz": r["f1_hz"],
                    "stiffness_min_n_m": r["k_min_n_m"]})
    return out


def heat_svg(title, unit, values, best, x0, y0, cell=46):
    """One heat map (rows: heights, columns: spreads) as SVG elements at (x0, y0)."""
    finite = values[np.isfinite(values)]
    lo, hi = (finite.min(), finite.max()) if finite.size else (0.0, 1.0)
    e = [f'<text x="{x0}" y="{y0 - 28}" font-size="14">{title}</text>']
    for i, h in enumerate(HEIGHTS_M):
        y = y0 + (len(HEIGHTS_M) - 1 - i) * cell
        e.append(f'<text x="{x0 - 8}" y="{y + cell / 2 + 4}" font-size="11" '
                 f'text-anchor="end">{h:g}</text>')
        for j, a in enumerate(SPREADS_M):
            x = x0 + j * cell
            v = values[i, j]
            if np.isfinite(v):
                u = (v - lo) / (hi - lo) if hi > lo else 0.5
                col = f"rgb({int(255 * (1 - u))},{int(120 + 100 * u)},{int(255 * u)})"
                label = f"{v:.3g}"
            else:
                col, label = "#bbbbbb", "fails"
            stroke = ' stroke="black" stroke-width="3"' if (i, j) == best else ""
            e.append(f'<rect x="{x}" y="{y}" width="{cell}" height="{cell}" fill="{col}"'
                     f'{stroke}/>')
            e.append(f'<text x="{x + cell / 2}" y="{y + cell / 2 + 4}" font-size="10" '
                     f'text-anchor="middle">{label}</text>')
    yb = y0 + len(HEIGHTS_M) * cell
    for j, a in enumerate(SPREADS_M):
        e.append(f'<text x="{x0 + j * cell + cell / 2}" y="{yb + 14}" font-size="11" '
                 f'text-anchor="middle">{a:g}</text>')
    e.append(f'<text x="{x0 + len(SPREADS_M) * cell / 2}" y="{yb + 32}" font-size="12" '
             f'text-anchor="middle">anchor spread A, m ({unit} in the cells)</text>')
    e.append(f'<text x="{x0 - 40}" y="{y0 + len(HEIGHTS_M) * cell / 2}" font-size="12" '
             f'text-anchor="middle" transform="rotate(-90 {x0 - 40} '
             f'{y0 + len(HEIGHTS_M) * cell / 2})">frame height H, m</text>')
    return e


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--out", default="design_study.svg")
    ap.add_argument("--side", type=int, default=11, help="grid values per workspace axis")
    ap.add_argument("--scheduler", help="address of a running Dask scheduler")
    ap.add_argument("--local-cluster", type=int, default=0, metavar="N",
                    help="run on a Dask LocalCluster of N worker processes")
    args = ap.parse_args()

    scenes = [design(h, a) for h in HEIGHTS_M for a in SPREADS_M]
    poses = grid(args.side)
    t0 = time.perf_counter()
    results = run(scenes, poses, args)
    secs = time.perf_counter() - t0
    n = len(scenes) * len(poses)

    f1 = np.full((len(HEIGHTS_M), len(SPREADS_M)), np.nan)
    kmin = np.full_like(f1, np.nan)
    print(f"{'design':>12} {'ok':>9} {'worst f1 Hz':>12} {'worst k_min N/m':>16}")
    for idx, (s, r) in enumerate(zip(scenes, results)):
        i, j = divmod(idx, len(SPREADS_M))
        ok = np.asarray(r["status"]) == "ok"
        # A design must serve the whole workspace: a point it cannot hold fails it.
        if ok.all():
            f1[i, j] = np.min(r["f1_hz"])
            kmin[i, j] = np.min(r["stiffness_min_n_m"])
        print(f"{s.name:>12} {ok.sum():>4}/{len(ok):<4} {f1[i, j]:12.4f} {kmin[i, j]:16.0f}")
    if np.isfinite(f1).any():
        best = np.unravel_index(np.nanargmax(f1), f1.shape)
        print(f"best design (highest worst f1): H = {HEIGHTS_M[best[0]]} m, "
              f"A = {SPREADS_M[best[1]]} m: worst f1 {f1[best]:.4f} Hz, "
              f"worst k_min {kmin[best]:.0f} N/m")
        kbest = np.unravel_index(np.nanargmax(kmin), kmin.shape)
        print(f"stiffest design (highest worst k_min): H = {HEIGHTS_M[kbest[0]]} m, "
              f"A = {SPREADS_M[kbest[1]]} m: worst k_min {kmin[kbest]:.0f} N/m, "
              f"worst f1 {f1[kbest]:.4f} Hz")
    else:
        best = (-1, -1)
        print("no design serves the whole workspace")
    print(f"{n} poses ({len(scenes)} designs x {len(poses)}) in {secs:.2f} s: "
          f"{n / secs:.0f} poses/s")

    cell = 46
    width = 2 * (len(SPREADS_M) * cell + 120) + 40
    height = len(HEIGHTS_M) * cell + 130
    e = [f'<svg xmlns="http://www.w3.org/2000/svg" width="{width}" height="{height}" '
         f'font-family="sans-serif">',
         f'<rect width="{width}" height="{height}" fill="white"/>']
    e += heat_svg("worst f1 over the workspace, Hz", "Hz", f1, best, 100, 60, cell)
    e += heat_svg("worst k_min over the workspace, N/m", "N/m", kmin, best,
                  100 + len(SPREADS_M) * cell + 160, 60, cell)
    e.append("</svg>")
    with open(args.out, "w") as fh:
        fh.write("\n".join(e) + "\n")
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
