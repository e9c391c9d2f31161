#!/usr/bin/env bash
# Training runs for the profile-guided build (make build; docs/ARCHITECTURE.md, "Build"): an
# instrumented centridem runs the repository's own examples, one thread, and writes its profile.
# The examples are the engine's everyday work, not the benchmark: examples/demo_settle.toml
# settles 2,025 spheres in a box of walls (contacts that last, local damping, the automatic
# timestep), then removes a wall and lets the column slump (contacts made and broken, rebuilds,
# ParaView frames written). About a minute instrumented, on one core.
#
# Usage: bash scripts/pgo_train.sh INSTRUMENTED_CENTRIDEM PROFILE_DIR
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."
bin=$1
profile=$2
[ -x "$bin" ] || { echo "pgo_train.sh: $bin is not an executable" >&2; exit 2; }
rm -rf "$profile"
mkdir -p "$profile"
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
echo "Training the profile-guided build: examples/demo_settle.toml, 1 thread ..."
OMP_NUM_THREADS=1 "$bin" run examples/demo_settle.toml --out "$out/demo_settle" --threads 1 > "$out/log" 2>&1 ||
  { cat "$out/log" >&2; echo "pgo_train.sh: the training run failed" >&2; exit 1; }
echo "Profile written to $profile ($(find "$profile" -name '*.gcda' | wc -l) files)."
