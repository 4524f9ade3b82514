"""A ROS 2 robot stand-in without ROS: differential-drive robots that obey `cmd_vel` and
publish `joint_states` and `ground_truth`, over rmw_zenoh's wire contract, for
`hnav run` of a scenario with `[sim] kind = "ros2"`. Shares no code with HNAV: PyPI
`eclipse-zenoh` for the network and `rosbags` for the ROS 2 Jazzy messages and CDR.

    python ros2_robots.py --listen tcp/127.0.0.1:7447 --scenario demo-ros2.toml \
        --wheel-radius 0.021 --axle 0.10 --radius 0.058 --cell 0.16

It is the Zenoh router of the graph (`--listen`; `hnav run --ros2-router` joins it) and one
node, `/robots`, with per robot `i` (as a `diff_drive_controller` and its joint state
broadcaster would, with a simulator's ground truth):

- a subscription to `/robot_<i>/cmd_vel` (`geometry_msgs/msg/Twist`): the body velocity,
  held until the next one, zero after `--cmd-timeout` without one (the controller's
  `cmd_vel_timeout`);
- `/robot_<i>/joint_states` (`sensor_msgs/msg/JointState`): the cumulative angles of
  `left_wheel_joint` and `right_wheel_joint`, rad;
- `/robot_<i>/ground_truth` (`nav_msgs/msg/Odometry`, frame `map`).

The robots start at their scenario cells' centres facing `start_heading_deg`, in the map
frame HNAV uses (x along the map's columns, y along its rows). Each step moves a robot along
the exact arc of its wheels' speeds. Its own collision check, every step: two robots' discs
(`--radius`) overlapping, or a disc overlapping a blocked cell or leaving the map.

With `--odom` each robot publishes `/robot_<i>/odom` (`nav_msgs/msg/Odometry` in its own
frame `robot_<i>/odom`, whose origin is where the robot started) instead of `joint_states`,
for a scenario with `[ros2] odometry = "odom"`.

Bad input for HNAV, on request: `--silent I` never publishes robot I's `joint_states`;
`--malformed I` publishes, once a second, a sample on robot I's `joint_states` that is not
CDR of a JointState.

When HNAV's node `/hnav` has come and gone for `--end-grace` seconds (the run's end; a
restarted `hnav-ros2 --robots` is away for less), it prints each robot's final
pose and distance to its goal, the collisions, and `OK` (exit 0) if every robot that was not
silent is within half a cell of its goal and nothing collided; otherwise `PROBLEM` lines,
exit 1.
"""

import argparse
import math
import struct
import sys
import threading
import time
import tomllib
from pathlib import Path

import numpy as np
import zenoh
from rosbags.typesys import Stores, get_typestore

TS = get_typestore(Stores.ROS2_JAZZY)
JointState = TS.types["sensor_msgs/msg/JointState"]
Odometry = TS.types["nav_msgs/msg/Odometry"]
Header = TS.types["std_msgs/msg/Header"]
Time = TS.types["builtin_interfaces/msg/Time"]
PoseWithCovariance = TS.types["geometry_msgs/msg/PoseWithCovariance"]
TwistWithCovariance = TS.types["geometry_msgs/msg/TwistWithCovariance"]
Pose = TS.types["geometry_msgs/msg/Pose"]
Point = TS.types["geometry_msgs/msg/Point"]
Quaternion = TS.types["geometry_msgs/msg/Quaternion"]
Twist = TS.types["geometry_msgs/msg/Twist"]
Vector3 = TS.types["geometry_msgs/msg/Vector3"]

WHEELS = ["left_wheel_joint", "right_wheel_joint"]


def dds(rtype):
    pkg, kind, name = rtype.split("/")
    return f"{pkg}::msg::dds_::{name}_"


def key(domain, topic, rtype):
    return f"{domain}/{topic.strip('/')}/{dds(rtype)}/{TS.hash_rihs01(rtype)}"


def mangle(s):
    return s.replace("/", "%")


