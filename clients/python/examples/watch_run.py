#!/usr/bin/env python3
"""Watch a live HNAV run from Python: its commits, ground truth and one agent's neural map.

    python examples/watch_run.py RUN_ID [--host NAME] [--agent I] [--commits N] [--timeout S]

RUN_ID is the run's id (`hnav run --run ID`, or the one `hnav ps` lists); `--host NAME` joins
host NAME's part of a run across hosts (`hnav run --host NAME`), on that host. Prints each commit
as it arrives (`commit R: a0 accept [x,y], a1 hold, ...`), the ground truth every 100 commits
(`truth period P: ...`), and at the end the agent's latest neural map as a log-scale heatmap
(`map agent I round R: W x H ...` and H rows of W glyphs). Exits 0 once N commits were seen;
1 when the run ended (no commit for `--timeout` seconds) before that; 2 when no run RUN_ID is
live within `--timeout` seconds (nothing is left behind: no node is made in a run that is not
there).
"""

import argparse
import ctypes
import math
import os
import sys
import time

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))

from hnav import msg  # noqa: E402
from hnav.run import Run, RunError  # noqa: E402

# Log-scale heatmap glyphs, lowest to highest activation; a blocked or unset cell is '@'.
GLYPHS = " .:-=+*#%"


def cell(width: int, index: int) -> str:
    """A cell index as `[x,y]` (column, row), as every HNAV output writes cells."""
    if index == msg.NO_CELL:
        return "-"
    return f"[{index % width},{index // width}]"


def describe(d, width: int) -> str:
    """One decision: `a3 accept [4,5]`, `a1 block head-on`, `a2 replan via [7,1]`,
    `a4 task goal [9,2]` (a lifelong run's next goal)."""
    verdict = msg.Verdict.NAMES.get(d.verdict, f"verdict-{d.verdict}")
    text = f"a{d.agent} {verdict}"
    if d.verdict == msg.Verdict.ACCEPT:
        text += f" {cell(width, d.cell)}"
    elif d.verdict == msg.Verdict.BLOCK:
        text += f" {msg.ConflictKind.NAMES.get(d.kind, d.kind)}"
    elif d.verdict == msg.Verdict.REPLAN:
        text += f" via {cell(width, d.waypoint)}"
    elif d.verdict == msg.Verdict.TASK:
        text += f" goal {cell(width, d.waypoint)}"
    return text


def heatmap(values, width: int, height: int):
    """Rows of glyphs: log(activation) spread over GLYPHS between the smallest positive
    value and the largest (activations fall off by orders of magnitude from the target)."""
    positive = [v for v in values if v > 0 and math.isfinite(v)]
    if not positive:
        return ["@" * width for _ in range(height)]
    lo, hi = math.log(min(positive)), math.log(max(positive))
    span = (hi - lo) or 1.0
    rows = []
    for y in range(height):
        row = ""
        for v in values[y * width : (y + 1) * width]:
            if not (v > 0 and math.isfinite(v)):
                row += "@"
            else:
                level = (math.log(v) - lo) / span
                row += GLYPHS[min(len(GLYPHS) - 1, int(level * len(GLYPHS)))]
        rows.append(row)
    return rows


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("run_id", metavar="RUN_ID")
    parser.add_argument(
        "--host", default=None, help="the host's part of a run across hosts (its domain)"
    )
    parser.add_argument("--agent", type=int, default=0, help="whose neural map (default 0)")
    parser.add_argument("--commits", type=int, default=200, help="stop after N commits")
    parser.add_argument(
        "--timeout", type=float, default=30.0, help="give up after S s without a commit"
    )
    a = parser.parse_args()

    try:
        # Waits for the run to be live before making a node in it (a mistyped id leaves
        # nothing behind); the node goes when `with` ends, however it ends.
        with Run(a.run_id, node_name="watch-run", wait_s=a.timeout, domain=a.host) as run:
            return watch(run, a)
    except RunError as e:
        print(f"error: {e}", file=sys.stderr)
        return 2


def watch(run: Run, a) -> int:
    """Subscribes, then prints what the docstring says; the exit code of `main`."""
    # The map first: its header gives the width that turns cell indices into [x,y], and a
    # late joiner gets the agent's last snapshot at once (the topic keeps it as history).
    maps = run.subscribe(f"map/{a.agent}", a.timeout)
    commits = run.subscribe("commit", a.timeout)
    truth = run.subscribe("truth", a.timeout)

    deadline = time.monotonic() + a.timeout
    snapshot = newest_map(maps, None)  # (header, values), copied out of shared memory
    while snapshot is None:
        left = deadline - time.monotonic()
        if left <= 0:
            print(f"error: no neural map from agent {a.agent} within {a.timeout} s", file=sys.stderr)
            return 1
        maps.wait(left)
        snapshot = newest_map(maps, None)
    width = snapshot[0].width

    seen, first, last, latest_truth = 0, None, None, None
    deadline = time.monotonic() + a.timeout
    while seen < a.commits:
        for s in commits.drain():
            c = msg.CommitHeader.from_buffer_copy(bytes(s.user_header().contents))
            decided = msg.slice_of(msg.Decision, c.count, s)
            decisions = ", ".join(describe(d, width) for d in decided) or "no decisions"
            print(f"commit {c.round}: {decisions}")
            first = c.round if first is None else first
            last = c.round
            seen += 1
            deadline = time.monotonic() + a.timeout
            if seen % 100 == 0 and latest_truth is not None:
                print_truth(latest_truth)
            if seen == a.commits:
                break
        for s in truth.drain():
            header = msg.TruthHeader.from_buffer_copy(bytes(s.user_header().contents))
            latest_truth = (header, msg.slice_of(msg.Pose, header.robots, s))
        snapshot = newest_map(maps, snapshot)
        if seen < a.commits:
            left = deadline - time.monotonic()
            if left <= 0:
                print(f"error: the run sent no commit for {a.timeout} s ({seen} seen)", file=sys.stderr)
                return 1
            commits.wait(left)
    if latest_truth is not None:
        print_truth(latest_truth)
    header, values = snapshot
    print(
        f"map agent {header.agent} round {header.round}: {header.width} x {header.height}, "
        f"target {cell(header.width, header.target)}, {header.iterations} sweeps, "
        f"{msg.ActivationKind.NAMES.get(header.activation, header.activation)}"
    )
    for row in heatmap(values, header.width, header.height):
        print(f"  |{row}|")
    print(f"watched {seen} commits (rounds {first}-{last}) of run {a.run_id}")
    return 0


def newest_map(topic, current):
    """The newest snapshot on `topic` as (header, values), or `current` if none came."""
    for s in topic.drain():
        header = msg.MapHeader.from_buffer_copy(bytes(s.user_header().contents))
        values = s.payload()
        # One value per cell: width x height, not `values.len()`, which the binding gives in
        # bytes (four per value). Copied out: the chunk goes back to the agent when `s` is
        # dropped.
        n = header.width * header.height
        current = (header, list((ctypes.c_float * n).from_address(values.as_ptr())))
    return current


def print_truth(truth) -> None:
    """The ground truth, (header, poses): each robot's pose and the collisions so far."""
    t, robots = truth
    poses = ", ".join(
        f"r{i} ({p.x_m:.2f}, {p.y_m:.2f}, {math.degrees(p.theta_rad):.0f} deg)"
        for i, p in enumerate(robots)
    )
    print(f"truth period {t.period}: {poses}; {t.collisions} collisions")


if __name__ == "__main__":
    sys.exit(main())
