#!/usr/bin/env bash
# Measures zenoh pub/sub latency with HNAV's latency method and writes
# OUT_DIR/peers-zenoh.csv, rows for `hnav-bench latency --peers OUT_DIR/peers-zenoh.csv`.
#
#   bash bench/peers/zenoh/run.sh OUT_DIR [--quick] [more hnav-peer-zenoh options]
#
# Builds in release first. CARGO_TARGET_DIR defaults to target/peers/zenoh under the repo
# root (gitignored); set it to build elsewhere. The build runs at nice 10 so it does not
# starve whatever else the machine does; the measurement itself runs at normal priority.
set -euo pipefail

if [[ $# -lt 1 || "$1" == -* ]]; then
    echo "usage: $0 OUT_DIR [--quick] [--sizes 8,64,...] [--variants zenoh,zenoh-shm]" >&2
    exit 2
fi
out_dir=$1
shift

here=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
root=$(cd "$here/../../.." && pwd)
export CARGO_TARGET_DIR=${CARGO_TARGET_DIR:-$root/target/peers/zenoh}

nice -n 10 cargo build --release --locked --manifest-path "$here/Cargo.toml"
mkdir -p "$out_dir"
bin=$CARGO_TARGET_DIR/release/hnav-peer-zenoh
status=0
"$bin" --out "$out_dir/peers-zenoh.csv" "$@" || status=$?
# Zenoh leaves the SHM segments its globals held at exit in /dev/shm; remove those no
# process holds any more (never another live process's).
"$bin" --cleanup-shm || true
exit "$status"