class Node:
    """A ROS 2 node as rmw_zenoh declares one: tokens, publishers with attachments."""

    def __init__(self, session, domain, name):
        self.session, self.domain, self.name = session, domain, name
        self.zid = str(session.info.zid())
        self.eid = 1
        self.tokens = [session.liveliness().declare_token(
            f"@ros2_lv/{domain}/{self.zid}/0/0/NN/%/%/{name}")]

    def _token(self, kind, topic, rtype):
        eid, self.eid = self.eid, self.eid + 1
        t = (f"@ros2_lv/{self.domain}/{self.zid}/0/{eid}/{kind}/%/%/{self.name}/"
             f"{mangle(topic)}/{dds(rtype)}/{TS.hash_rihs01(rtype)}/::,10:,:,:,,")
        self.tokens.append(self.session.liveliness().declare_token(t))
        return t

    def publisher(self, topic, rtype):
        token = self._token("MP", topic, rtype)
        return Publisher(self.session.declare_publisher(key(self.domain, topic, rtype)), token)

    def subscription(self, topic, rtype, callback):
        self._token("MS", topic, rtype)
        return self.session.declare_subscriber(key(self.domain, topic, rtype), callback)


class Publisher:
    def __init__(self, pub, token):
        self.pub, self.seq = pub, 0
        # Any 16 bytes unique to the publisher do for a GID here.
        self.gid = token.encode()[-16:].ljust(16, b"\0")

    def put(self, payload):
        self.seq += 1
        att = struct.pack("<qqB", self.seq, time.time_ns(), 16) + self.gid
        self.pub.put(bytes(payload), attachment=att)


