#!/usr/bin/env python3
"""Python controller of a running `cablevib serve`, over iceoryx2 (zero-copy shared memory).

The Python twin of service/examples/controller.rs: takes the estimates as they arrive, asks the
service for its vibration margin against --required-hz (request-response: MarginRequest ->
MarginResponse, margin = f1 - required for the latest pose), prints f1 and the margin once per
second and a summary at the end.

Before it talks it reads the iceoryx2 service attributes of the estimate and margin services
and exits with a one-line error when their schema version is not the one of the message
definitions it imports (ipc-schema/python/cablevib_ipc.py, generated from the Rust layout).

    python3 -m venv venv && venv/bin/pip install iceoryx2==0.10.0 flatbuffers==25.12.19
    cablevib serve --instance demo &
    cargo run --release --example replay -- --instance demo --seconds 10 &
    venv/bin/python examples/python/controller.py --instance demo --seconds 5

The service must be running (the controller waits --connect-timeout-s for it): unlike the
Rust peers, this script opens the services and never creates them.

With --hold-f1 HZ it acts on the margin, as the Rust controller does: it asks for HZ + guard
and publishes the uniform T_min set-point of hold_f1.py (the mirror of service/src/hold.rs:
raised at once, relaxed rate-limited above a hysteresis band, between --hold-floor-n and
--hold-ceiling-n; docs/service.md, "Holding f1"):

    venv/bin/python examples/python/controller.py --instance demo --seconds 5 \
        --hold-f1 9.5 --hold-floor-n 60 --hold-ceiling-n 350
"""

import argparse
import ctypes
import json
import math
import os
import sys
import time

sys.path.insert(
    0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "ipc-schema", "python")
)

import cablevib_ipc as cv  # noqa: E402
import hold_f1  # noqa: E402
import iceoryx2 as iox2  # noqa: E402

# How long one blocking wait on the wake-controller event lasts at most, s: the loop checks the
# clock (and answers Ctrl-C) at least this often.
WAIT_SLICE_S = 0.010
# A margin request unanswered for this long is counted as lost and a new one is sent, s.
MARGIN_TIMEOUT_S = 0.5
# How often the controller looks for the service while it waits for it to come up, s.
CONNECT_POLL_S = 0.05


def fail(message):
    """Prints a one-line error and exits with status 2."""
    print("%s: error: %s" % (os.path.basename(sys.argv[0]), message), file=sys.stderr)
    sys.exit(2)


def parse_args():
    p = argparse.ArgumentParser(description="Take estimates and margins from a cablevib service.")
    p.add_argument("--instance", default="", help="instance name, as given to `cablevib serve --instance`")
    p.add_argument("--seconds", type=float, default=10.0, help="how long to run, s (default 10)")
    p.add_argument("--required-hz", type=float, default=8.0,
                   help="required first natural frequency, Hz: margin = f1 - required (default 8)")
    p.add_argument("--connect-timeout-s", type=float, default=10.0,
                   help="how long to wait for the service to come up, s (default 10)")
    p.add_argument("--json", action="store_true", help="end with a one-line JSON summary on stdout")
    p.add_argument("--hold-f1", type=float, metavar="HZ",
                   help="hold f1 at or above HZ: publish the T_min set-point the margin answers name "
                        "(raised at once below HZ + guard, relaxed when f1 >= HZ + relax band); the "
                        "margin is then asked against HZ + guard; needs --hold-floor-n and "
                        "--hold-ceiling-n")
    p.add_argument("--hold-floor-n", type=float, metavar="N",
                   help="lowest set-point the hold relaxes to, N: the scene's T_min")
    p.add_argument("--hold-ceiling-n", type=float, metavar="N",
                   help="highest set-point, N: the smallest t_max of the scene's cables")
    p.add_argument("--hold-guard-hz", type=float, default=hold_f1.DEFAULT_GUARD_HZ, metavar="HZ",
                   help="guard above HZ the hold raises to, Hz (default %(default)s)")
    p.add_argument("--hold-relax-band-hz", type=float, default=hold_f1.DEFAULT_RELAX_BAND_HZ,
                   metavar="HZ", help="relax only when f1 >= HZ + this, Hz (> the guard; default "
                   "%(default)s)")
    p.add_argument("--hold-relax-n-per-s", type=float, default=hold_f1.DEFAULT_RELAX_RATE_N_PER_S,
                   metavar="N_PER_S", help="largest decrease of the set-point per second, N/s "
                   "(default %(default)s)")
    a = p.parse_args()
    if not (math.isfinite(a.seconds) and a.seconds > 0):
        fail("--seconds must be finite and > 0")
    if not (math.isfinite(a.required_hz) and a.required_hz > 0):
        fail("--required-hz must be finite and > 0")
    a.hold = None
    if a.hold_f1 is not None:
        if a.hold_floor_n is None or a.hold_ceiling_n is None:
            fail("--hold-f1 needs --hold-floor-n (the scene's T_min, N) and --hold-ceiling-n "
                 "(the smallest cable t_max, N)")
        try:
            a.hold = hold_f1.HoldParams(a.hold_f1, a.hold_floor_n, a.hold_ceiling_n,
                                        guard_hz=a.hold_guard_hz,
                                        relax_band_hz=a.hold_relax_band_hz,
                                        relax_rate_n_per_s=a.hold_relax_n_per_s)
        except hold_f1.HoldError as e:
            fail(str(e))
        a.required_hz = a.hold.request_hz()
    elif a.hold_floor_n is not None or a.hold_ceiling_n is not None:
        fail("--hold-floor-n and --hold-ceiling-n need --hold-f1")
    return a


