#!/usr/bin/env bash
# cargo-deny over the workspace, offline: `supply-chain/deny.sh [CHECK...]` (default: all of
# advisories, bans, licenses, sources; deny.toml says what each allows).
#
# Advisories are checked against the repository's copy of the RustSec advisory database,
# supply-chain/advisory-db/ (refreshed by supply-chain/refresh-advisory-db.sh on a machine
# with internet). cargo-deny opens a database as a git checkout named after its URL under
# `db-path` and judges its age by the checkout's commit, so the copy is committed there as
# one commit dated like the upstream commit it copies, so that its age is the copy's real age.
set -euo pipefail
cd "$(dirname "$0")/.."

read -r commit date <supply-chain/advisory-db.rev
# deny.toml's db-path; the child is cargo-deny's name for https://github.com/rustsec/advisory-db.
db=target/advisory-dbs/advisory-db-3157b0e258782691
rm -rf "$db"
mkdir -p "$db"
cp -R supply-chain/advisory-db/. "$db/"
export GIT_AUTHOR_DATE="$date" GIT_COMMITTER_DATE="$date"
git -C "$db" init --quiet
git -C "$db" add --all
git -C "$db" -c user.name=hnav -c user.email=hnav@example.invalid -c commit.gpgsign=false \
    commit --quiet -m "rustsec/advisory-db $commit"
# cargo-deny takes the newer of the commit's date and .git/HEAD's modification time.
touch -d "$date" "$db/.git/HEAD"

# deny.toml lets any age pass (a commit's CI result must not change with the calendar): say
# it here instead.
age_days=$(( ($(date +%s) - $(date -d "$date" +%s)) / 86400 ))
if [ "$age_days" -gt 180 ]; then
    echo "warning: the advisory database copy is $age_days days old (of $date);" \
        "refresh it: supply-chain/refresh-advisory-db.sh" >&2
fi

# cargo-deny reads the whole graph for deny.toml's target (`cargo metadata`), optional
# dependencies the build never downloads too (nalgebra's glam conversions, ...): fetch them
# from crates.io first; a no-op where they are on disk already.
cargo fetch --locked --target x86_64-unknown-linux-gnu
# --offline: no fetch of the database (GitHub), and `cargo metadata` reads only what is on disk.
cargo deny --offline --locked --color never check "${@:-all}"
