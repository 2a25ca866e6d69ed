"""Reads a `cablevib monitor` MCAP recording with the official Python `mcap` reader.

full EXPECTED.json FILE.mcap: the complete file (summary, schemas, metadata): every JSON
schema parses, the SceneUpdate schema (a protobuf FileDescriptorSet) builds a message class
that decodes the scene messages, the counts of estimates and poses equal those of EXPECTED
(what the test's controller received and sent), and every estimate value equals the
controller's bit for bit (floats compared as IEEE-754 bit patterns; a JSON null is a NaN).

killed FILE.mcap: a file whose writer was killed: read record by record up to where it ends;
prints the number of estimates read (each a decodable JSON object).

completeness FILE.mcap: prints one JSON object: the metadata records (`cablevib`,
`cablevib.completeness`), and, counted from the messages themselves, per channel the number
of messages and, from their sequence numbers, first, last and the number missing between them.
"""
import json
import struct
import sys

from mcap.reader import make_reader
from mcap.stream_reader import StreamReader
from mcap.records import Message, Channel, Schema


def bits(v):
    if v is None:
        return None
    return struct.pack(">d", v).hex()


def is_nan_hex(h):
    return struct.unpack(">d", bytes.fromhex(h))[0] != struct.unpack(">d", bytes.fromhex(h))[0]


def same(recorded, expected_hex):
    if recorded is None:
        return is_nan_hex(expected_hex)
    return bits(float(recorded)) == expected_hex


FLOATS = ["f1_hz", "ee_mode_hz", "eigen_residual", "measured_f1_hz", "f1_residual_hz",
          "measured_ee_mode_hz", "ee_mode_residual_hz"]
FLOAT_ARRAYS = ["tensions_n", "stiffness"]
INTS = ["sequence", "pose_sequence", "pose_timestamp_ns", "receive_timestamp_ns", "publish_timestamp_ns",
        "status", "cable_count", "ee_mode_age_cycles", "stiffness_dim", "compute_ns",
        "eigen_evaluations", "tension_iterations", "skipped_poses", "measured_f1_status",
        "measured_ee_mode_status", "vibration_samples", "vibration_refused", "vibration_lost",
        "measured_age_ns"]


def scene_class(schema):
    from google.protobuf import descriptor_pb2, descriptor_pool, message_factory
    fds = descriptor_pb2.FileDescriptorSet.FromString(schema.data)
    pool = descriptor_pool.DescriptorPool()
    pending = list(fds.file)
    while pending:  # dependencies first, whatever the set's order
        left = []
        for f in pending:
            try:
                pool.Add(f)
            except Exception:
                left.append(f)
        assert len(left) < len(pending), [f.name for f in left]
        pending = left
    return message_factory.GetMessageClass(pool.FindMessageTypeByName(schema.name))