def service_attributes(name, pattern, timeout_s):
    """The attributes {key: value} of service `name`, once it exists (None on timeout)."""
    sname = iox2.ServiceName.new(name)
    deadline = time.monotonic() + timeout_s
    while True:
        details = iox2.Service.details(sname, iox2.config.global_config(), pattern, iox2.ServiceType.Ipc)
        if details is not None:
            return {a.key.to_string(): a.value.to_string() for a in details.attributes().values}
        if time.monotonic() > deadline:
            return None
        time.sleep(CONNECT_POLL_S)


def check_schema(name, attributes):
    """Exits with a one-line error unless service `name` speaks this module's schema."""
    found = attributes.get(cv.ATTR_SCHEMA_VERSION)
    if found != str(cv.SCHEMA_VERSION):
        fail('service "%s" has %s = %s, but this controller speaks cablevib-ipc schema v%d; '
             "regenerate ipc-schema/python/cablevib_ipc.py from the service's schema" % (
                 name, cv.ATTR_SCHEMA_VERSION, "(none)" if found is None else '"%s"' % found,
                 cv.SCHEMA_VERSION))


def schema_verifier():
    """iceoryx2 refuses to open a service without this schema-version attribute."""
    return iox2.AttributeVerifier.new().require(
        iox2.AttributeKey.new(cv.ATTR_SCHEMA_VERSION), iox2.AttributeValue.new(str(cv.SCHEMA_VERSION)))


