#!/usr/bin/env bash
# The "same bits" check of docs/results/bench.md: a change meant only to go faster must leave
# every result unchanged. Runs one build on a settling column with walls and the automatic
# timestep (2 threads) and on the periodic brick the specimen generator relaxes, and prints one
# md5 for each (compare them between the builds before and after the change).
#
# Hashed: the column's final_state.csv and measurements.csv; the brick's brick.json (positions and
# contact history, 17 digits) and the assembled specimen.xyzr.
# Usage (from the repo root):  bash bench/same_bits.sh [./build/centridem]
# 3f77657 to 7e0dd1a: 5a22be9a25a8 and 7bd84ad5bbee (the column's hash is the one bench.md
# quotes for every engine since 5da09e9; the brick's was first taken on 3f77657).
set -euo pipefail
bin="${1:-./build/centridem}"
[ -x "$bin" ] || { echo "same_bits.sh: '$bin' is not an executable (make build first)" >&2; exit 2; }
bin="$(cd "$(dirname "$bin")" && pwd)/$(basename "$bin")"
here="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
out="$(mktemp -d "${TMPDIR:-/tmp}/same_bits.XXXXXX")"
trap 'rm -rf "$out"' EXIT
cd "$here"
run() { "$bin" "$@" >"$out/log" 2>&1 || { cat "$out/log" >&2; echo "same_bits.sh: '$bin $*' failed" >&2; exit 1; }; }
run run examples/settle_column.toml --threads 2 --out "$out/column"
run generate examples/shear_small.toml --out "$out/brick"
column="$(cat "$out/column/final_state.csv" "$out/column/measurements.csv" | md5sum | cut -c1-12)"
brick="$(cat "$out/brick/brick.json" "$out/brick/specimen.xyzr" | md5sum | cut -c1-12)"
echo "settle_column (2 threads): $column"
echo "shear_small brick:         $brick"
