#!/usr/bin/env bash
# Refreshes supply-chain/advisory-db/, the repository's copy of the RustSec advisory database
# (https://github.com/rustsec/advisory-db, dedicated to the public domain under CC0-1.0), and
# supply-chain/advisory-db.rev, the commit and date it is a copy of.
#
# Needs the internet (GitHub): run it on a developer machine, then `supply-chain/deny.sh` and
# commit `supply-chain/`. CI reaches only the package registries, so it never fetches the
# database; it checks against this copy. An argument clones from elsewhere (a mirror, a local
# clone) instead of GitHub.
set -euo pipefail
cd "$(dirname "$0")/.."

source=${1:-https://github.com/rustsec/advisory-db.git}
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
git clone --quiet --depth 1 "$source" "$tmp/db"
rev=$(git -C "$tmp/db" log -1 --format='%H %cI')

# Only the tree (no .git): `supply-chain/deny.sh` makes the git checkout cargo-deny opens.
rm -rf supply-chain/advisory-db
mkdir supply-chain/advisory-db
git -C "$tmp/db" archive HEAD | tar -x -C supply-chain/advisory-db
echo "$rev" >supply-chain/advisory-db.rev
echo "supply-chain/advisory-db: rustsec/advisory-db at $rev"