class Ports:
    """Estimate subscriber, margin client, and the two wake-up event ports."""

    def __init__(self, node, instance, timeout_s, t_min_publisher=False):
        names = {base: cv.prefixed(instance, base) for base in (
            cv.SERVICE_ESTIMATE, cv.SERVICE_MARGIN, cv.SERVICE_WAKE_SERVICE, cv.SERVICE_WAKE_CONTROLLER)}
        self.estimate_name = names[cv.SERVICE_ESTIMATE]
        margin_name = names[cv.SERVICE_MARGIN]
        self.attributes = None
        # The wake services too: the service creates them after the estimate and margin ones.
        for name, pattern in ((self.estimate_name, iox2.MessagingPattern.PublishSubscribe),
                              (margin_name, iox2.MessagingPattern.RequestResponse),
                              (names[cv.SERVICE_WAKE_SERVICE], iox2.MessagingPattern.Event),
                              (names[cv.SERVICE_WAKE_CONTROLLER], iox2.MessagingPattern.Event)):
            attributes = service_attributes(name, pattern, timeout_s)
            if attributes is None:
                fail('no cablevib service "%s" within %g s: is `cablevib serve --instance %s` running?' % (
                    name, timeout_s, instance))
            check_schema(name, attributes)
            self.attributes = self.attributes or attributes
        try:
            estimate = node.service_builder(iox2.ServiceName.new(self.estimate_name)) \
                .publish_subscribe(cv.EstimateSample).open_with_attributes(schema_verifier())
            margin = node.service_builder(iox2.ServiceName.new(margin_name)) \
                .request_response(cv.MarginRequest, cv.MarginResponse).open_with_attributes(schema_verifier())
        except (iox2.PublishSubscribeOpenError, iox2.RequestResponseOpenError) as e:
            fail("cannot open the cablevib services of instance \"%s\": %s (another schema or "
                 "layout than ipc-schema/python/cablevib_ipc.py?)" % (instance, e))
        self.subscriber = estimate.subscriber_builder().create()
        self.client = margin.client_builder().create()
        wake_service = node.service_builder(iox2.ServiceName.new(names[cv.SERVICE_WAKE_SERVICE])).event().open()
        wake_controller = node.service_builder(iox2.ServiceName.new(names[cv.SERVICE_WAKE_CONTROLLER])).event().open()
        self.notifier = wake_service.notifier_builder().create()
        self.listener = wake_controller.listener_builder().create()
        self.t_min = None
        if t_min_publisher:
            try:
                t_min = node.service_builder(iox2.ServiceName.new(cv.prefixed(instance, cv.SERVICE_T_MIN))) \
                    .publish_subscribe(cv.TminSetpoint).open_with_attributes(schema_verifier())
            except iox2.PublishSubscribeOpenError as e:
                fail("cannot open the T_min service of instance \"%s\": %s" % (instance, e))
            self.t_min = t_min.publisher_builder().create()

    def send_t_min(self, sequence, t_min_n):
        """Publishes a uniform T_min set-point (N) and wakes the service."""
        self.t_min.send_copy(cv.TminSetpoint(sequence=sequence, timestamp_ns=time.monotonic_ns(),
                                             t_min_n=t_min_n))
        self.notifier.notify_with_custom_event_id(iox2.EventId.new(cv.EVENT_ID_T_MIN))

    def estimates(self):
        """Copies of every queued estimate, oldest first (each sample is released at once)."""
        out = []
        while True:
            sample = self.subscriber.receive()
            if sample is None:
                return out
            out.append(cv.EstimateSample.from_buffer_copy(sample.payload().contents))
            sample.delete()

    def ask_margin(self, sequence, required_hz):
        """Sends a margin request and wakes the service; returns the pending response."""
        request = cv.MarginRequest(sequence=sequence, timestamp_ns=time.monotonic_ns(),
                                   required_f1_hz=required_hz)
        pending = self.client.send_copy(request)
        self.notifier.notify_with_custom_event_id(iox2.EventId.new(cv.EVENT_ID_MARGIN_REQUEST))
        return pending

    def wait(self, seconds):
        """Blocks until the service notifies (estimate or margin response) or `seconds` pass."""
        self.listener.timed_wait(iox2.Duration.from_secs_f64(seconds))


def take_response(pending):
    """A copy of the margin response of `pending`, or None when it has not arrived."""
    response = pending.receive()
    if response is None:
        return None
    r = cv.MarginResponse.from_buffer_copy(response.payload().contents)
    response.delete()
    return r


