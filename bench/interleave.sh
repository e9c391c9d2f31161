#!/usr/bin/env bash
# Two or more centridem builds measured in alternating rounds on the same core(s), so that the
# machine's slow spells fall on every build alike: one line per run, then each build's median and
# its ratio to the first build, paired by round (the "before/after" tables of
# docs/results/bench.md). Even rounds run the builds in reverse order (A B, B A, A B, ...), so a
# machine slowing or speeding up through a round favours neither. From 5 rounds on, each ratio
# comes with a 90 % interval of the paired median (2,000 bootstrap resamples of the rounds, a
# fixed seed): a difference is shown only when the interval excludes 1.
#
# Usage:  bash bench/interleave.sh [--cores 0] [--rounds 4] BIN_A BIN_B [...] -- BENCH ARGS
#   e.g.  bash bench/interleave.sh /tmp/before/build/centridem ./build/centridem -- \
#           --law peers --threads 1 --steps 2000
#         bash bench/interleave.sh --cores 0,1 A B -- --law peers --threads 2 --steps 2000
#         bash bench/interleave.sh A B -- --law peers --workload flowing --threads 1 --steps 10000 --warmup 0
# (one thread count per run: without --threads the flowing workload runs 1 and 2 and prints both).
# Build the "before" from another commit with `git worktree add /tmp/before <rev>` and `make
# build` there (the profile and link-time optimisation as `make build` gives them).
set -euo pipefail

cores=0
rounds=4
bins=()
while [ $# -gt 0 ]; do
  case "$1" in
    --cores) cores="$2"; shift 2 ;;
    --rounds) rounds="$2"; shift 2 ;;
    --) shift; break ;;
    -h|--help) sed -n '2,14p' "${BASH_SOURCE[0]}" | sed 's/^# \{0,1\}//'; exit 0 ;;
    *) bins+=("$1"); shift ;;
  esac
done
case "$rounds" in ''|*[!0-9]*|0) echo "interleave.sh: --rounds needs a positive integer, got '$rounds'" >&2; exit 2 ;; esac
[[ $cores =~ ^[0-9]+([,-][0-9]+)*$ ]] || { echo "interleave.sh: --cores needs a CPU list such as 0 or 0,1 or 0-1 (taskset -c), got '$cores'" >&2; exit 2; }
[ "${#bins[@]}" -ge 2 ] || { echo "interleave.sh: give at least two centridem binaries, then -- and the bench arguments" >&2; exit 2; }
for b in "${bins[@]}"; do
  [ -x "$b" ] || { echo "interleave.sh: '$b' is not an executable" >&2; exit 2; }
done

vals="$(mktemp)"
trap 'rm -f "$vals"' EXIT
# shellcheck source=bench/cpu_others.sh
source "$(dirname "${BASH_SOURCE[0]}")/cpu_others.sh"
echo "interleave.sh: $(date -u '+%F %T') UTC, cores $cores, $rounds rounds, bench $*"
cpu_others_start
for r in $(seq 1 "$rounds"); do
  order=("${!bins[@]}")
  if [ $((r % 2)) -eq 0 ]; then mapfile -t order < <(printf '%s\n' "${order[@]}" | tac); fi
  for i in "${order[@]}"; do
    v="$(taskset -c "$cores" "${bins[$i]}" bench "$@" | awk '/^particle_steps_per_s:/{print $2}')"
    [ -n "$v" ] || { echo "interleave.sh: '${bins[$i]} bench $*' gave no particle_steps_per_s" >&2; exit 1; }
    [ "$(wc -l <<<"$v")" -eq 1 ] || { echo "interleave.sh: '${bins[$i]} bench $*' gave $(wc -l <<<"$v") figures (one run per thread count?); give --threads" >&2; exit 2; }
    echo "round $r: ${bins[$i]} $v"
    echo "$i $r $v" >>"$vals"
  done
done
python3 - "$vals" "${bins[@]}" <<'PY'
import random, sys, statistics as st
v = {}
for line in open(sys.argv[1]):
    i, r, x = line.split()
    v.setdefault(int(i), {})[int(r)] = float(x)
names = sys.argv[2:]
for i, n in enumerate(names):
    m = st.median(v[i].values())
    if i == 0:
        print(f"{n}: median {m:.4g} particle-steps/s")
    else:
        q = [v[i][r] / v[0][r] for r in sorted(v[0])]
        ci = ""
        if len(q) >= 5:
            rng = random.Random(1)
            b = sorted(st.median(rng.choices(q, k=len(q))) for _ in range(2000))
            ci = f" [90 %: x{b[100]:.3f} to x{b[1899]:.3f}]"
        print(f"{n}: median {m:.4g}; / first, paired by round: x{st.median(q):.3f}{ci} (" +
              ", ".join(f"{x:.3f}" for x in q) + ")")
PY
cpu_others_report interleave.sh
