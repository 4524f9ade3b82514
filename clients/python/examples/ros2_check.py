"""A ROS 2 client without ROS: joins `hnav run --ros2` over rmw_zenoh's wire contract and
checks what it sees. Shares no code with HNAV: PyPI `eclipse-zenoh` for the network and
`rosbags` for the ROS 2 Jazzy message definitions, type hashes and CDR.

    python ros2_check.py --listen tcp/127.0.0.1:7447 --scenario scenarios/demo.toml

It is the Zenoh router of the graph (`--listen`; `hnav run --ros2 --ros2-router` joins it),
and a peer of a ROS 2 node would see what it sees:

- the liveliness tokens rmw_zenoh announces (`@ros2_lv/<domain>/<zid>/<nid>/<eid>/<kind>/
  <enclave>/<namespace>/<node>[/<topic>/<type>/<hash>/<qos>]`): node `/hnav` and a publisher
  (`MP`) for every topic below, each with the type hash of its key expression;
- every sample's key expression `<domain>/<topic>/<dds type>/<RIHS01 hash>`, the hash the
  one rosbags computes for the type, the payload decoded with rosbags, the attachment
  (sequence number, source time, a 16-byte GID per publisher);
- each robot's `odom`, `ground_truth`, `plan` (frames `robot_<i>/odom`, `map`), `/map`
  (transient local: asked for again by a late subscriber, which gets the cached map) and
  `/tf` (`map` -> `robot_<i>/odom` -> `robot_<i>/base_link` for every robot);
- the robots' last ground-truth poses, once the run has ended (the node's token is gone):
  each within half a cell of its goal (the scenario's `[[agents]] goal`).

Prints one line per finding and `OK`, exit 0; otherwise what is missing or wrong, exit 1.
"""

import argparse
import math
import struct
import sys
import threading
import time
import tomllib
from pathlib import Path

import zenoh
import zenoh.ext
from rosbags.typesys import Stores, get_typestore

TYPESTORE = get_typestore(Stores.ROS2_JAZZY)


def demangle(s):
    return s.replace("%", "/")


def ros_type(dds):
    """`nav_msgs::msg::dds_::Odometry_` -> `nav_msgs/msg/Odometry`."""
    pkg, kind, _dds, name = dds.split("::")
    return f"{pkg}/{kind}/{name.rstrip('_')}"


def parse_token(key):
    """The fields of an rmw_zenoh liveliness token, names demangled; None if it is not one."""
    parts = key.split("/")
    if len(parts) < 9 or parts[0] != "@ros2_lv":
        return None
    t = {
        "domain": int(parts[1]),
        "zid": parts[2],
        "nid": parts[3],
        "eid": parts[4],
        "kind": parts[5],
        "enclave": demangle(parts[6]),
        "namespace": demangle(parts[7]),
        "node": demangle(parts[8]),
    }
    if t["kind"] != "NN":
        if len(parts) != 13:
            return None
        t.update(topic=demangle(parts[9]), dds=parts[10], hash=parts[11], qos=parts[12])
    return t


class Graph:
    """What the client saw, filled by Zenoh's callback threads."""

    def __init__(self):
        self.lock = threading.Lock()
        self.tokens = {}  # key -> parsed token, while alive
        self.node_seen = False
        self.latest = {}  # topic -> decoded message
        self.gids = {}  # topic -> GID bytes
        self.seqs = {}  # topic -> last sequence number
        self.errors = []

    def on_token(self, sample):
        key = str(sample.key_expr)
        with self.lock:
            if sample.kind == zenoh.SampleKind.PUT:
                t = parse_token(key)
                if t is None:
                    self.errors.append(f"not an rmw_zenoh token: {key}")
                    return
                self.tokens[key] = t
                if t["kind"] == "NN" and t["node"] == "hnav":
                    self.node_seen = True
            else:
                self.tokens.pop(key, None)

    def node_alive(self):
        with self.lock:
            return any(t["kind"] == "NN" and t["node"] == "hnav" for t in self.tokens.values())

    def on_data(self, sample, domain):
        key = str(sample.key_expr)
        parts = key.split("/")
        try:
            if parts[0] != str(domain) or len(parts) < 4:
                raise ValueError("not <domain>/<topic>/<type>/<hash>")
            dds, rihs = parts[-2], parts[-1]
            topic = "/" + "/".join(parts[1:-2])
            rtype = ros_type(dds)
            want = TYPESTORE.hash_rihs01(rtype)
            if rihs != want:
                raise ValueError(f"type hash {rihs}, rosbags computes {want} for {rtype}")
            payload = sample.payload.to_bytes()
            if payload[:4] != b"\x00\x01\x00\x00":
                raise ValueError(f"encapsulation {payload[:4].hex()}, not CDR little-endian")
            msg = TYPESTORE.deserialize_cdr(payload, rtype)
            att = sample.attachment.to_bytes() if sample.attachment is not None else b""
            if len(att) != 33 or att[16] != 16:
                raise ValueError(f"attachment of {len(att)} bytes: {att.hex()}")
            seq, stamp = struct.unpack_from("<qq", att)
            gid = att[17:]
            now_ns = time.time_ns()
            if abs(now_ns - stamp) > 60e9:
                raise ValueError(f"source timestamp {stamp} is not about now ({now_ns})")
        except Exception as e:  # noqa: BLE001: every malformed sample is a finding
            with self.lock:
                self.errors.append(f"{key}: {e}")
            return
        with self.lock:
            if self.gids.setdefault(topic, gid) != gid:
                self.errors.append(f"{topic}: the GID changed")
            last = self.seqs.get(topic, 0)
            if seq <= last:
                self.errors.append(f"{topic}: sequence {seq} after {last}")
            self.seqs[topic] = seq
            self.latest[topic] = msg


