#!/usr/bin/env python3
"""A Foxglove WebSocket client that shares no code with HNAV: it checks what
`hnav run --foxglove ADDR` (or `hnav view`) serves, and that `hnav log export --mcap`
writes the same channels.

    live URL --width W --height H --robots N --advertised OUT.json [--timeout S]
        Connects offering the subprotocols `foxglove.websocket.v1` and `foxglove.sdk.v1`
        (the protocol's old and new names; retrying until the server listens), reads `serverInfo` and `advertise`, first drops one connection in the
        middle of the stream (the server must not mind), then subscribes to /map, /scene,
        /log and every /robots/<i>/stats and decodes the binary `messageData` frames
        (opcode 0x01: subscription id u32 LE, log time u64 LE, payload) until the server
        closes (the run ended) or S seconds pass. Checks: a grid of W x H cells, scene
        updates with every robot as an entity, a robot that moved, speeds plotted. Writes
        the advertised channels to OUT.json.

    mcap FILE --advertised OUT.json
        Opens FILE with the `mcap` package and checks that it holds every channel
        advertised live, with the same schema name, schema encoding, schema and message
        encoding, and messages on /map and /scene.

Prints `ok ...` lines; exits 1 with `FAIL ...` on the first check that fails.
Packages: websockets, mcap (clients/python/requirements.txt).
"""

import argparse
import asyncio
import base64
import json
import struct
import sys
import time

# The Foxglove WebSocket protocol's name, old and new: the Foxglove SDK (the `foxglove` crate
# HNAV serves with) negotiates it as `foxglove.sdk.v1`, Foxglove's current name for the
# protocol first published as `foxglove.websocket.v1` (the same messages and frames), and
# refuses a client that offers only the old name with HTTP 400.
SUBPROTOCOLS = ["foxglove.websocket.v1", "foxglove.sdk.v1"]
MESSAGE_DATA = 0x01


def fail(why):
    print(f"FAIL {why}", flush=True)
    sys.exit(1)


async def connect(url, deadline):
    from websockets.asyncio.client import connect as ws_connect

    while True:
        try:
            ws = await ws_connect(url, subprotocols=SUBPROTOCOLS, max_size=None)
            if ws.subprotocol not in SUBPROTOCOLS:
                fail(f"the server chose the subprotocol {ws.subprotocol!r}")
            return ws
        except OSError:
            if time.monotonic() > deadline:
                fail(f"no Foxglove server at {url}")
            await asyncio.sleep(0.05)


async def handshake(ws):
    """serverInfo, then advertise: {channel id: channel}."""
    info = json.loads(await ws.recv())
    if info.get("op") != "serverInfo":
        fail(f"the first message is not serverInfo: {info}")
    channels = {}
    # Advertised one channel at a time, /log last (the order of channels::shown).
    while "/log" not in {c["topic"] for c in channels.values()}:
        msg = await ws.recv()
        if isinstance(msg, bytes):
            continue
        msg = json.loads(msg)
        if msg.get("op") == "advertise":
            for c in msg["channels"]:
                channels[c["id"]] = c
    return info, channels


def wanted(topic):
    return topic in ("/map", "/scene", "/log") or (
        topic.startswith("/robots/") and topic.endswith("/stats")
    )


async def subscribe(ws, channels):
    subs = {}
    for i, (cid, c) in enumerate(sorted(channels.items())):
        if wanted(c["topic"]):
            subs[i + 1] = c
    await ws.send(
        json.dumps(
            {
                "op": "subscribe",
                "subscriptions": [
                    {"id": sid, "channelId": c["id"]} for sid, c in subs.items()
                ],
            }
        )
    )
    return subs


def decode(frame, subs):
    if frame[0] != MESSAGE_DATA:
        return None
    sid, t_ns = struct.unpack_from("<IQ", frame, 1)
    c = subs.get(sid)
    if c is None:
        fail(f"messageData for subscription {sid}, which was never made")
    return c["topic"], t_ns, json.loads(frame[13:])


async def drop_mid_stream(url, deadline):
    ws = await connect(url, deadline)
    _, channels = await handshake(ws)
    subs = await subscribe(ws, channels)
    while True:
        frame = await ws.recv()
        if isinstance(frame, bytes) and decode(frame, subs):
            break
    # Gone without a close frame, as a crashed viewer would go.
    ws.transport.abort()
    print("ok a client dropped in the middle of the stream", flush=True)


def robot_xy(entity):
    p = entity["cubes"][0]["pose"]["position"]
    return p["x"], p["y"]