def full(expected_path, path):
    expected = json.load(open(expected_path))
    with open(path, "rb") as f:
        reader = make_reader(f)
        summary = reader.get_summary()
        assert summary is not None, "no summary: the file was not closed"
        classes = {}
        for sid, s in summary.schemas.items():
            if s.encoding == "jsonschema":
                js = json.loads(s.data)
                assert js["type"] == "object" and js["properties"], s.name
            elif s.encoding == "protobuf":
                classes[sid] = scene_class(s)
            else:
                raise AssertionError(f"unexpected schema encoding {s.encoding}")
        meta = {m.name: dict(m.metadata) for m in reader.iter_metadata()}
        assert "cablevib" in meta and meta["cablevib"].get("scene"), meta
        # Stopped by SIGTERM: the file is complete and says it was interrupted.
        end = meta.get("cablevib.end", {})
        assert end.get("stopped_by") == "signal" and end.get("interrupted") == "true", meta
        estimates, poses, scenes, t_mins = [], [], 0, 0
        for schema, channel, message in reader.iter_messages():
            if schema.name == "cablevib.Estimate":
                estimates.append(json.loads(message.data))
            elif schema.name == "cablevib.Pose":
                poses.append(json.loads(message.data))
            elif schema.name == "cablevib.TminSetpoint":
                t_mins += 1
            elif schema.encoding == "protobuf":
                u = classes[schema.id]()
                u.ParseFromString(message.data)
                assert len(u.entities) == 4, u
                scenes += 1
    exp_e = expected["estimates"]
    assert len(estimates) == len(exp_e), f"{len(estimates)} estimates recorded, {len(exp_e)} received"
    assert len(poses) == expected["poses"], f"{len(poses)} poses recorded, {expected['poses']} sent"
    assert scenes > 0 and t_mins >= 1, (scenes, t_mins)
    by_seq = {e["pose_sequence"]: e for e in estimates}
    for x in exp_e:
        r = by_seq[x["pose_sequence"]]
        for k in INTS:
            assert r[k] == x[k], (k, r[k], x[k])
        for k in FLOATS:
            assert same(r[k], x[k]), (x["pose_sequence"], k, r[k], x[k])
        for k in FLOAT_ARRAYS:
            assert len(r[k]) == len(x[k]), k
            for a, b in zip(r[k], x[k]):
                assert same(a, b), (x["pose_sequence"], k, a, b)
    # The test's accelerometer (a 29.4 Hz sine) is measured once its 2 s window is full: the
    # recorded end-effector mode is the sine's, the status named. Every ok estimate reads
    # the sine within 0.01 Hz (the noise limit of the 2 s window at amplitude/sigma = 50 is
    # 0.1 mHz; a grid step is 0.25 Hz, the Hann first sidelobe 1.18 Hz away). Where the
    # model's end-effector mode jumps to its other mode (~33 Hz) for a few cycles, the band
    # of an evaluation started then misses the sine: a status (outside_band, no_peak), never
    # a number.
    measured = [e for e in estimates if e["measured_ee_mode_status_name"] == "ok"]
    assert len(measured) > len(estimates) // 2, (len(measured), len(estimates))
    off = [e for e in measured if abs(e["measured_ee_mode_hz"] - 29.4) >= 0.01]
    assert not off, (len(off), len(measured), [(e["sequence"], e["measured_ee_mode_hz"], e["ee_mode_hz"]) for e in off[:5]])
    names = {}
    for e in estimates:
        n = e["measured_ee_mode_status_name"]
        names[n] = names.get(n, 0) + 1
    print(f"measured end-effector mode: {len(measured)} ok, all within 0.01 Hz of the sine; statuses {names}")
    print(f"OK {len(estimates)} estimates ({len(measured)} with a measured end-effector mode), "
          f"{len(poses)} poses, {t_mins} T_min, {scenes} scene updates; every estimate value bit for bit")


def killed(path):
    n_est = 0
    ended = "end of file"
    with open(path, "rb") as f:
        try:
            for record in StreamReader(f).records:
                if isinstance(record, Message):
                    pass
                if isinstance(record, Schema) or isinstance(record, Channel):
                    continue
                if isinstance(record, Message):
                    d = json.loads(record.data) if record.data[:1] == b"{" else None
                    if d is not None and "f1_hz" in d:
                        n_est += 1
        except Exception as e:  # the cut in the last, incomplete chunk
            ended = f"{type(e).__name__}"
    print(f"READ {n_est} estimates ({ended})")


def completeness(path):
    with open(path, "rb") as f:
        reader = make_reader(f)
        meta = {m.name: dict(m.metadata) for m in reader.iter_metadata()}
        sequences = {"estimate": [], "pose": [], "t_min": []}
        scene = 0
        for schema, channel, message in reader.iter_messages():
            name = channel.topic.rsplit("/", 1)[-1]
            if name in sequences:
                sequences[name].append(json.loads(message.data)["sequence"])
            elif name == "scene":
                scene += 1
    counted = {"scene": {"messages": scene}}
    for name, seqs in sequences.items():
        c = {"messages": len(seqs), "distinct": len(set(seqs))}
        if seqs:
            c.update(first=min(seqs), last=max(seqs), missing=max(seqs) - min(seqs) + 1 - len(set(seqs)))
        counted[name] = c
    print(json.dumps({"metadata": meta, "counted": counted}))


if __name__ == "__main__":
    if sys.argv[1] == "full":
        full(sys.argv[2], sys.argv[3])
    elif sys.argv[1] == "completeness":
        completeness(sys.argv[2])
    else:
        killed(sys.argv[2])