class Summary:
    """What the controller saw."""

    def __init__(self, attributes):
        self.attributes = attributes
        self.estimates = 0
        self.statuses = {}
        self.f1_min = math.inf
        self.f1_max = -math.inf
        self.last_estimate = None
        self.margins = 0
        self.margin_statuses = {}
        self.margin_min = math.inf
        self.last_margin = None
        self.lost_margins = 0
        # Pose timestamp -> estimate received, and margin request sent -> answer received, ns
        # (CLOCK_MONOTONIC, the clock of every *timestamp_ns field).
        self.latency_ns = []
        self.margin_rtt_ns = []
        # --hold-f1: set-points published, actions, and the ok estimates below the requirement
        # after the first answer that carried a T_min (hold_start_ns, CLOCK_MONOTONIC).
        self.hold_start_ns = None
        self.hold_setpoints = 0
        self.hold_setpoint_range = None
        self.hold_actions = {}
        self.hold_counted = 0
        self.hold_below = 0

    def estimate(self, e, now_ns):
        self.estimates += 1
        self.latency_ns.append(now_ns - e.pose_timestamp_ns)
        name = cv.status_str(e.status)
        self.statuses[name] = self.statuses.get(name, 0) + 1
        if e.status == cv.STATUS_OK:
            self.f1_min = min(self.f1_min, e.f1_hz)
            self.f1_max = max(self.f1_max, e.f1_hz)
        self.last_estimate = e

    def margin(self, r, rtt_ns):
        self.margins += 1
        self.margin_rtt_ns.append(rtt_ns)
        name = cv.status_str(r.status)
        self.margin_statuses[name] = self.margin_statuses.get(name, 0) + 1
        if r.status == cv.STATUS_OK:
            self.margin_min = min(self.margin_min, r.margin_hz)
        self.last_margin = r

    def hold_answer(self, hold, ports, r):
        """Takes a margin answer into the hold; publishes a changed set-point."""
        before = hold.setpoint_n
        action = hold.on_response(r)
        self.hold_actions[action] = self.hold_actions.get(action, 0) + 1
        if hold.setpoint_n != before:
            self.hold_setpoints += 1
            ports.send_t_min(self.hold_setpoints, hold.setpoint_n)
            lo, hi = self.hold_setpoint_range or (hold.params.floor_n, hold.params.floor_n)
            self.hold_setpoint_range = (min(lo, hold.setpoint_n), max(hi, hold.setpoint_n))
        if action != "no_answer" and self.hold_start_ns is None:
            self.hold_start_ns = time.monotonic_ns()

    def hold_estimate(self, hold, e):
        """Counts an ok estimate of a pose the service took after the hold's first answer."""
        if self.hold_start_ns is not None and e.status == cv.STATUS_OK \
                and e.receive_timestamp_ns > self.hold_start_ns:
            self.hold_counted += 1
            if e.f1_hz < hold.params.required_hz:
                self.hold_below += 1

    def as_json(self, required_hz):
        def num(x):
            return x if math.isfinite(x) else None

        m = self.last_margin
        return json.dumps({
            "attributes": self.attributes,
            "estimates": self.estimates,
            "statuses": self.statuses,
            "f1_min_hz": num(self.f1_min),
            "f1_max_hz": num(self.f1_max),
            "required_hz": required_hz,
            "margins": self.margins,
            "margin_statuses": self.margin_statuses,
            "margin_min_hz": num(self.margin_min),
            "lost_margins": self.lost_margins,
            "latency_us": percentiles_us(self.latency_ns),
            "margin_rtt_us": percentiles_us(self.margin_rtt_ns),
            "hold": None if self.hold_start_ns is None and not self.hold_actions else {
                "setpoints": self.hold_setpoints,
                "setpoint_range_n": self.hold_setpoint_range,
                "actions": self.hold_actions,
                "counted": self.hold_counted,
                "below": self.hold_below},
            "last_margin": None if m is None else {
                "status": cv.status_str(m.status), "pose_sequence": m.pose_sequence,
                "f1_hz": num(m.f1_hz), "margin_hz": num(m.margin_hz),
                "margin_ratio": num(m.margin_ratio)},
        }, sort_keys=True)


def percentiles_us(samples_ns):
    """{"p50", "p99", "max"} of `samples_ns` in µs (nearest rank), or None without samples."""
    if not samples_ns:
        return None
    v = sorted(samples_ns)

    def rank(q):
        return v[min(len(v) - 1, max(0, math.ceil(q * len(v)) - 1))] * 1e-3

    return {"p50": rank(0.50), "p99": rank(0.99), "max": v[-1] * 1e-3}


