#!/usr/bin/env bash
# Runs one coverage-guided AFL++ campaign: `fuzz/run.sh TARGET SECONDS` (targets: map, scen,
# scenario, record, log, payload). Builds the harness with `cargo afl` (installed on first use:
# `cargo install cargo-afl`, which builds AFL++ from source with the C compiler), fuzzes from
# the committed corpus fuzz/corpus/TARGET for SECONDS, then prints executions, coverage and
# crashes. Findings land in target/fuzz/TARGET/default/{crashes,queue}; minimise a crash with
# `cargo afl tmin -i CRASH -o fuzz/corpus/TARGET/crash-NAME -- target/fuzz/afl/release/hnav-fuzz-afl TARGET`
# and commit it: the CI-sized campaign (`cargo test -p hnav-fuzz`) replays it from then on.
# `FUZZ_BUILD_ONLY=1 fuzz/run.sh` only builds the harness.
set -euo pipefail
cd "$(dirname "$0")/.."
root=$PWD
target=${1:-}
seconds=${2:-60}
afl_version=0.18.2

if ! cargo afl --version >/dev/null 2>&1; then
    echo "installing cargo-afl $afl_version (builds AFL++, a few minutes)" >&2
    cargo install cargo-afl --version "$afl_version" --locked
fi
export CARGO_TARGET_DIR="$root/target/fuzz/afl"
cargo afl build --release --locked --manifest-path fuzz/afl/Cargo.toml
bin="$CARGO_TARGET_DIR/release/hnav-fuzz-afl"
[ -n "${FUZZ_BUILD_ONLY:-}" ] && exit 0

if [ -z "$target" ] || [ ! -d "fuzz/corpus/$target" ]; then
    echo "usage: fuzz/run.sh TARGET SECONDS (targets: $(ls fuzz/corpus | tr '\n' ' '))" >&2
    exit 2
fi
out="$root/target/fuzz/$target"
rm -rf "$out"
mkdir -p "$out"
# No UI (the log goes to a file), no CPU pinning (the machine is shared), and no complaint
# about the core-dump pattern of a container.
AFL_NO_UI=1 AFL_NO_AFFINITY=1 AFL_I_DONT_CARE_ABOUT_MISSING_CRASHES=1 AFL_SKIP_CPUFREQ=1 \
    cargo afl fuzz -V "$seconds" -i "fuzz/corpus/$target" -o "$out" -- "$bin" "$target" \
    >"$out/afl.log" 2>&1 || { tail -20 "$out/afl.log" >&2; exit 1; }
stats="$out/default/fuzzer_stats"
field() { awk -F' *: *' -v k="$1" '$1 == k { print $2 }' "$stats"; }
crashes=$(field saved_crashes)
echo "$target: $(field execs_done) execs in $(field run_time) s ($(field execs_per_sec)/s)," \
    "edges $(field edges_found) of $(field total_edges), map density $(field bitmap_cvg)," \
    "corpus $(field corpus_count), crashes $crashes, hangs $(field saved_hangs)"
[ "$crashes" = 0 ]