def expected_topics(agents, namespace):
    ns = f"/{namespace.strip('/')}" if namespace.strip("/") else ""
    robots = [
        (f"{ns}/robot_{i}/{t}", ty)
        for i in range(agents)
        for t, ty in [
            ("odom", "nav_msgs/msg/Odometry"),
            ("ground_truth", "nav_msgs/msg/Odometry"),
            ("plan", "nav_msgs/msg/Path"),
            ("cmd_vel", "geometry_msgs/msg/Twist"),
        ]
    ]
    return dict(
        robots
        + [
            ("/map", "nav_msgs/msg/OccupancyGrid"),
            ("/tf", "tf2_msgs/msg/TFMessage"),
            ("/hnav/markers", "visualization_msgs/msg/MarkerArray"),
            ("/hnav/decisions", "std_msgs/msg/String"),
        ]
    )


def check_tokens(g, topics):
    """The node's token and a publisher token per topic, with the right type and hash."""
    problems = []
    toks = list(g.tokens.values())
    nodes = [t for t in toks if t["kind"] == "NN" and t["node"] == "hnav"]
    if len(nodes) != 1:
        problems.append(f"{len(nodes)} node tokens for /hnav")
    else:
        n = nodes[0]
        if (n["namespace"], n["enclave"], n["nid"]) != ("/", "/", n["eid"]):
            problems.append(f"node token fields {n}")
    pubs = {t["topic"]: t for t in toks if t["kind"] == "MP" and t["node"] == "hnav"}
    for topic, rtype in topics.items():
        p = pubs.get(topic)
        if p is None:
            problems.append(f"no publisher token for {topic}")
            continue
        if ros_type(p["dds"]) != rtype or p["hash"] != TYPESTORE.hash_rihs01(rtype):
            problems.append(f"{topic}: token type {p['dds']} {p['hash']}")
        qos = p["qos"].split(":")
        durability = qos[1] if len(qos) == 6 else "?"
        if (durability == "1") != (topic == "/map"):
            problems.append(f"{topic}: durability {durability!r} in QoS {p['qos']}")
    return problems, len(nodes) + len(pubs)


def check_messages(g, agents, namespace):
    problems = []
    ns = f"/{namespace.strip('/')}" if namespace.strip("/") else ""
    for i in range(agents):
        odom = g.latest.get(f"{ns}/robot_{i}/odom")
        if odom is None or odom.header.frame_id != f"robot_{i}/odom":
            problems.append(f"robot {i}: odom {odom and odom.header.frame_id}")
        elif odom.child_frame_id != f"robot_{i}/base_link":
            problems.append(f"robot {i}: odom child frame {odom.child_frame_id}")
        gt = g.latest.get(f"{ns}/robot_{i}/ground_truth")
        if gt is None or gt.header.frame_id != "map":
            problems.append(f"robot {i}: ground truth {gt and gt.header.frame_id}")
        plan = g.latest.get(f"{ns}/robot_{i}/plan")
        if plan is None or plan.header.frame_id != "map" or len(plan.poses) < 1:
            problems.append(f"robot {i}: plan {plan and len(plan.poses)}")
    grid = g.latest.get("/map")
    if grid is None or len(grid.data) != grid.info.width * grid.info.height:
        problems.append("no /map, or its data is not width x height")
    tf = g.latest.get("/tf")
    pairs = {(t.header.frame_id, t.child_frame_id) for t in (tf.transforms if tf else [])}
    for i in range(agents):
        for pair in [("map", f"robot_{i}/odom"), (f"robot_{i}/odom", f"robot_{i}/base_link")]:
            if pair not in pairs:
                problems.append(f"/tf lacks {pair[0]} -> {pair[1]}")
    return problems