def run(ports, a):
    s = Summary(ports.attributes)
    hold = None if a.hold is None else hold_f1.F1Hold(a.hold)
    start = time.monotonic()
    next_print = 1.0
    pending, sent_ns, sequence, asked_at = None, 0, 0, 0
    while time.monotonic() - start < a.seconds:
        for e in ports.estimates():
            s.estimate(e, time.monotonic_ns())
            if hold is not None:
                s.hold_estimate(hold, e)
        if pending is not None:
            r = take_response(pending)
            if r is not None:
                s.margin(r, time.monotonic_ns() - sent_ns)
                pending = None
                if hold is not None:
                    s.hold_answer(hold, ports, r)
            elif time.monotonic_ns() - sent_ns > MARGIN_TIMEOUT_S * 1e9:
                s.lost_margins += 1
                pending = None
        if pending is None and s.estimates > asked_at:
            # One request per new estimate, as service/examples/controller.rs does.
            asked_at = s.estimates
            sequence += 1
            sent_ns = time.monotonic_ns()
            pending = ports.ask_margin(sequence, a.required_hz)
        t = time.monotonic() - start
        if t >= next_print and s.last_estimate is not None:
            next_print += 1.0
            m = s.last_margin
            print("controller.py: t = %.1f s  f1 = %.6f Hz (%s)  margin = %s" % (
                t, s.last_estimate.f1_hz, cv.status_str(s.last_estimate.status),
                "none yet" if m is None else "%.6f Hz (%s)" % (m.margin_hz, cv.status_str(m.status))))
            e = s.last_estimate
            if e.vibration_samples > 0:
                # measured_*_status: cv.MEASURED_OK (0) with a number, another code without.
                print("controller.py:   measured: near f1 %.3f Hz (status %d), end-effector mode "
                      "%.3f Hz (status %d, model %.3f Hz); vibration samples %d taken, %d refused, "
                      "%d lost" % (e.measured_f1_hz, e.measured_f1_status, e.measured_ee_mode_hz,
                                   e.measured_ee_mode_status, e.ee_mode_hz, e.vibration_samples,
                                   e.vibration_refused, e.vibration_lost))
            if hold is not None:
                print("controller.py: T_min set-point %.3f N" % hold.setpoint_n)
        ports.wait(WAIT_SLICE_S)
    return s


def main():
    a = parse_args()
    iox2.set_log_level_from_env_or(iox2.LogLevel.Error)
    # The name starts with "cablevib", so `cablevib serve` cleans up after this node if the
    # process dies.
    node = iox2.NodeBuilder.new().name(iox2.NodeName.new("cablevib-py-controller")).create(iox2.ServiceType.Ipc)
    ports = Ports(node, a.instance, a.connect_timeout_s, t_min_publisher=a.hold is not None)
    attrs = ", ".join("%s=%s" % kv for kv in sorted(ports.attributes.items()))
    print('controller.py: taking estimates from "%s" for %g s, margin against %g Hz' % (
        ports.estimate_name, a.seconds, a.required_hz))
    print("controller.py: service attributes: " + attrs)
    try:
        s = run(ports, a)
    except KeyboardInterrupt:
        return 130
    print("controller.py: %d estimates %s, f1 %.6f .. %.6f Hz; %d margin answers %s, worst margin %.6f Hz, %d lost" % (
        s.estimates, s.statuses, s.f1_min, s.f1_max, s.margins, s.margin_statuses, s.margin_min, s.lost_margins))
    for what, samples in (("pose -> estimate latency", s.latency_ns), ("margin round trip", s.margin_rtt_ns)):
        p = percentiles_us(samples)
        if p is not None:
            print("controller.py: %s: p50 %.1f us  p99 %.1f us  max %.1f us (%d samples)" % (
                what, p["p50"], p["p99"], p["max"], len(samples)))
    if a.hold is not None:
        lo, hi = s.hold_setpoint_range or (a.hold.floor_n, a.hold.floor_n)
        print("controller.py: hold f1 >= %g Hz: %d set-points (%.2f..%.2f N; actions %s); ok estimates "
              "below %g Hz after the first answer: %d of %d" % (
                  a.hold.required_hz, s.hold_setpoints, lo, hi,
                  ", ".join("%s %d" % kv for kv in sorted(s.hold_actions.items())),
                  a.hold.required_hz, s.hold_below, s.hold_counted))
    if a.json:
        print(s.as_json(a.required_hz))
    return 0


if __name__ == "__main__":
    sys.exit(main())
