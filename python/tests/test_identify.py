"""cablevib.identify against `cablevib identify --json` on the same record (the same library
function behind two front ends: equal to the last bit), and against the record's known modes:
two modes simulated here by exact discrete-time integration, 60 s at 1 kHz, 2 channels."""

import math

import numpy as np
import pytest

import cablevib


def record(tmp_path):
    """Two modes (4 Hz ζ 1 %, 9 Hz ζ 2 %) under white noise, exact per step for a force held
    over it; accelerations on two channels with 20 dB sensor noise."""
    rng = np.random.default_rng(7)
    fs, n = 1000.0, 60_000
    h = 1.0 / fs
    modes = [(4.0, 0.01, (1.0, 0.5)), (9.0, 0.02, (0.3, -1.0))]
    y = np.zeros((n, 2))
    for f, z, phi in modes:
        w = 2 * math.pi * f
        s, wd = z * w, w * math.sqrt(1 - z * z)
        c, sn, ex = math.cos(wd * h), math.sin(wd * h), math.exp(-s * h)
        e = np.array([[ex * (c + s / wd * sn), ex * sn / wd],
                      [-ex * w * w * sn / wd, ex * (c - s / wd * sn)]])
        u = rng.standard_normal(n)
        q = np.zeros(2)
        a = np.empty(n)
        for k in range(n):
            a[k] = u[k] - 2 * z * w * q[1] - w * w * q[0]
            qs = u[k] / (w * w)
            q = e @ (q - [qs, 0.0]) + [qs, 0.0]
        y += np.outer(a, phi)
    y += rng.standard_normal(y.shape) * y.std(axis=0) / 10.0
    t = np.arange(n) * h
    path = tmp_path / "rec.csv"
    with open(path, "w") as f:
        f.write("t,ax,ay\n")
        for k in range(n):
            f.write(f"{float(t[k])!r},{float(y[k, 0])!r},{float(y[k, 1])!r}\n")
    return t, y, path, [m[0] for m in modes], [m[1] for m in modes]


def test_identify_equals_the_command_line_and_finds_the_modes(tmp_path, cli_json):
    t, y, path, f_true, z_true = record(tmp_path)
    py = cablevib.identify(t, y, to_hz=30.0)
    cli = cli_json("identify", str(path), "--to-hz", "30")
    wp, wc = py["windows"][0], cli["windows"][0]
    assert wp["status"] == wc["status"] == "ok"
    for k in ("t_start_s", "t_end_s", "samples"):
        assert wp[k] == wc[k]
    assert len(wp["modes"]) == len(wc["modes"]) == 2
    for mp, mc, f, z in zip(wp["modes"], wc["modes"], f_true, z_true):
        for k in ("frequency_hz", "damping_ratio", "frequency_std_hz", "damping_ratio_std"):
            assert mp[k] == mc[k], k
        # The record's statistical limits (docs/identify.md): 3σ in frequency and damping.
        w = 2 * math.pi * f
        sf, sz = math.sqrt(z / (w * 60.0)), 1.0 / math.sqrt(z * w * 60.0)
        assert abs(mp["frequency_hz"] - f) / f <= max(3 * sf, 1e-3)
        assert abs(mp["damping_ratio"] - z) / z <= max(3 * sz, 0.1)


def test_identify_refusals():
    t = np.arange(1000) * 0.01
    with pytest.raises(cablevib.CablevibError, match="too low for the band"):
        cablevib.identify(t, np.zeros((1000, 2)))
    with pytest.raises(cablevib.CablevibError, match="shape"):
        cablevib.identify(t, np.zeros((999, 2)))
    bad = t.copy()
    bad[500] = bad[499]
    with pytest.raises(cablevib.CablevibError, match="duplicated"):
        cablevib.identify(bad, np.zeros(1000), to_hz=20.0)
