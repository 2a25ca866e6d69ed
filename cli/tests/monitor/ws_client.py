"""A Foxglove WebSocket protocol client for the monitor test. It offers the protocol's v1
subprotocol under both its names, `foxglove.websocket.v1` and `foxglove.sdk.v1` (the same v1
messages: the Foxglove SDK's server accepts only the second name), and checks that v1 was chosen.

ws_client.py URL T_MIN_N T_MAX_N: connects, reads serverInfo and the channel advertisements,
subscribes to the estimate, pose and scene channels, decodes JSON estimates and poses and the
protobuf SceneUpdate (from the advertised FileDescriptorSet), and checks one SceneUpdate
against what it received independently: the end-effector's position and orientation equal the
pose the update names (pose_sequence), and each cable's colour is the documented map of the
estimate's tension for that pose between T_MIN_N and T_MAX_N (blue (0.1, 0.3, 1.0) at T_min,
red (1.0, 0.1, 0.1) at T_max, linear, clamped). Prints one OK line, exit 0; else exit 1.
"""
import asyncio
import base64
import json
import struct
import sys

import websockets


def scene_class(name, data):
    from google.protobuf import descriptor_pb2, descriptor_pool, message_factory
    fds = descriptor_pb2.FileDescriptorSet.FromString(data)
    pool = descriptor_pool.DescriptorPool()
    pending = list(fds.file)
    while pending:
        left = []
        for f in pending:
            try:
                pool.Add(f)
            except Exception:
                left.append(f)
        assert len(left) < len(pending)
        pending = left
    return message_factory.GetMessageClass(pool.FindMessageTypeByName(name))


def colour(t, lo, hi):
    u = min(max((t - lo) / (hi - lo), 0.0), 1.0)
    return (0.1 + 0.9 * u, 0.3 - 0.2 * u, 1.0 - 0.9 * u)


async def main(url, t_min, t_max):
    # proxy=None: a proxy from the environment must not stand between the test and 127.0.0.1.
    async with websockets.connect(url, subprotocols=["foxglove.websocket.v1", "foxglove.sdk.v1"],
                                  max_size=None, proxy=None) as ws:
        assert ws.subprotocol in ("foxglove.websocket.v1", "foxglove.sdk.v1"), ws.subprotocol
        channels = {}
        info = None
        while len(channels) < 5:
            m = json.loads(await asyncio.wait_for(ws.recv(), 10))
            if m["op"] == "serverInfo":
                info = m
            elif m["op"] == "advertise":
                for c in m["channels"]:
                    channels[c["topic"].rsplit("/", 1)[1]] = c
        assert info is not None and "scene" in info.get("metadata", {}), info
        subs = {}
        for i, name in enumerate(["estimate", "pose", "scene"], start=1):
            subs[i] = name
        await ws.send(json.dumps({"op": "subscribe", "subscriptions": [
            {"id": i, "channelId": channels[n]["id"]} for i, n in subs.items()]}))
        sc = channels["scene"]
        assert sc["encoding"] == "protobuf" and sc["schemaName"] == "foxglove.SceneUpdate", sc
        Scene = scene_class(sc["schemaName"], base64.b64decode(sc["schema"]))
        estimates, poses, counts = {}, {}, {"estimate": 0, "pose": 0, "scene": 0}
        scenes = []
        deadline = asyncio.get_event_loop().time() + 20
        while asyncio.get_event_loop().time() < deadline:
            m = await asyncio.wait_for(ws.recv(), 10)
            if isinstance(m, str):
                continue
            assert m[0] == 1, m[0]  # MessageData
            sub, _ts = struct.unpack_from("<IQ", m, 1)
            payload = m[13:]
            name = subs[sub]
            counts[name] += 1
            if name == "estimate":
                e = json.loads(payload)
                estimates[e["pose_sequence"]] = e
            elif name == "pose":
                p = json.loads(payload)
                poses[p["sequence"]] = p
            else:
                u = Scene()
                u.ParseFromString(payload)
                scenes.append(u)
            for u in scenes:
                ents = {e.id: e for e in u.entities}
                seq = int({kv.key: kv.value for kv in ents["end_effector"].metadata}["pose_sequence"])
                e, p = estimates.get(seq), poses.get(seq)
                if e is None or p is None or e["status"] != 0:
                    continue
                ee = (ents["end_effector"].cubes or ents["end_effector"].spheres)[0].pose
                assert [ee.position.x, ee.position.y, ee.position.z] == p["position_m"], (ee, p)
                q = p["orientation_wxyz"]
                assert [ee.orientation.w, ee.orientation.x, ee.orientation.y, ee.orientation.z] == q
                lines = ents["cables"].lines
                assert len(lines) == len(e["tensions_n"])
                for line, t in zip(lines, e["tensions_n"]):
                    want = colour(t, t_min, t_max)
                    got = (line.color.r, line.color.g, line.color.b)
                    # The same three operations in IEEE double on both sides: equal to 1e-15.
                    assert all(abs(a - b) <= 1e-15 for a, b in zip(got, want)), (got, want, t)
                print(f"OK subprotocol {ws.subprotocol}: scene update of pose {seq}: {len(lines)} cable colours and the "
                      f"end-effector pose match; received {counts}")
                return 0
        print(f"FAIL no matching scene update; received {counts}")
        return 1


if __name__ == "__main__":
    sys.exit(asyncio.run(main(sys.argv[1], float(sys.argv[2]), float(sys.argv[3]))))
