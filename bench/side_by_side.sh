#!/usr/bin/env bash
# centridem beside the peers in one window, as issue 18's acceptance asks: R alternating rounds,
# medians, and each round's ratio to the faster peer per core. Every 1-thread and 1-process run is
# pinned to core 0, the 2-thread runs to cores 0-1 (the machines are shared and noisy: only ratios
# measured side by side mean anything).
#
# Usage (from the repo root):  bash bench/side_by_side.sh [--bin ./build/centridem] [--rounds 3]
#   [--packed-steps 2000] [--flow-steps 10000] [--packing FILE]
# Each round: `centridem bench --law peers --threads 1` and `--threads 2` at the default skin and
# at `--skin 5e-5` (the peers' skin), `--law paper --threads 1`, then LIGGGHTS (epsd2) and LAMMPS
# (granular) with 1 process (bench/run_peers.sh). Then R rounds of the flowing column at both
# skins beside LAMMPS's flowing column. Needs the peers: apt-get install -y lammps liggghts.
# Prints one line per run and a summary table in Markdown (medians; each round's values after).
set -euo pipefail

here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
bin="$here/../build/centridem"
rounds=3
psteps=2000
fsteps=10000
packing=""
while [ $# -gt 0 ]; do
  case "$1" in
    --bin) bin="$2"; shift 2 ;;
    --rounds) rounds="$2"; shift 2 ;;
    --packed-steps) psteps="$2"; shift 2 ;;
    --flow-steps) fsteps="$2"; shift 2 ;;
    --packing) packing="$2"; shift 2 ;;
    -h|--help) sed -n '2,13p' "${BASH_SOURCE[0]}" | sed 's/^# \{0,1\}//'; exit 0 ;;
    *) echo "side_by_side.sh: unknown argument '$1' (see --help)" >&2; exit 2 ;;
  esac
done
for v in "$rounds" "$psteps" "$fsteps"; do
  case "$v" in ''|*[!0-9]*|0) echo "side_by_side.sh: --rounds/--packed-steps/--flow-steps need positive integers, got '$v'" >&2; exit 2 ;; esac
done
[ -x "$bin" ] || { echo "side_by_side.sh: centridem binary '$bin' not found (make build, or --bin)" >&2; exit 2; }
for p in lmp liggghts; do
  command -v "$p" >/dev/null || { echo "side_by_side.sh: '$p' not found: apt-get install -y lammps liggghts" >&2; exit 2; }
done
pk=()
[ -z "$packing" ] || pk=(--packing "$packing")

out="$(mktemp -d "${TMPDIR:-/tmp}/side_by_side.XXXXXX")"
trap 'rm -rf "$out"' EXIT

# centridem bench ... -> its particle_steps_per_s
centridem_run() { # cores, args...
  local cores="$1"; shift
  taskset -c "$cores" "$bin" bench "${pk[@]}" "$@" | tee "$out/last" | awk '/^particle_steps_per_s:/{print $2}'
}
# The last run's wait for the slowest thread (both passes' wait_share summed; nan from a build
# that does not print it).
last_wait() { awk '/^wait_share_/{s += $2; n++} END{print n ? s : "nan"}' "$out/last"; }
peer_run() { # steps warmup codes -> one value per code, in order
  taskset -c 0 bash "$here/run_peers.sh" "${pk[@]}" --steps "$1" --warmup "$2" --codes "$3" \
    --procs 1 2>/dev/null | sed -E 's/.*particle_steps_per_s=([^ ]+).*/\1/'
}
rec() { # key round value
  [ -n "$3" ] || { echo "side_by_side.sh: round $2: the run for '$1' gave no particle_steps_per_s (run it alone to see why)" >&2; exit 1; }
  echo "$1 $2 $3" >>"$out/values"
  echo "round $2: $1 = $3"
}

