#!/usr/bin/env python3
"""Watch a changing world from Python: what one robot's sensor sees, the cells the agents saw
change, and the coordinator's map as it hands it to agents that restart (`[sensing]`).

    python examples/watch_world.py RUN_ID --width W [--agent I] [--timeout S]

W is the map's width (it turns cell indices into [x,y]). Prints the robot's first view
(`view agent I period P: N cells seen, B blocked`), every sighting (`sighting round R a0:
closed [5,0]`) and every map the coordinator sends (`world round R for [0]: closed [5,0];
opened -`). Exits 0 once it has printed a view, a sighting and a map; 1 when the run goes
`--timeout` seconds without one of them still missing; 2 when no run RUN_ID is live within
`--timeout` seconds.
"""

import argparse
import ctypes
import os
import sys
import time

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))

from hnav import msg  # noqa: E402
from hnav.run import Run, RunError  # noqa: E402


def cells(width: int, indices) -> str:
    """Cell indices as `[x,y] [x,y]`, or `-` for none."""
    return " ".join(f"[{c % width},{c // width}]" for c in indices) or "-"


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("run_id", metavar="RUN_ID")
    parser.add_argument("--width", type=int, required=True, help="the map's width, cells")
    parser.add_argument("--agent", type=int, default=0, help="whose view (default 0)")
    parser.add_argument(
        "--first",
        type=int,
        help="the first robot of the agent's process, whose view/<first> topic carries the "
        "agent's view (default: the agent, as with one robot a process)",
    )
    parser.add_argument("--timeout", type=float, default=30.0, help="give up after S s")
    a = parser.parse_args()
    try:
        with Run(a.run_id, node_name="watch-world", wait_s=a.timeout) as run:
            return watch(run, a)
    except RunError as e:
        print(f"error: {e}", file=sys.stderr)
        return 2


def watch(run: Run, a) -> int:
    """Subscribes, then prints what the docstring says; the exit code of `main`."""
    topics = {
        "view": run.subscribe(f"view/{a.agent if a.first is None else a.first}", a.timeout),
        "sighting": run.subscribe("sightings", a.timeout),
        "world": run.subscribe("world", a.timeout),
    }
    missing = set(topics)
    deadline = time.monotonic() + a.timeout
    while missing:
        for s in topics["view"].drain():
            # One sample per agent process: the view of each of its robots.
            h = msg.ViewsHeader.from_buffer_copy(bytes(s.user_header().contents))
            mine = [v for v in msg.slice_of(msg.View, h.count, s) if v.agent == a.agent]
            for v in mine[:1] if "view" in missing else []:
                seen = list(v.cells())
                blocked = sum(1 for _, _, b in seen if b)
                print(f"view agent {v.agent} period {v.period}: {len(seen)} cells seen, {blocked} blocked")
                missing.discard("view")
        for s in topics["sighting"].drain():
            g = msg.Sighting.from_buffer_copy(bytes(s.payload().contents))
            changes = list(g.changes())
            closed = cells(a.width, [c for c, shut in changes if shut])
            opened = cells(a.width, [c for c, shut in changes if not shut])
            print(f"sighting round {g.round} a{g.agent}: closed {closed}; opened {opened}")
            missing.discard("sighting")
        for s in topics["world"].drain():
            h = msg.WorldHeader.from_buffer_copy(bytes(s.user_header().contents))
            # The header's counts, not the payload's length: the binding gives it in bytes.
            words = msg.slice_of(ctypes.c_uint32, h.to + h.closed + h.opened, s)
            agents, closed, opened = h.split(words)
            print(
                f"world round {h.round} for {agents}: closed {cells(a.width, closed)}; "
                f"opened {cells(a.width, opened)}"
            )
            missing.discard("world")
        if not missing:
            break
        left = deadline - time.monotonic()
        if left <= 0:
            print(f"error: nothing on {sorted(missing)} within {a.timeout} s", file=sys.stderr)
            return 1
        # Sightings are sent silently (the candidate after them wakes the coordinator): poll
        # at a tenth of a second rather than wait on their listener.
        topics["view"].wait(min(left, 0.1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
