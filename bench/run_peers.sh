#!/usr/bin/env bash
# Peer-code benchmark: LAMMPS and LIGGGHTS (Debian 12 packages `lammps`, `liggghts`) on the
# benchmark packing, 1 and 2 MPI processes, one line per run:
#   code=<name> model=<desc> procs=<n> steps=<N> particles=<P> wall_s=<t>
#     particle_steps_per_s=<v> contacts_per_particle=<c>
# wall_s is the loop time of the timed `run` reported by the code itself (after a warm-up run),
# so start-up, reading the data file and the contact count afterwards are not included.
#
# Usage (from the repo root):  bash bench/run_peers.sh [--steps N] [--packing FILE]
#   [--warmup N] [--procs "1 2"] [--codes "lammps liggghts_rolling liggghts_cohesion"]
#   (code lammps_flow: the flowing workload, bench/peers/lammps_flow.in; give it --steps 100000
#   --warmup 0 to match `centridem bench --workload flowing --law peers --steps 100000 --warmup 0`)
#   [--repeat R] [--workdir DIR] [--keep]
# Install the peers first:  apt-get update && apt-get install -y lammps liggghts
# Environment: PEER_MPIRUN_ARGS (default "--bind-to none"), PEER_TIMEOUT_S (default 900).
# See bench/peers/NOTES.md for the models and how they differ from centridem's.
set -euo pipefail

here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
repo="$(cd "$here/.." && pwd)"
peers="$here/peers"

steps=5000
warmup=200
packing=""
procs_list="1 2"
codes="lammps liggghts_rolling liggghts_cohesion"
repeat=1
workdir=""
keep=0

usage() { sed -n '2,16p' "${BASH_SOURCE[0]}" | sed 's/^# \{0,1\}//'; }

while [ $# -gt 0 ]; do
  case "$1" in
    --steps) steps="$2"; shift 2 ;;
    --steps=*) steps="${1#*=}"; shift ;;
    --packing) packing="$2"; shift 2 ;;
    --packing=*) packing="${1#*=}"; shift ;;
    --warmup) warmup="$2"; shift 2 ;;
    --warmup=*) warmup="${1#*=}"; shift ;;
    --procs) procs_list="$2"; shift 2 ;;
    --procs=*) procs_list="${1#*=}"; shift ;;
    --codes) codes="$2"; shift 2 ;;
    --codes=*) codes="${1#*=}"; shift ;;
    --repeat) repeat="$2"; shift 2 ;;
    --repeat=*) repeat="${1#*=}"; shift ;;
    --workdir) workdir="$2"; keep=1; shift 2 ;;
    --workdir=*) workdir="${1#*=}"; keep=1; shift ;;
    --keep) keep=1; shift ;;
    -h|--help) usage; exit 0 ;;
    *) echo "run_peers.sh: unknown argument '$1'" >&2; usage >&2; exit 2 ;;
  esac
done

for v in "$steps" "$warmup" "$repeat"; do
  case "$v" in ''|*[!0-9]*) echo "run_peers.sh: --steps/--warmup/--repeat need integers" >&2; exit 2 ;; esac
done

# default packing: shared/bench beside the repo (as CI and the developers have it)
if [ -z "$packing" ]; then
  for cand in "$repo/../shared/bench/packing_30k.xyzr" "$repo/shared/bench/packing_30k.xyzr" \
              "/work/shared/bench/packing_30k.xyzr"; do
    if [ -f "$cand" ]; then packing="$cand"; break; fi
  done
fi
if [ -z "$packing" ] || [ ! -f "$packing" ]; then
  echo "run_peers.sh: packing file not found (give --packing FILE)" >&2; exit 2
fi
packing="$(cd "$(dirname "$packing")" && pwd)/$(basename "$packing")"

if [ -z "$workdir" ]; then
  workdir="$(mktemp -d "${TMPDIR:-/tmp}/centridem_peers.XXXXXX")"
else
  mkdir -p "$workdir"
fi
workdir="$(cd "$workdir" && pwd)"
if [ "$keep" -eq 0 ]; then trap 'rm -rf "$workdir"' EXIT; fi

export OMP_NUM_THREADS=1
mpirun_args=(${PEER_MPIRUN_ARGS:---bind-to none})
timeout_s="${PEER_TIMEOUT_S:-900}"
if [ "$(id -u)" -eq 0 ]; then mpirun_args+=(--allow-run-as-root); fi
# quiet Open MPI in containers (no high-speed interconnect, shared-memory single copy off)
export OMPI_MCA_btl_vader_single_copy_mechanism=none
export OMPI_MCA_btl="self,vader"

python3 "$peers/xyzr_to_data.py" "$packing" "$workdir/packing.data" >&2

