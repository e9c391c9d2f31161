#!/usr/bin/env bash
# Does the ratio to the peer depend on how fast the host runs? Rounds of one centridem run and one
# LIGGGHTS run on the same core (peers' law, packed, 1 thread; the order alternating round by
# round), then the slope of log(centridem) against log(LIGGGHTS) across the rounds, with a 90 %
# bootstrap interval (2,000 resamples, a fixed seed) and the reverse regression's slope. A slope
# of 1: both codes follow the host's slow spells alike, so the ratio does not depend on when a
# window is taken; above 1: centridem slows more in them. The least-squares slope is pulled
# towards 0 by LIGGGHTS's own scatter, the reverse one away from it by centridem's: the true
# value lies between the two. Also the paired ratio's median, and in the slower and faster half
# of the rounds (split by LIGGGHTS's rate). docs/results/bench.md, the thirteenth session's
# section, has a run of it.
#
# Usage:  bash bench/host_sensitivity.sh [--core 0] [--rounds 24] [--steps 1000] BIN
#   e.g.  bash bench/host_sensitivity.sh --rounds 30 ./build/centridem
# Needs LIGGGHTS (apt-get install -y liggghts) and the shared packing (bench/run_peers.sh).
set -euo pipefail

here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
core=0
rounds=24
steps=1000
bin=""
while [ $# -gt 0 ]; do
  case "$1" in
    --core) core="$2"; shift 2 ;;
    --rounds) rounds="$2"; shift 2 ;;
    --steps) steps="$2"; shift 2 ;;
    -h|--help) sed -n '2,15p' "${BASH_SOURCE[0]}" | sed 's/^# \{0,1\}//'; exit 0 ;;
    -*) echo "host_sensitivity.sh: unknown option '$1'" >&2; exit 2 ;;
    *) bin="$1"; shift ;;
  esac
done
for v in "$core" "$rounds" "$steps"; do
  case "$v" in ''|*[!0-9]*) echo "host_sensitivity.sh: --core/--rounds/--steps need whole numbers" >&2; exit 2 ;; esac
done
if [ -z "$bin" ] || [ ! -x "$bin" ]; then
  echo "host_sensitivity.sh: give the centridem binary to measure (got '${bin}')" >&2; exit 2
fi
if [ "$rounds" -lt 4 ]; then echo "host_sensitivity.sh: --rounds must be at least 4" >&2; exit 2; fi

run_c() {
  taskset -c "$core" "$bin" bench --law peers --threads 1 --steps "$steps" 2>/dev/null |
    awk '/^particle_steps_per_s:/ {print $2}'
}
run_l() {
  taskset -c "$core" bash "$here/run_peers.sh" --codes liggghts_rolling --procs 1 \
    --steps "$steps" --warmup 50 2>/dev/null | sed -n 's/.*particle_steps_per_s=\([^ ]*\).*/\1/p'
}

out="$(mktemp)"
trap 'rm -f "$out"' EXIT
for r in $(seq "$rounds"); do
  if [ $((r % 2)) -eq 1 ]; then c="$(run_c)"; l="$(run_l)"; else l="$(run_l)"; c="$(run_c)"; fi
  if [ -z "$c" ] || [ -z "$l" ]; then
    echo "host_sensitivity.sh: round $r gave no rate (centridem '$c', LIGGGHTS '$l')" >&2; exit 3
  fi
  echo "round $r $(date -u +%H:%M:%S): centridem $c LIGGGHTS $l" | tee -a "$out"
done

python3 - "$out" <<'EOF'
import math, random, statistics as st, sys
C, L = [], []
for line in open(sys.argv[1]):
    f = line.split()  # round R HH:MM:SS: centridem C LIGGGHTS L
    C.append(float(f[4]))
    L.append(float(f[6]))
lc, ll = [math.log(x) for x in C], [math.log(x) for x in L]
n = len(C)
slope = st.linear_regression(ll, lc).slope
reverse = 1.0 / st.linear_regression(lc, ll).slope
random.seed(1)
boot = []
for _ in range(2000):
    idx = [random.randrange(n) for _ in range(n)]
    x = [ll[i] for i in idx]
    if max(x) > min(x):
        boot.append(st.linear_regression(x, [lc[i] for i in idx]).slope)
boot.sort()
lo, hi = boot[len(boot) // 20], boot[len(boot) - 1 - len(boot) // 20]
ratio = [c / l for c, l in zip(C, L)]
by_l = sorted(zip(L, ratio))
h = n // 2
print(f"rounds {n}: centridem {min(C):.3g}-{max(C):.3g}, LIGGGHTS {min(L):.3g}-{max(L):.3g} "
      f"particle-steps/s; correlation of the logs {st.correlation(lc, ll):.2f}")
print(f"slope of log(centridem) on log(LIGGGHTS) {slope:.2f} (90 % {lo:.2f}-{hi:.2f}); "
      f"reverse regression {reverse:.2f}")
print(f"paired ratio median {st.median(ratio):.2f} (range {min(ratio):.2f}-{max(ratio):.2f}); "
      f"slower half {st.median(r for _, r in by_l[:h]):.2f}, "
      f"faster half {st.median(r for _, r in by_l[h:]):.2f}")
EOF
