#!/usr/bin/env bash
# Measures dora-rs node-to-node latency with HNAV's latency method and writes
# OUT_DIR/peers-dora.csv, rows for `hnav-bench latency --peers OUT_DIR/peers-dora.csv`.
#
#   bash bench/peers/dora/run.sh OUT_DIR [--quick] [--sizes 8,64,...]
#
# 1. A Python venv (target/peers/dora-venv under the repo root) with the dora CLI/daemon from
#    PyPI (dora-rs-cli, pinned to the version of dora-node-api in Cargo.toml).
# 2. The two nodes (one binary, hnav-peer-dora ping|pong) in release; CARGO_TARGET_DIR
#    defaults to target/peers/dora under the repo root. The build runs at nice 10.
# 3. `dora run` on a copy of dataflow.yml pointing at that binary: dora's local mode, which
#    runs the daemon inside the CLI process (no coordinator, nothing left behind to `dora
#    destroy`). It is bounded by HNAV_DORA_TIMEOUT seconds (default 600 quick, 3600 full),
#    then stopped like Ctrl-C and killed 15 s later; on any exit the trap stops it too.
# The log of the run (dora's and the nodes' output) goes to OUT_DIR/peers-dora.log.
set -euo pipefail

DORA_VERSION=1.1.0

usage() {
    echo "usage: $0 OUT_DIR [--quick] [--sizes 8,64,...]" >&2
    exit 2
}
[[ $# -ge 1 && "$1" != -* ]] || usage
out_dir=$1
shift
quick=no
sizes=
while [[ $# -gt 0 ]]; do
    case $1 in
        --quick) quick=yes ;;
        --sizes) [[ $# -ge 2 ]] || usage; sizes=$2; shift ;;
        --sizes=*) sizes=${1#--sizes=} ;;
        *) usage ;;
    esac
    shift
done

here=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
root=$(cd "$here/../../.." && pwd)
export CARGO_TARGET_DIR=${CARGO_TARGET_DIR:-$root/target/peers/dora}
venv=$root/target/peers/dora-venv
mkdir -p "$out_dir"
out_dir=$(cd "$out_dir" && pwd)
csv=$out_dir/peers-dora.csv
log=$out_dir/peers-dora.log

# 1. The dora CLI (it carries the daemon), exactly the node API's version.
if [[ "$("$venv/bin/dora" --version 2>/dev/null || true)" != "dora-cli $DORA_VERSION" ]]; then
    echo "installing dora-rs-cli==$DORA_VERSION into $venv" >&2
    python3 -m venv "$venv"
    "$venv/bin/pip" install --quiet --disable-pip-version-check "dora-rs-cli==$DORA_VERSION"
fi
dora=$venv/bin/dora
"$dora" --version >&2

# 2. The nodes.
nice -n 10 cargo build --release --locked --manifest-path "$here/Cargo.toml"
bin=$CARGO_TARGET_DIR/release/hnav-peer-dora

# 3. The dataflow, in a scratch directory (dora writes its run logs beside the YAML).
work=$(mktemp -d "${TMPDIR:-/tmp}/hnav-peer-dora.XXXXXX")
dora_pid=
cleanup() {
    if [[ -n "$dora_pid" ]] && kill -0 "$dora_pid" 2>/dev/null; then
        echo "stopping dora run (pid $dora_pid)" >&2
        kill -INT "$dora_pid" 2>/dev/null || true
        for _ in $(seq 150); do kill -0 "$dora_pid" 2>/dev/null || break; sleep 0.1; done
        kill -KILL "$dora_pid" 2>/dev/null || true
    fi
    rm -rf "$work"
}
trap cleanup EXIT
trap 'exit 130' INT TERM
sed "s|^\(\s*path:\s*\).*hnav-peer-dora\s*$|\1$bin|" "$here/dataflow.yml" >"$work/dataflow.yml"
grep -q "path: $bin\$" "$work/dataflow.yml" || {
    echo "error: could not point $work/dataflow.yml at $bin" >&2
    exit 1
}

rm -f "$csv"
export HNAV_DORA_OUT=$csv HNAV_DORA_QUICK=$quick HNAV_DORA_SIZES=$sizes
if [[ $quick == yes ]]; then default_timeout=600; else default_timeout=3600; fi
timeout_s=${HNAV_DORA_TIMEOUT:-$default_timeout}
started=$(date +%s)
(cd "$work" && exec "$dora" run dataflow.yml) >"$log" 2>&1 &
dora_pid=$!
status=0
while kill -0 "$dora_pid" 2>/dev/null; do
    if (($(date +%s) - started >= timeout_s)); then
        echo "error: dora run did not finish within ${timeout_s} s (HNAV_DORA_TIMEOUT); stopping it. Last lines of $log:" >&2
        tail -n 20 "$log" >&2
        exit 124
    fi
    sleep 0.5
done
wait "$dora_pid" || status=$?
dora_pid=
if [[ $status -ne 0 || ! -s "$csv" ]]; then
    echo "error: dora run failed (exit $status, CSV $( [[ -s "$csv" ]] && echo written || echo missing)); the nodes' errors, from $log:" >&2
    grep -E -A3 "(ping|pong): (Error|thread .* panicked)" "$log" | grep -v -E "^\s+at |Stack backtrace" | head -n 30 >&2 || true
    echo "last lines of $log:" >&2
    tail -n 15 "$log" >&2
    exit 1
fi
# Ping's summary (which buffers were shared memory), from the log.
grep -E "ping: (dora $DORA_VERSION latency|  [0-9]+ B: |wrote )" "$log" | sed 's/^.* ping: //' >&2 || true

# The table.
awk -F, 'NR == 1 { printf "%-22s %10s %7s %11s %11s %11s %11s %11s %11s\n", "name", "size_B", "n", "avg_us", "p50_us", "p90_us", "p99_us", "p99.9_us", "max_us"; next }
         { printf "%-22s %10s %7s %11s %11s %11s %11s %11s %11s\n", $4, $5, $10, $6, $7, $8, $9, $11, $12 }' "$csv"
echo "wrote $csv (${SECONDS} s in all)"
