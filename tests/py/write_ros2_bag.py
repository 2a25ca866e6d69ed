"""Write a ROS 2 bag in MCAP (the ROS 2 MCAP writer, its own CDR encoder) from a CSV record
`t,c1,c2,c3` (t from 0 s): sensor_msgs/msg/Imu on /imu with the three channels as
linear_acceleration, header stamps from UNIX_SEC on; geometry_msgs/msg/PoseStamped on /pose
every POSE_EVERY samples at POSITION. With WRENCH.csv `t,fx,fy,fz` (its own times), also
geometry_msgs/msg/WrenchStamped on /wrench, the messages of both topics written in time order
(as `ros2 bag record` logs them). Usage: write_ros2_bag.py IN.csv OUT.mcap X Y Z [WRENCH.csv]."""

import csv
import sys

from mcap_ros2.writer import Writer

IMU = """std_msgs/Header header
geometry_msgs/Quaternion orientation
float64[9] orientation_covariance
geometry_msgs/Vector3 angular_velocity
float64[9] angular_velocity_covariance
geometry_msgs/Vector3 linear_acceleration
float64[9] linear_acceleration_covariance
================================================================================
MSG: std_msgs/Header
builtin_interfaces/Time stamp
string frame_id
================================================================================
MSG: builtin_interfaces/Time
int32 sec
uint32 nanosec
================================================================================
MSG: geometry_msgs/Quaternion
float64 x 0
float64 y 0
float64 z 0
float64 w 1
================================================================================
MSG: geometry_msgs/Vector3
float64 x
float64 y
float64 z
"""

POSE = """std_msgs/Header header
geometry_msgs/Pose pose
================================================================================
MSG: std_msgs/Header
builtin_interfaces/Time stamp
string frame_id
================================================================================
MSG: builtin_interfaces/Time
int32 sec
uint32 nanosec
================================================================================
MSG: geometry_msgs/Pose
Point position
Quaternion orientation
================================================================================
MSG: geometry_msgs/Point
float64 x
float64 y
float64 z
================================================================================
MSG: geometry_msgs/Quaternion
float64 x 0
float64 y 0
float64 z 0
float64 w 1
"""

WRENCH = """std_msgs/Header header
geometry_msgs/Wrench wrench
================================================================================
MSG: std_msgs/Header
builtin_interfaces/Time stamp
string frame_id
================================================================================
MSG: builtin_interfaces/Time
int32 sec
uint32 nanosec
================================================================================
MSG: geometry_msgs/Wrench
Vector3 force
Vector3 torque
================================================================================
MSG: geometry_msgs/Vector3
float64 x
float64 y
float64 z
"""

UNIX_SEC = 1_700_000_000
POSE_EVERY = 10


def stamp_of(t_s):
    """The header stamp and the log time (ns) of a time in s from the record's start."""
    ns = round(float(t_s) * 1e9)
    stamp = {"sec": UNIX_SEC + ns // 1_000_000_000, "nanosec": ns % 1_000_000_000}
    return stamp, UNIX_SEC * 1_000_000_000 + ns


def wrench_rows(path):
    """The wrench CSV's rows as (log time, row), in file order."""
    with open(path) as f:
        rows = csv.reader(f)
        next(rows)
        for r in rows:
            yield stamp_of(r[0])[1], r


src, dst, x, y, z = sys.argv[1], sys.argv[2], *map(float, sys.argv[3:6])
with open(src) as f, open(dst, "wb") as out:
    w = Writer(out)
    imu = w.register_msgdef("sensor_msgs/msg/Imu", IMU)
    pose = w.register_msgdef("geometry_msgs/msg/PoseStamped", POSE)
    wrenches = iter(())
    if len(sys.argv) > 6:
        wrench = w.register_msgdef("geometry_msgs/msg/WrenchStamped", WRENCH)
        wrenches = wrench_rows(sys.argv[6])
    pending = next(wrenches, None)
    written = 0

    def write_wrenches(until_ns):
        """Write the wrench messages logged before `until_ns` (None: all)."""
        global pending, written
        while pending is not None and (until_ns is None or pending[0] < until_ns):
            tw, r = pending
            stamp = stamp_of(r[0])[0]
            v = {"x": float(r[1]), "y": float(r[2]), "z": float(r[3])}
            msg = {
                "header": {"stamp": stamp, "frame_id": "ft_sensor"},
                "wrench": {"force": v, "torque": {"x": 0.0, "y": 0.0, "z": 0.0}},
            }
            w.write_message("/wrench", wrench, msg, log_time=tw, publish_time=tw, sequence=written)
            written += 1
            pending = next(wrenches, None)

    rows = csv.reader(f)
    next(rows)
    for k, r in enumerate(rows):
        stamp, t = stamp_of(r[0])
        write_wrenches(t)
        header = {"stamp": stamp, "frame_id": "imu_link"}
        msg = {
            "header": header,
            "orientation": {"x": 0.0, "y": 0.0, "z": 0.0, "w": 1.0},
            "orientation_covariance": [0.0] * 9,
            "angular_velocity": {"x": 0.0, "y": 0.0, "z": 0.0},
            "angular_velocity_covariance": [0.0] * 9,
            "linear_acceleration": {"x": float(r[1]), "y": float(r[2]), "z": float(r[3])},
            "linear_acceleration_covariance": [0.0] * 9,
        }
        w.write_message("/imu", imu, msg, log_time=t, publish_time=t, sequence=k)
        if k % POSE_EVERY == 0:
            p = {
                "header": {"stamp": stamp, "frame_id": "world"},
                "pose": {
                    "position": {"x": x, "y": y, "z": z},
                    "orientation": {"x": 0.0, "y": 0.0, "z": 0.0, "w": 1.0},
                },
            }
            w.write_message("/pose", pose, p, log_time=t, publish_time=t, sequence=k)
    write_wrenches(None)
    w.finish()