echo "side_by_side.sh: $(date -u '+%F %T') UTC, $bin, $rounds rounds, load $(cut -d' ' -f1-3 /proc/loadavg)"
echo "side_by_side.sh: $("$bin" bench "${pk[@]}" --steps 1 --warmup 0 --threads 1 | grep -E '^(cpu|simd):' | paste -sd' ')"
# shellcheck source=bench/cpu_others.sh
source "$here/cpu_others.sh"
cpu_others_start
for r in $(seq 1 "$rounds"); do
  rec c1 "$r" "$(centridem_run 0 --law peers --threads 1 --steps "$psteps")"
  rec c1s "$r" "$(centridem_run 0 --law peers --threads 1 --steps "$psteps" --skin 5e-5)"
  rec c2 "$r" "$(centridem_run 0,1 --law peers --threads 2 --steps "$psteps")"
  rec c2w "$r" "$(last_wait)"
  rec c2s "$r" "$(centridem_run 0,1 --law peers --threads 2 --steps "$psteps" --skin 5e-5)"
  rec c2sw "$r" "$(last_wait)"
  rec paper "$r" "$(centridem_run 0 --law paper --threads 1 --steps "$psteps")"
  mapfile -t pv < <(peer_run "$psteps" 200 "liggghts_rolling lammps")
  rec liggghts "$r" "${pv[0]}"
  rec lammps "$r" "${pv[1]}"
done
for r in $(seq 1 "$rounds"); do
  rec f1 "$r" "$(centridem_run 0 --law peers --workload flowing --threads 1 --steps "$fsteps" --warmup 0)"
  rec f1s "$r" "$(centridem_run 0 --law peers --workload flowing --threads 1 --steps "$fsteps" --warmup 0 --skin 5e-5)"
  rec lammps_flow "$r" "$(peer_run "$fsteps" 0 lammps_flow)"
done

python3 - "$out/values" "$rounds" <<'PY'
import sys, statistics as st
vals = {}
for line in open(sys.argv[1]):
    k, r, v = line.split()
    vals.setdefault(k, {})[int(r)] = float(v)
R = range(1, int(sys.argv[2]) + 1)
def row(k): return [vals[k][r] for r in R]
def show(x): return f"{st.median(x):.3e} (" + ", ".join(f"{v:.3g}" for v in x) + ")"
def ratio(x): return f"**{st.median(x):.2f}** (" + ", ".join(f"{v:.2f}" for v in x) + ")"
peer = [max(vals["liggghts"][r], vals["lammps"][r]) for r in R]
print("\n| workload | centridem, default skin | centridem, `--skin 5e-5` | LIGGGHTS 1 process | LAMMPS 1 process | ratio to the faster peer per core (default / 5e-5), or 1 -> 2 thread speed-up |")
print("|---|---|---|---|---|---|")
print(f"| peers' law, packed, 1 thread | {show(row('c1'))} | {show(row('c1s'))} | {show(row('liggghts'))} | {show(row('lammps'))} | "
      f"{ratio([vals['c1'][r] / p for r, p in zip(R, peer)])} / {ratio([vals['c1s'][r] / p for r, p in zip(R, peer)])} |")
print(f"| peers' law, packed, 2 threads | {show(row('c2'))} | {show(row('c2s'))} | | | "
      f"{ratio([vals['c2'][r] / vals['c1'][r] for r in R])} / {ratio([vals['c2s'][r] / vals['c1s'][r] for r in R])} |")
print(f"| peers' law, packed, 2 threads: share of the time the threads waited for the slowest | "
      + " | ".join(f"{st.median(row(k)):.4f} (" + ", ".join(f"{v:.4f}" for v in row(k)) + ")" for k in ("c2w", "c2sw"))
      + " | | | |")
print(f"| paper's law, packed, 1 thread | {show(row('paper'))} | | | | |")
print(f"| flowing column, 1 core | {show(row('f1'))} | {show(row('f1s'))} | | {show(row('lammps_flow'))} | "
      f"{ratio([vals['f1'][r] / vals['lammps_flow'][r] for r in R])} / {ratio([vals['f1s'][r] / vals['lammps_flow'][r] for r in R])} |")
PY
cpu_others_report side_by_side.sh
echo "side_by_side.sh: done $(date -u '+%F %T') UTC"