def stamp(t_ns):
    return Time(sec=t_ns // 1_000_000_000, nanosec=t_ns % 1_000_000_000)


class Robot:
    def __init__(self, i, x, y, yaw):
        self.i, self.x, self.y, self.yaw = i, x, y, yaw
        self.v = self.w = 0.0
        self.cmd_at = None
        self.wheels = [0.0, 0.0]
        self.cmds = 0

    def on_cmd(self, sample):
        try:
            t = TS.deserialize_cdr(sample.payload.to_bytes(), "geometry_msgs/msg/Twist")
        except Exception as e:  # noqa: BLE001: HNAV's message is under test too
            print(f"PROBLEM robot {self.i}: a cmd_vel that does not decode: {e}", flush=True)
            return
        self.v, self.w, self.cmd_at = t.linear.x, t.angular.z, time.monotonic()
        self.cmds += 1

    def step(self, dt, r, axle, timeout):
        if self.cmd_at is None or time.monotonic() - self.cmd_at > timeout:
            self.v = self.w = 0.0
        wl = (self.v - self.w * axle / 2) / r
        wr = (self.v + self.w * axle / 2) / r
        self.wheels[0] += wl * dt
        self.wheels[1] += wr * dt
        ds, dth = self.v * dt, self.w * dt
        half = dth / 2
        chord = ds if abs(half) < 1e-12 else ds * math.sin(half) / half
        self.x += chord * math.cos(self.yaw + half)
        self.y += chord * math.sin(self.yaw + half)
        self.yaw = math.atan2(math.sin(self.yaw + dth), math.cos(self.yaw + dth))
        return wl, wr


def disc_hits_cell(x, y, rad, cx, cy, cell):
    nx = min(max(x, cx * cell), (cx + 1) * cell)
    ny = min(max(y, cy * cell), (cy + 1) * cell)
    return (x - nx) ** 2 + (y - ny) ** 2 < rad * rad


class Contacts:
    """The stand-in's own collision check: contacts counted when they begin."""

    def __init__(self, rows, cell, radius):
        self.rows, self.cell, self.radius = rows, cell, radius
        self.now, self.events = set(), []

    def check(self, robots, t):
        found = set()
        for a in range(len(robots)):
            ra = robots[a]
            for b in range(a + 1, len(robots)):
                rb = robots[b]
                if math.hypot(ra.x - rb.x, ra.y - rb.y) < 2 * self.radius - 1e-9:
                    found.add(("robot", a, b))
            cx, cy = int(ra.x // self.cell), int(ra.y // self.cell)
            for yy in range(cy - 1, cy + 2):
                for xx in range(cx - 1, cx + 2):
                    outside = not (0 <= yy < len(self.rows) and 0 <= xx < len(self.rows[0]))
                    if (outside or self.rows[yy][xx] != ".") and disc_hits_cell(
                            ra.x, ra.y, self.radius, xx, yy, self.cell):
                        found.add(("cell", a, (xx, yy)))
        for c in found - self.now:
            self.events.append((t, c))
        self.now = found


def joint_state(t_ns, wheels, speeds):
    return JointState(
        header=Header(stamp=stamp(t_ns), frame_id=""),
        name=list(WHEELS),
        position=np.array(wheels, dtype=np.float64),
        velocity=np.array(speeds, dtype=np.float64),
        effort=np.array([], dtype=np.float64),
    )


def odometry(t_ns, i, r, frame="map", origin=(0.0, 0.0, 0.0)):
    """Robot `r`'s pose and twist, in `frame` whose origin is `origin` (x, y, yaw) in map."""
    ox, oy, oyaw = origin
    dx, dy = r.x - ox, r.y - oy
    c, s = math.cos(-oyaw), math.sin(-oyaw)
    x, y, yaw = c * dx - s * dy, s * dx + c * dy, r.yaw - oyaw
    return Odometry(
        header=Header(stamp=stamp(t_ns), frame_id=frame),
        child_frame_id=f"robot_{i}/base_link",
        pose=PoseWithCovariance(
            pose=Pose(
                position=Point(x=x, y=y, z=0.0),
                orientation=Quaternion(x=0.0, y=0.0, z=math.sin(yaw / 2), w=math.cos(yaw / 2)),
            ),
            covariance=np.zeros(36, dtype=np.float64),
        ),
        twist=TwistWithCovariance(
            twist=Twist(linear=Vector3(x=r.v, y=0.0, z=0.0), angular=Vector3(x=0.0, y=0.0, z=r.w)),
            covariance=np.zeros(36, dtype=np.float64),
        ),
    )


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--listen", required=True)
    ap.add_argument("--scenario", required=True, type=Path)
    ap.add_argument("--wheel-radius", type=float, required=True)
    ap.add_argument("--axle", type=float, required=True)
    ap.add_argument("--radius", type=float, required=True, help="body radius, m")
    ap.add_argument("--cell", type=float, required=True, help="cell size, m")
    ap.add_argument("--rate", type=float, default=50.0, help="steps and messages per second")
    ap.add_argument("--cmd-timeout", type=float, default=0.5)
    ap.add_argument("--domain", type=int, default=0)
    ap.add_argument("--odom", action="store_true", help="publish odom, not joint_states")
    ap.add_argument("--silent", type=int, action="append", default=[])
    ap.add_argument("--malformed", type=int, action="append", default=[])
    ap.add_argument("--timeout", type=float, default=150.0)
    ap.add_argument("--end-grace", type=float, default=2.0,
                    help="s without HNAV's node before the run counts as ended (a restarted "
                         "hnav-ros2 --robots is away meanwhile)")
    a = ap.parse_args()

    scen = tomllib.loads(a.scenario.read_text())
    rows = scen["map"]["rows"]
    agents = scen["agents"]
    robots = []
    for i, ag in enumerate(agents):
        (sx, sy) = ag["start"]
        yaw = math.radians(ag.get("start_heading_deg", 0.0))
        robots.append(Robot(i, (sx + 0.5) * a.cell, (sy + 0.5) * a.cell, yaw))
    goals = [((g[0] + 0.5) * a.cell, (g[1] + 0.5) * a.cell) for g in (ag["goal"] for ag in agents)]

    conf = zenoh.Config()
    conf.insert_json5("mode", '"router"')
    conf.insert_json5("listen/endpoints", f'["{a.listen}"]')
    conf.insert_json5("scouting/multicast/enabled", "false")
    session = zenoh.open(conf)
    node = Node(session, a.domain, "robots")
    hnav = {"seen": False, "alive": 0}
    lock = threading.Lock()

    def on_token(sample):
        k = str(sample.key_expr)
        if k.split("/")[5:6] == ["NN"] and k.endswith("/hnav"):
            with lock:
                if sample.kind == zenoh.SampleKind.PUT:
                    hnav["seen"] = True
                    hnav["alive"] += 1
                else:
                    hnav["alive"] -= 1

    live = session.liveliness().declare_subscriber(f"@ros2_lv/{a.domain}/**", on_token, history=True)
    subs, joints, truths, odoms = [], [], [], []
    origins = [(r.x, r.y, r.yaw) for r in robots]
    for r in robots:
        subs.append(node.subscription(f"/robot_{r.i}/cmd_vel", "geometry_msgs/msg/Twist", r.on_cmd))
        if a.odom:
            odoms.append(node.publisher(f"/robot_{r.i}/odom", "nav_msgs/msg/Odometry"))
        else:
            joints.append(node.publisher(f"/robot_{r.i}/joint_states", "sensor_msgs/msg/JointState"))
        truths.append(node.publisher(f"/robot_{r.i}/ground_truth", "nav_msgs/msg/Odometry"))
    contacts = Contacts(rows, a.cell, a.radius)
    print(f"router up {a.listen}", flush=True)

    dt = 1.0 / a.rate
    t0 = time.monotonic()
    deadline = t0 + a.timeout
    next_t, next_bad, malformed_sent = t0, t0 + 1.0, 0
    gone_since = None
    while time.monotonic() < deadline:
        with lock:
            gone = hnav["seen"] and hnav["alive"] <= 0
        if not gone:
            gone_since = None
        elif gone_since is None:
            gone_since = time.monotonic()
        elif time.monotonic() - gone_since >= a.end_grace:
            break
        now_ns = time.time_ns()
        for r in robots:
            speeds = r.step(dt, a.wheel_radius, a.axle, a.cmd_timeout)
            if r.i in a.silent:
                pass
            elif a.odom:
                odoms[r.i].put(TS.serialize_cdr(
                    odometry(now_ns, r.i, r, f"robot_{r.i}/odom", origins[r.i]),
                    "nav_msgs/msg/Odometry"))
            else:
                joints[r.i].put(TS.serialize_cdr(joint_state(now_ns, r.wheels, speeds),
                                                 "sensor_msgs/msg/JointState"))
            truths[r.i].put(TS.serialize_cdr(odometry(now_ns, r.i, r), "nav_msgs/msg/Odometry"))
        contacts.check(robots, time.monotonic() - t0)
        if a.malformed and time.monotonic() >= next_bad:
            for i in a.malformed:
                # A CDR header, then a name count far beyond the payload, then junk.
                joints[i].put(b"\x00\x01\x00\x00" + b"\x00" * 8 + struct.pack("<I", 0xFFFFFFF0)
                              + b"junk")
                malformed_sent += 1
            next_bad += 1.0
        next_t += dt
        time.sleep(max(0.0, next_t - time.monotonic()))

    problems = []
    with lock:
        if not hnav["seen"]:
            problems.append("never saw HNAV's node /hnav")
        elif hnav["alive"] > 0:
            problems.append(f"the run did not end within {a.timeout} s")
    for r in robots:
        gx, gy = goals[r.i]
        d = math.hypot(r.x - gx, r.y - gy)
        line = (f"robot {r.i} final ({r.x:.3f}, {r.y:.3f}) {d:.3f} m from goal "
                f"{agents[r.i]['goal']}, {r.cmds} cmd_vel")
        print(line, flush=True)
        if r.i not in a.silent and d > a.cell / 2:
            problems.append(f"{line}: more than half a cell")
        if r.cmds == 0 and r.i not in a.silent:
            problems.append(f"robot {r.i}: no cmd_vel received")
    print(f"collisions {len(contacts.events)}", flush=True)
    for t, c in contacts.events[:10]:
        problems.append(f"collision at {t:.2f} s: {c}")
    if a.malformed:
        print(f"malformed sent {malformed_sent}", flush=True)
    live.undeclare()
    session.close()
    if problems:
        for p in problems:
            print(f"PROBLEM {p}", flush=True)
        return 1
    print("OK", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
