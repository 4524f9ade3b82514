#!/usr/bin/env bash
# The performance suite with its peers, in one run (docs/explanation/performance.md):
#
#   bench/perf.sh OUT [--quick] [--no-peers]
#
# 1. builds hnav-bench and hnav-coordinator in release;
# 2. measures the peers with their own projects (bench/peers/zenoh, bench/peers/dora: each
#    run.sh builds what it needs and writes OUT/peers-<name>.csv); a peer that cannot run
#    here is reported and left out of the table, never silently;
# 3. runs `hnav-bench perf` (latency with the peers' rows, decision round at 1..256 agents,
#    neural map), which writes OUT/perf.md, OUT/latency.{csv,md,svg}, OUT/round.csv.
#
# Run it on a quiet machine: nothing else busy, so that every ratio compares like with like.
set -euo pipefail
cd "$(dirname "$0")/.."

out="${1:?usage: bench/perf.sh OUT [--quick] [--no-peers]}"
shift
quick=()
peers=1
for arg in "$@"; do
    case "$arg" in
        --quick) quick=(--quick) ;;
        --no-peers) peers=0 ;;
        *) echo "unknown argument $arg" >&2; exit 2 ;;
    esac
done
mkdir -p "$out"
out="$(cd "$out" && pwd)"

cargo build --release --locked -p hnav-bench -p hnav-coordinator

files=()
if [ "$peers" = 1 ]; then
    for peer in zenoh dora; do
        script="bench/peers/$peer/run.sh"
        if [ ! -f "$script" ]; then
            echo "perf: no $script; $peer left out" >&2
            continue
        fi
        rm -f "$out/peers-$peer.csv"
        status=0
        bash "$script" "$out" "${quick[@]}" || status=$?
        if [ -f "$out/peers-$peer.csv" ]; then
            # A peer that lost a message at one point still wrote the others' rows.
            [ "$status" = 0 ] || echo "perf: $script exit $status; the points it measured stay" >&2
            files+=("$out/peers-$peer.csv")
        else
            echo "perf: $script failed (exit $status); $peer left out of the table" >&2
        fi
    done
fi

peer_args=()
if [ "${#files[@]}" -gt 0 ]; then
    peer_args=(--peers "$(IFS=,; echo "${files[*]}")")
fi
target/release/hnav-bench perf --out "$out" "${quick[@]}" "${peer_args[@]}"
