"""Holding f1: the T_min set-point a controller publishes from the service's margin answers.

The Python mirror of service/src/hold.rs (`F1Hold`), used by controller.py's --hold-f1; the
rules, defaults and their reasons are that module's doc and docs/service.md ("Holding f1").
hold_f1_cases.json next to this file is a fixed sequence of answers with the set-points and
actions the Rust implementation produces (its tests write and check the file);
python/tests/test_hold_f1.py checks that this module reproduces them exactly.

- raise (f1 < required + guard): the set-point becomes the answer's T_min at once; an answer
  older than its pose (age > 0) never lowers it while raising, a fresh one (age 0) may;
- relax (f1 >= required + relax band): towards the answer's T_min, at most
  relax_rate_n_per_s per second of the answers' timestamps;
- hold in between; the set-point stays within [floor_n, ceiling_n] (+inf or a T_min above
  the ceiling gives the ceiling); not-ok answers and NaN T_min change nothing.
"""

import math

# Defaults, as service/src/hold.rs.
DEFAULT_GUARD_HZ = 0.05
DEFAULT_RELAX_BAND_HZ = 0.15
DEFAULT_RELAX_RATE_N_PER_S = 20.0
MAX_BAND_HZ = 1e3
MAX_RELAX_RATE_N_PER_S = 1e9
# cablevib_ipc's REQUIRED_F1_MIN_HZ / REQUIRED_F1_MAX_HZ (the margin request's range).
REQUIRED_F1_MIN_HZ = 1e-6
REQUIRED_F1_MAX_HZ = 1e6


class HoldError(ValueError):
    """A bad hold parameter (one line)."""


def _check(what, value, ok, bound):
    if not (ok and math.isfinite(value)):
        raise HoldError("%s %r must be %s" % (what, value, bound))


class HoldParams:
    """What the hold acts on; the constructor checks every value (HoldError)."""

    def __init__(self, required_hz, floor_n, ceiling_n, guard_hz=DEFAULT_GUARD_HZ,
                 relax_band_hz=DEFAULT_RELAX_BAND_HZ,
                 relax_rate_n_per_s=DEFAULT_RELAX_RATE_N_PER_S):
        self.required_hz = float(required_hz)
        self.guard_hz = float(guard_hz)
        self.relax_band_hz = float(relax_band_hz)
        self.relax_rate_n_per_s = float(relax_rate_n_per_s)
        self.floor_n = float(floor_n)
        self.ceiling_n = float(ceiling_n)
        r, g, b = self.required_hz, self.guard_hz, self.relax_band_hz
        _check("hold-f1 (Hz)", r, REQUIRED_F1_MIN_HZ <= r <= REQUIRED_F1_MAX_HZ,
               "in [%g, %g] Hz" % (REQUIRED_F1_MIN_HZ, REQUIRED_F1_MAX_HZ))
        _check("hold guard (Hz)", g, 0.0 <= g <= MAX_BAND_HZ and r + g <= REQUIRED_F1_MAX_HZ,
               "in [0, %g] Hz, with hold-f1 + guard <= %g Hz" % (MAX_BAND_HZ, REQUIRED_F1_MAX_HZ))
        _check("hold relax band (Hz)", b, g < b <= MAX_BAND_HZ,
               "> the guard (%g Hz) and <= %g Hz" % (g, MAX_BAND_HZ))
        _check("hold relax rate (N/s)", self.relax_rate_n_per_s,
               0.0 < self.relax_rate_n_per_s <= MAX_RELAX_RATE_N_PER_S,
               "in (0, %g] N/s" % MAX_RELAX_RATE_N_PER_S)
        _check("hold ceiling (N)", self.ceiling_n, self.ceiling_n > 0.0,
               "finite and > 0 N (the smallest cable t_max)")
        _check("hold floor (N)", self.floor_n, 0.0 < self.floor_n <= self.ceiling_n,
               "in (0, %g] N (the ceiling, the smallest cable t_max)" % self.ceiling_n)

    def request_hz(self):
        """The frequency the margin query asks for, Hz: required + guard."""
        return self.required_hz + self.guard_hz


class F1Hold:
    """The hold's state: the set-point in force (starting at the floor) and the last answer's
    time."""

    def __init__(self, params):
        self.params = params
        self.setpoint_n = params.floor_n
        self.last_timestamp_ns = None

    def on_answer(self, ok, f1_hz, t_min_required_n, t_min_required_age_cycles, timestamp_ns):
        """Takes one margin answer's fields; returns the action ("no_answer", "held", "raised",
        "relaxed", "ceiling"). Publish when self.setpoint_n changed."""
        p = self.params
        if self.last_timestamp_ns is None:
            dt_s = 0.0
            self.last_timestamp_ns = timestamp_ns
        else:
            dt_s = max(0, timestamp_ns - self.last_timestamp_ns) * 1e-9
            self.last_timestamp_ns = max(timestamp_ns, self.last_timestamp_ns)
        t = t_min_required_n
        if not ok or math.isnan(t) or not math.isfinite(f1_hz) or t <= 0.0:
            return "no_answer"
        above_ceiling = t > p.ceiling_n
        target = min(max(t, p.floor_n), p.ceiling_n)
        if f1_hz < p.required_hz + p.guard_hz:
            if t_min_required_age_cycles == 0:
                self.setpoint_n = target
            else:
                self.setpoint_n = max(self.setpoint_n, target)
            return "ceiling" if above_ceiling else "raised"
        if f1_hz >= p.required_hz + p.relax_band_hz and target < self.setpoint_n:
            self.setpoint_n = max(target, self.setpoint_n - p.relax_rate_n_per_s * dt_s)
            return "relaxed"
        return "held"

    def on_response(self, r):
        """on_answer with a cablevib_ipc.MarginResponse (status 0 is ok)."""
        return self.on_answer(r.status == 0, r.f1_hz, r.t_min_required_n,
                              r.t_min_required_age_cycles, r.timestamp_ns)