async def live(args):
    from websockets.exceptions import ConnectionClosed

    deadline = time.monotonic() + args.timeout
    await drop_mid_stream(args.url, deadline)
    ws = await connect(args.url, deadline)
    info, channels = await handshake(ws)
    print(f"ok subprotocol {ws.subprotocol}, serverInfo from {info.get('name')!r}", flush=True)
    subs = await subscribe(ws, channels)
    grids, scenes, logs, speeds = [], [], [], {}
    try:
        while time.monotonic() < deadline:
            try:
                frame = await asyncio.wait_for(ws.recv(), deadline - time.monotonic())
            except asyncio.TimeoutError:
                break
            if not isinstance(frame, bytes):
                continue
            topic, t_ns, body = decode(frame, subs)
            if topic == "/map":
                grids.append(body)
            elif topic == "/scene":
                scenes.append((t_ns, body))
            elif topic == "/log":
                logs.append(body)
            else:
                speeds.setdefault(topic, []).append(body["speed_m_s"])
    except ConnectionClosed:
        pass
    advertised = sorted(
        (
            {k: c[k] for k in ("topic", "encoding", "schemaName", "schemaEncoding", "schema")}
            for c in channels.values()
        ),
        key=lambda c: c["topic"],
    )
    with open(args.advertised, "w") as f:
        json.dump(advertised, f)
    print(f"ok {len(advertised)} channels advertised", flush=True)

    if not grids:
        fail("no /map grid received")
    g = grids[0]
    data = base64.b64decode(g["data"])
    if g["column_count"] != args.width or len(data) != args.width * args.height * g["cell_stride"]:
        fail(f"grid of {g['column_count']} columns and {len(data)} bytes, not {args.width} x {args.height}")
    print(f"ok grid {args.width} x {args.height}", flush=True)

    if len(scenes) < 5:
        fail(f"{len(scenes)} scene updates")
    robots = args.robots
    first, last = {}, {}
    for _, body in scenes:
        for e in body["entities"]:
            if e["id"].startswith("robot/"):
                first.setdefault(e["id"], robot_xy(e))
                last[e["id"]] = robot_xy(e)
    if len(last) != robots:
        fail(f"robots in the scene: {sorted(last)}")
    moved = [r for r in last if abs(first[r][0] - last[r][0]) + abs(first[r][1] - last[r][1]) > 0.1]
    if not moved:
        fail("no robot moved in the scene")
    times = [t for t, _ in scenes]
    if times != sorted(times):
        fail("scene updates out of time order")
    print(f"ok {len(scenes)} scene updates, robots moved: {sorted(moved)}", flush=True)
    if len(speeds) != robots or not any(max(v) > 0 for v in speeds.values()):
        fail(f"speeds: {sorted(speeds)}")
    print(f"ok speeds of {len(speeds)} robots, {len(logs)} log lines", flush=True)


def check_mcap(args):
    from mcap.reader import make_reader

    with open(args.advertised) as f:
        advertised = json.load(f)
    with open(args.file, "rb") as f:
        reader = make_reader(f)
        summary = reader.get_summary()
        if summary is None:
            fail(f"{args.file}: no summary")
        by_topic = {c.topic: c for c in summary.channels.values()}
        for a in advertised:
            c = by_topic.get(a["topic"])
            if c is None:
                fail(f"{args.file}: no channel {a['topic']}")
            s = summary.schemas[c.schema_id]
            got = (s.name, s.encoding, s.data.decode(), c.message_encoding)
            want = (a["schemaName"], a["schemaEncoding"], a["schema"], a["encoding"])
            if got != want:
                fail(f"{a['topic']}: {got[:2] + got[3:]} in the file, {want[:2] + want[3:]} live (or the schemas differ)")
        counts = summary.statistics.channel_message_counts
        for topic in ("/map", "/scene"):
            if counts.get(by_topic[topic].id, 0) == 0:
                fail(f"{args.file}: no message on {topic}")
    print(f"ok {args.file} holds the {len(advertised)} channels advertised live", flush=True)


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    sub = p.add_subparsers(dest="cmd", required=True)
    lv = sub.add_parser("live")
    lv.add_argument("url")
    lv.add_argument("--width", type=int, required=True)
    lv.add_argument("--height", type=int, required=True)
    lv.add_argument("--robots", type=int, required=True)
    lv.add_argument("--advertised", required=True)
    lv.add_argument("--timeout", type=float, default=60.0)
    mc = sub.add_parser("mcap")
    mc.add_argument("file")
    mc.add_argument("--advertised", required=True)
    args = p.parse_args()
    if args.cmd == "live":
        asyncio.run(live(args))
    else:
        check_mcap(args)


if __name__ == "__main__":
    main()
