#!/usr/bin/env python3
"""Python accelerometer publisher of a running `cablevib serve`, over iceoryx2.

The Python twin of service/examples/accelerometer.rs: publishes VibrationSamples at a fixed
rate, the way a driver of a sensor on the platform would. The signal is synthetic: sines at
--sine-hz (amplitude --amplitude-m-s2 each, on the x axis), gravity on z and white noise of
--noise-m-s2 on every axis; replace `reading` with the sensor's.

    python3 -m venv venv && venv/bin/pip install iceoryx2==0.10.0 flatbuffers==25.12.19
    cablevib serve --instance demo &
    cargo run --release --example replay -- --instance demo --seconds 10 &
    venv/bin/python examples/python/accelerometer.py --instance demo --seconds 10 --sine-hz 29.4

Each sample carries its sequence number (1, 2, ...: a gap is a lost sample) and the
CLOCK_MONOTONIC time it was taken (here the time it was due), so the service learns the sample
period from the timestamps; it measures the dominant frequencies near the model's f1 and
end-effector mode and publishes them in every estimate (controller.py prints them). The
service must be running: this script opens its vibration service and never creates it.
"""

import argparse
import math
import os
import random
import sys
import time

sys.path.insert(
    0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "ipc-schema", "python")
)

import cablevib_ipc as cv  # noqa: E402
import iceoryx2 as iox2  # noqa: E402
from controller import check_schema, fail, schema_verifier, service_attributes  # noqa: E402


def parse_args():
    p = argparse.ArgumentParser(description="Publish accelerometer samples to a cablevib service.")
    p.add_argument("--instance", default="", help="instance name, as given to `cablevib serve --instance`")
    p.add_argument("--rate-hz", type=float, default=1000.0,
                   help="sample rate, Hz, in [10, 4000] (default 1000)")
    p.add_argument("--seconds", type=float, default=10.0, help="how long to publish, s (default 10)")
    p.add_argument("--sine-hz", default="29.4",
                   help="frequencies of the sines on x, Hz, comma-separated (default 29.4)")
    p.add_argument("--amplitude-m-s2", type=float, default=1.0,
                   help="amplitude of each sine, m/s^2 (default 1)")
    p.add_argument("--noise-m-s2", type=float, default=0.02,
                   help="standard deviation of the noise on each axis, m/s^2 (default 0.02)")
    p.add_argument("--connect-timeout-s", type=float, default=10.0,
                   help="how long to wait for the service to come up, s (default 10)")
    a = p.parse_args()

    def within(name, v, lo, hi):
        if not (math.isfinite(v) and lo <= v <= hi):
            fail("--%s %r must be in [%g, %g]" % (name, v, lo, hi))

    within("rate-hz", a.rate_hz, 10.0, 4000.0)
    within("seconds", a.seconds, 0.0, 86400.0)
    within("amplitude-m-s2", a.amplitude_m_s2, 0.0, 1000.0)
    within("noise-m-s2", a.noise_m_s2, 0.0, 1000.0)
    try:
        a.sine_hz = [float(f) for f in a.sine_hz.split(",")]
    except ValueError:
        fail("--sine-hz %r: numbers separated by commas" % a.sine_hz)
    for f in a.sine_hz:
        within("sine-hz", f, 0.0, 0.5 * a.rate_hz)
    return a


def reading(a, t_s, rng):
    """The sines on x, gravity on z, noise on every axis at time t_s, m/s^2."""
    sines = sum(a.amplitude_m_s2 * math.sin(2.0 * math.pi * f * t_s) for f in a.sine_hz)
    return (sines + a.noise_m_s2 * rng.gauss(0.0, 1.0),
            a.noise_m_s2 * rng.gauss(0.0, 1.0),
            9.81 + a.noise_m_s2 * rng.gauss(0.0, 1.0))


def main():
    a = parse_args()
    iox2.set_log_level_from_env_or(iox2.LogLevel.Error)
    name = cv.prefixed(a.instance, cv.SERVICE_VIBRATION)
    attributes = service_attributes(name, iox2.MessagingPattern.PublishSubscribe, a.connect_timeout_s)
    if attributes is None:
        fail('no cablevib service "%s" within %g s: is `cablevib serve --instance %s` running?' % (
            name, a.connect_timeout_s, a.instance))
    check_schema(name, attributes)
    # The name starts with "cablevib", so `cablevib serve` cleans up after this node if the
    # script is killed.
    node = iox2.NodeBuilder.new().name(iox2.NodeName.new("cablevib-py-accelerometer")).create(
        iox2.ServiceType.Ipc)
    try:
        service = node.service_builder(iox2.ServiceName.new(name)) \
            .publish_subscribe(cv.VibrationSample).open_with_attributes(schema_verifier())
    except iox2.PublishSubscribeOpenError as e:
        fail('cannot open "%s": %s (another schema or layout than ipc-schema/python/cablevib_ipc.py?)'
             % (name, e))
    publisher = service.publisher_builder().create()
    period_ns = round(1e9 / a.rate_hz)
    count = round(a.seconds * a.rate_hz)
    rng = random.Random(1)
    start_ns = time.monotonic_ns()
    for k in range(count):
        due_ns = start_ns + k * period_ns
        while True:
            now = time.monotonic_ns()
            if now >= due_ns:
                break
            time.sleep(min(due_ns - now, 200_000) * 1e-9)
        s = cv.VibrationSample(sequence=k + 1, timestamp_ns=due_ns)
        s.acceleration_m_s2[:] = reading(a, k * period_ns * 1e-9, rng)
        publisher.send_copy(s)
    print("accelerometer.py: sent %d samples at %g Hz on %s" % (count, a.rate_hz, name))


if __name__ == "__main__":
    try:
        main()
    except KeyboardInterrupt:
        sys.exit(130)