have_mpirun=1
command -v mpirun >/dev/null 2>&1 || have_mpirun=0

# code name -> binary, input script, model description
code_bin() {
  case "$1" in
    lammps|lammps_flow) echo lmp ;;
    liggghts_*) echo liggghts ;;
  esac
}
code_in() {
  case "$1" in
    lammps) echo "$peers/lammps_granular.in" ;;
    lammps_flow) echo "$peers/lammps_flow.in" ;;
    liggghts_rolling) echo "$peers/liggghts_rolling.in" ;;
    liggghts_cohesion) echo "$peers/liggghts_cohesion.in" ;;
  esac
}
code_model() {
  case "$1" in
    lammps) echo "granular:hooke+linear_history+rolling_sds" ;;
    lammps_flow) echo "flowing:granular:hooke+linear_history+rolling_sds" ;;
    liggghts_rolling) echo "gran:hooke/stiffness+history+rolling_friction_epsd2" ;;
    liggghts_cohesion) echo "gran:hooke/stiffness+history+cohesion_sjkr+rolling_friction_epsd2" ;;
  esac
}
code_label() {
  case "$1" in
    lammps|lammps_flow) echo "lammps" ;;
    liggghts_*) echo "liggghts" ;;
  esac
}

nok=0
nfail=0
for code in $codes; do
  bin="$(code_bin "$code")"; inp="$(code_in "$code")"
  if [ -z "$bin" ] || [ -z "$inp" ]; then
    echo "run_peers.sh: unknown code '$code'" >&2; nfail=$((nfail + 1)); continue
  fi
  if ! command -v "$bin" >/dev/null 2>&1; then
    echo "run_peers.sh: '$bin' not found; install with: apt-get install -y lammps liggghts" >&2
    nfail=$((nfail + 1)); continue
  fi
  for np in $procs_list; do
    for rep in $(seq 1 "$repeat"); do
      tag="${code}_np${np}_r${rep}"
      log="$workdir/$tag.log"
      cmd=("$bin" -in "$inp" -var data "$workdir/packing.data" -var nsteps "$steps"
           -var nwarm "$warmup" -log "$log")
      if [ "$have_mpirun" -eq 1 ]; then
        cmd=(mpirun "${mpirun_args[@]}" -x OMP_NUM_THREADS -np "$np" "${cmd[@]}")
      elif [ "$np" -ne 1 ]; then
        echo "run_peers.sh: mpirun not found, skipping procs=$np" >&2; continue
      fi
      echo "run_peers.sh: [$tag] ${cmd[*]}" >&2
      if [ -r /proc/loadavg ]; then
        echo "run_peers.sh: [$tag] load average before: $(cut -d' ' -f1-3 /proc/loadavg)" >&2
      fi
      if ! (cd "$workdir" && timeout "$timeout_s" "${cmd[@]}" >"$workdir/$tag.screen" 2>&1); then
        echo "run_peers.sh: [$tag] failed; last lines of $workdir/$tag.screen:" >&2
        tail -n 15 "$workdir/$tag.screen" >&2 || true
        nfail=$((nfail + 1)); keep=1; trap - EXIT; continue
      fi
      # 2nd "Loop time" line = the timed run (1st is the warm-up)
      loop="$(grep -a '^Loop time of' "$log" | sed -n 2p || true)"
      if [ -z "$loop" ]; then
        echo "run_peers.sh: [$tag] no timed loop in $log" >&2; nfail=$((nfail + 1)); continue
      fi
      read -r wall lprocs lsteps latoms <<<"$(echo "$loop" |
        sed -E 's/^Loop time of ([^ ]+) on ([0-9]+) procs for ([0-9]+) steps with ([0-9]+) atoms.*/\1 \2 \3 \4/')"
      cpp="$(grep -a '^CONTACTS_PER_PARTICLE' "$log" | head -n 1 | awk '{print $2}' || true)"
      [ -n "$cpp" ] || cpp="NA"
      [ "$cpp" = "NA" ] || cpp="$(awk -v c="$cpp" 'BEGIN{printf "%.3f", c}')"
      awk -v code="$(code_label "$code")" -v model="$(code_model "$code")" -v np="$lprocs" \
          -v st="$lsteps" -v na="$latoms" -v w="$wall" -v c="$cpp" 'BEGIN{
            printf "code=%s model=%s procs=%d steps=%d particles=%d wall_s=%.4g particle_steps_per_s=%.3e contacts_per_particle=%s\n",
                   code, model, np, st, na, w, na*st/w, c }'
      nok=$((nok + 1))
    done
  done
done

if [ "$keep" -eq 1 ]; then echo "run_peers.sh: logs kept in $workdir" >&2; fi
if [ "$nok" -eq 0 ] || [ "$nfail" -gt 0 ]; then exit 1; fi
