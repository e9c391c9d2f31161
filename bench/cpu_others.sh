# shellcheck shell=bash
# Sourced by bench/interleave.sh and bench/side_by_side.sh: how much CPU the rest of the machine
# used while they measured. A ratio measured beside another load can be wrong in every round
# alike (2026-12-06: x1.053 beside a CI compile, x1.009 on the quiet machine, the same two
# binaries; docs/results/bench.md), so each script says at the end whether it ran alone.
#
#   cpu_others_start            before the first run
#   cpu_others_report NAME      after the last: one line, and a warning when others used more
#                               than 5 % of one core, or the hypervisor stole more than 5 %
#
# Busy time is /proc/stat's user + nice + system + irq + softirq over all CPUs; the script's own
# runs are its waited-for children (/proc/$$/stat cutime + cstime), taken away from it. Steal is
# the time the hypervisor gave the vCPUs to other guests.

cpu_others_busy_steal() { # -> "busy steal" in clock ticks, all CPUs
  awk '/^cpu /{print $2 + $3 + $4 + $7 + $8, $9}' /proc/stat
}
cpu_others_children() { # -> cutime + cstime of this shell, in clock ticks
  # Field 2 of /proc/PID/stat is "(comm)", which may hold spaces: count from after its ')'.
  sed 's/.*) //' "/proc/$$/stat" | awk '{print $14 + $15}'
}

cpu_others_start() {
  read -r _co_busy0 _co_steal0 < <(cpu_others_busy_steal)
  _co_child0="$(cpu_others_children)"
  _co_t0="$(date +%s.%N)"
}

cpu_others_report() { # NAME
  local busy1 steal1 child1 t1
  read -r busy1 steal1 < <(cpu_others_busy_steal)
  child1="$(cpu_others_children)"
  t1="$(date +%s.%N)"
  python3 - "$1" "$(getconf CLK_TCK)" "$_co_t0" "$t1" "$_co_busy0" "$busy1" "$_co_steal0" \
    "$steal1" "$_co_child0" "$child1" <<'PY'
import sys
name, hz = sys.argv[1], float(sys.argv[2])
t0, t1, b0, b1, s0, s1, c0, c1 = map(float, sys.argv[3:])
wall = max(t1 - t0, 1e-9)
others = max((b1 - b0) - (c1 - c0), 0.0) / hz  # CPU seconds not spent by our runs
steal = (s1 - s0) / hz
share, steal_share = others / wall, steal / wall
print(f"{name}: the rest of the machine used {others:.1f} CPU-s in {wall:.0f} s "
      f"({100 * share:.1f} % of one core); steal {100 * steal_share:.1f} %")
if share > 0.05 or steal_share > 0.05:
    print(f"{name}: WARNING: the runs were not alone on the machine; a ratio measured beside "
          "another load can be biased in every round alike: measure again when it is quiet")
PY
}