def late_map(session, key, timeout):
    """A late subscriber's /map, from the publisher's cache (rmw_zenoh's transient local)."""
    got = []
    sub = zenoh.ext.declare_advanced_subscriber(
        session,
        key,
        got.append,
        history=zenoh.ext.HistoryConfig(detect_late_publishers=True),
    )
    deadline = time.monotonic() + timeout
    while not got and time.monotonic() < deadline:
        time.sleep(0.05)
    sub.undeclare()
    if not got:
        return None
    return TYPESTORE.deserialize_cdr(got[0].payload.to_bytes(), "nav_msgs/msg/OccupancyGrid")


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--listen", required=True, help="router endpoint, e.g. tcp/127.0.0.1:7447")
    ap.add_argument("--scenario", required=True, type=Path)
    ap.add_argument("--domain", type=int, default=0)
    ap.add_argument("--namespace", default="")
    ap.add_argument("--timeout", type=float, default=120.0)
    a = ap.parse_args()

    scen = tomllib.loads(a.scenario.read_text())
    goals = [tuple(agent["goal"]) for agent in scen["agents"]]
    cell = scen.get("robot", {}).get("cell_size_m", 0.16)
    agents = len(goals)
    topics = expected_topics(agents, a.namespace)

    conf = zenoh.Config()
    conf.insert_json5("mode", '"router"')
    conf.insert_json5("listen/endpoints", f'["{a.listen}"]')
    conf.insert_json5("scouting/multicast/enabled", "false")
    session = zenoh.open(conf)
    g = Graph()
    live = session.liveliness().declare_subscriber(
        f"@ros2_lv/{a.domain}/**", g.on_token, history=True
    )
    data = session.declare_subscriber(f"{a.domain}/**", lambda s: g.on_data(s, a.domain))
    print(f"router up {a.listen}", flush=True)

    deadline = time.monotonic() + a.timeout
    map_key = None
    late = None
    token_count = 0
    # Until the node has come and gone (the run's end): the tokens and the late /map are
    # checked while it lives.
    while time.monotonic() < deadline:
        with g.lock:
            seen, alive = g.node_seen, any(
                t["kind"] == "NN" and t["node"] == "hnav" for t in g.tokens.values()
            )
            if alive and token_count == 0:
                problems, n = check_tokens(g, topics)
                if not problems:
                    token_count = n
                    for t in g.tokens.values():
                        if t["kind"] == "MP" and t["topic"] == "/map":
                            map_key = f"{a.domain}/map/{t['dds']}/{t['hash']}"
        if map_key and late is None:
            late = late_map(session, map_key, 10.0)
            if late is None:
                late = False
        if seen and not alive:
            break
        time.sleep(0.05)
    live.undeclare()
    data.undeclare()
    session.close()

    problems = []
    if not g.node_seen:
        problems.append("never saw node /hnav's liveliness token")
    elif g.node_alive():
        problems.append(f"the run did not end within {a.timeout} s")
    if token_count == 0:
        with g.lock:
            problems += check_tokens(g, topics)[0] or ["the tokens were never all there"]
    else:
        print(f"tokens {token_count}: node /hnav and a publisher per topic, types and hashes as rosbags'")
    if late:
        print(f"late /map {late.info.width}x{late.info.height} from the publisher's cache")
    else:
        problems.append("a late subscriber got no /map from the publisher's cache")
    problems += check_messages(g, agents, a.namespace)
    missing = [t for t in topics if t not in g.latest]
    if missing:
        problems.append(f"no sample on {missing}")
    ns = f"/{a.namespace.strip('/')}" if a.namespace.strip("/") else ""
    for i, (gx, gy) in enumerate(goals):
        gt = g.latest.get(f"{ns}/robot_{i}/ground_truth")
        if gt is None:
            continue
        p = gt.pose.pose.position
        d = math.hypot(p.x - (gx + 0.5) * cell, p.y - (gy + 0.5) * cell)
        line = f"robot {i} final ground truth ({p.x:.3f}, {p.y:.3f}) {d:.3f} m from goal [{gx}, {gy}]"
        print(line)
        if d > cell / 2:
            problems.append(f"{line}: more than half a cell")
    grid = g.latest.get("/map")
    if grid is not None:
        print(f"/map {grid.info.width}x{grid.info.height} at {grid.info.resolution:.3f} m")
    print(f"samples decoded on {len(g.latest)} topics")
    problems += g.errors[:20]
    if problems:
        for p in problems:
            print(f"PROBLEM {p}")
        return 1
    print("OK")
    return 0


if __name__ == "__main__":
    sys.exit(main())
