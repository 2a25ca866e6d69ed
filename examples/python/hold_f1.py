"""Holding f1: the T_min set-point a controller publishes from the service's margin answers.

The Python mirror of service/src/hold.rs (`F1Hold`), used by controller.py's --hold-f1; the
rules, defaults and their reasons are that module's doc and docs/service.md ("Holding f1").
hold_f1_cases.json next to this file is a fixed sequence of answers with the set-points and
actions the Rust implementation produces (its tests write and check the file);
python/tests/test_hold_f1.py checks that this module reproduces them exactly.

- raise (f1 < required + guard), at once: a fresh answer (age 0) sets the answer's T_min; an
  older one the largest of the set-point, the answer's T_min and base * (request / f1)^2
  (f1 ~ sqrt(T_min)), base the smaller of the set-point and the one before its last change
  when the answer's pose is at most IN_FLIGHT_POSES after the pose that changed it, else the
  set-point;
- a tension_infeasible answer above the floor sends the set-point back to the floor;
- relax (f1 >= required + relax band): towards the answer's T_min, at most
  relax_rate_n_per_s per second of the answers' timestamps;
- hold in between; the set-point stays within [floor_n, ceiling_n] (a T_min above the
  ceiling gives the ceiling; +inf, unreachable, leaves the set-point as it is); not-ok answers and NaN T_min change nothing.
"""

import math

# Defaults, as service/src/hold.rs.
DEFAULT_GUARD_HZ = 0.1
DEFAULT_RELAX_BAND_HZ = 0.25
DEFAULT_RELAX_RATE_N_PER_S = 20.0
MAX_BAND_HZ = 1e3
MAX_RELAX_RATE_N_PER_S = 1e9
IN_FLIGHT_POSES = 1
# cablevib_ipc's status codes ok and tension_infeasible.
STATUS_OK = 0
STATUS_TENSION_INFEASIBLE = 1
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
        self.previous_n = params.floor_n
        self.change_pose_sequence = 0
        self.last_timestamp_ns = None

    def on_answer(self, ok, f1_hz, t_min_required_n, t_min_required_age_cycles, timestamp_ns,
                  pose_sequence, tension_infeasible=False):
        """Takes one margin answer's fields; returns the action ("no_answer", "held", "raised",
        "relaxed", "ceiling", "unreachable", "infeasible"). Publish when self.setpoint_n changed."""
        before = self.setpoint_n
        action = self._step(ok, f1_hz, t_min_required_n, t_min_required_age_cycles, timestamp_ns,
                            pose_sequence, tension_infeasible)
        if self.setpoint_n != before:
            self.previous_n = before
            self.change_pose_sequence = pose_sequence
        return action

    def _step(self, ok, f1_hz, t_min_required_n, t_min_required_age_cycles, timestamp_ns,
              pose_sequence, tension_infeasible):
        p = self.params
        if self.last_timestamp_ns is None:
            dt_s = 0.0
            self.last_timestamp_ns = timestamp_ns
        else:
            dt_s = max(0, timestamp_ns - self.last_timestamp_ns) * 1e-9
            self.last_timestamp_ns = max(timestamp_ns, self.last_timestamp_ns)
        if tension_infeasible and self.setpoint_n > p.floor_n:
            self.setpoint_n = p.floor_n
            return "infeasible"
        t = t_min_required_n
        if not ok or math.isnan(t) or not (math.isfinite(f1_hz) and f1_hz > 0.0) or t <= 0.0:
            return "no_answer"
        if t == math.inf:
            return "unreachable"
        target = min(max(t, p.floor_n), p.ceiling_n)
        request_hz = p.request_hz()
        if f1_hz < request_hz:
            if t_min_required_age_cycles == 0:
                self.setpoint_n = target
            else:
                r = request_hz / f1_hz
                if pose_sequence <= self.change_pose_sequence + IN_FLIGHT_POSES:
                    base = min(self.setpoint_n, self.previous_n)
                else:
                    base = self.setpoint_n
                scaled = min(base * (r * r), p.ceiling_n)
                self.setpoint_n = max(self.setpoint_n, target, scaled)
            return "ceiling" if t > p.ceiling_n or self.setpoint_n >= p.ceiling_n else "raised"
        if f1_hz >= p.required_hz + p.relax_band_hz and target < self.setpoint_n:
            self.setpoint_n = max(target, self.setpoint_n - p.relax_rate_n_per_s * dt_s)
            return "relaxed"
        return "held"

    def on_response(self, r):
        """on_answer with a cablevib_ipc.MarginResponse (status 0 is ok)."""
        return self.on_answer(r.status == STATUS_OK, r.f1_hz, r.t_min_required_n,
                              r.t_min_required_age_cycles, r.timestamp_ns, r.pose_sequence,
                              r.status == STATUS_TENSION_INFEASIBLE)
