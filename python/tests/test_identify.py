"""cablevib.identify against `cablevib identify --json` on the same record (the same library
function behind two front ends: equal to the last bit), and against the record's known modes:
two modes simulated here by exact discrete-time integration, 60 s at 1 kHz, 2 channels."""

import math

import numpy as np
import pytest

import cablevib


def record(tmp_path, forced=False):
    """Two modes (4 Hz ζ 1 %, 9 Hz ζ 2 %) under white noise, exact per step for a force held
    over it; accelerations on two channels with 20 dB sensor noise. `forced`: one measured
    white force u drives both modes (modal participations 1 and 0.7), written as column fx."""
    rng = np.random.default_rng(7)
    n = 60_000
    force = rng.standard_normal(n) if forced else None
    fs = 1000.0
    h = 1.0 / fs
    modes = [(4.0, 0.01, (1.0, 0.5)), (9.0, 0.02, (0.3, -1.0))]
    y = np.zeros((n, 2))
    for (f, z, phi), part in zip(modes, (1.0, 0.7)):
        w = 2 * math.pi * f
        s, wd = z * w, w * math.sqrt(1 - z * z)
        c, sn, ex = math.cos(wd * h), math.sin(wd * h), math.exp(-s * h)
        e = np.array([[ex * (c + s / wd * sn), ex * sn / wd],
                      [-ex * w * w * sn / wd, ex * (c - s / wd * sn)]])
        u = part * force if forced else rng.standard_normal(n)
        q = np.zeros(2)
        a = np.empty(n)
        for k in range(n):
            a[k] = u[k] - 2 * z * w * q[1] - w * w * q[0]
            qs = u[k] / (w * w)
            q = e @ (q - [qs, 0.0]) + [qs, 0.0]
        y += np.outer(a, phi)
    y += rng.standard_normal(y.shape) * y.std(axis=0) / 10.0
    t = np.arange(n) * h
    path = tmp_path / ("forced.csv" if forced else "rec.csv")
    with open(path, "w") as f:
        f.write("t,ax,ay,fx\n" if forced else "t,ax,ay\n")
        for k in range(n):
            extra = f",{float(force[k])!r}" if forced else ""
            f.write(f"{float(t[k])!r},{float(y[k, 0])!r},{float(y[k, 1])!r}{extra}\n")
    out = (t, y, path, [m[0] for m in modes], [m[1] for m in modes])
    return out + (force,) if forced else out


def same_and_known(py, cli, f_true, z_true, keys):
    """Window 0 of the binding and of the command line: the same status and modes (`keys`
    equal to the last bit), each within the record's statistical limits (docs/identify.md:
    3σ in frequency and damping) of the known mode."""
    wp, wc = py["windows"][0], cli["windows"][0]
    assert wp["status"] == wc["status"] == "ok"
    assert len(wp["modes"]) == len(wc["modes"]) == 2
    for mp, mc, f, z in zip(wp["modes"], wc["modes"], f_true, z_true):
        for k in keys:
            assert mp[k] == mc[k], k
        w = 2 * math.pi * f
        sf, sz = math.sqrt(z / (w * 60.0)), 1.0 / math.sqrt(z * w * 60.0)
        assert abs(mp["frequency_hz"] - f) / f <= max(3 * sf, 1e-3)
        assert abs(mp["damping_ratio"] - z) / z <= max(3 * sz, 0.1)


def test_identify_equals_the_command_line_and_finds_the_modes(tmp_path, cli_json):
    t, y, path, f_true, z_true = record(tmp_path)
    py = cablevib.identify(t, y, to_hz=30.0)
    cli = cli_json("identify", str(path), "--to-hz", "30")
    for k in ("t_start_s", "t_end_s", "samples"):
        assert py["windows"][0][k] == cli["windows"][0][k]
    same_and_known(py, cli, f_true, z_true,
                   ("frequency_hz", "damping_ratio", "frequency_std_hz", "damping_ratio_std"))


def test_identify_refusals():
    t = np.arange(1000) * 0.01
    # The band's top named as the argument is (the command line says --to-hz).
    with pytest.raises(cablevib.CablevibError, match="too low for the band.*lower to_hz to"):
        cablevib.identify(t, np.zeros((1000, 2)))
    with pytest.raises(cablevib.CablevibError, match="shape"):
        cablevib.identify(t, np.zeros((999, 2)))
    bad = t.copy()
    bad[500] = bad[499]
    with pytest.raises(cablevib.CablevibError, match="duplicated"):
        cablevib.identify(bad, np.zeros(1000), to_hz=20.0)


def test_identify_with_a_measured_input_equals_the_command_line(tmp_path, cli_json):
    """inputs=: H1 and its modal fit, as `--input fx`, to the last bit; the known modes to
    the record's 3σ limits."""
    t, y, path, f_true, z_true, force = record(tmp_path, forced=True)
    py = cablevib.identify(t, y, to_hz=30.0, inputs=force)
    cli = cli_json("identify", str(path), "--to-hz", "30", "--input", "fx")
    assert cli["method"] == "h1-era"
    same_and_known(py, cli, f_true, z_true,
                   ("frequency_hz", "damping_ratio", "frequency_std_hz", "coherence"))
    with pytest.raises(cablevib.CablevibError, match="shape"):
        cablevib.identify(t, y, to_hz=30.0, inputs=force[:-1])
