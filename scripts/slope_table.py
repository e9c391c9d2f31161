#!/usr/bin/env python3
"""One markdown table row per trial level of `centridem slope` run folders.

Usage: python3 scripts/slope_table.py RUN_DIR [RUN_DIR ...]

Reads RUN_DIR/trial_*/result.json (and RUN_DIR/scenario.toml for s) and prints: run, s, g-level,
state, onset, time of the level, start zone, particles sliding and volume share, mean and largest
displacement of the sliding mass (DEM mm), benches crossed, runout (model mm), particles in the
foundation and the slope, wall time and throughput. Standard library only.
"""
import glob
import json
import os
import re
import sys


def scale_of(run_dir):
    try:
        with open(os.path.join(run_dir, "scenario.toml"), encoding="utf-8") as f:
            m = re.search(r"^size_reduction_factor\s*=\s*([0-9.eE+-]+)", f.read(), re.M)
            return float(m.group(1)) if m else float("nan")
    except OSError:
        return float("nan")


def rows(run_dir):
    s = scale_of(run_dir)
    for path in sorted(glob.glob(os.path.join(run_dir, "trial_*", "result.json")),
                       key=lambda p: float(re.search(r"trial_([0-9.]+)g", p).group(1))):
        with open(path, encoding="utf-8") as f:
            r = json.load(f)
        for lv in r["levels"]:
            failed = lv["state"] == "failed"
            yield "| {} | {:g} | {:g} | {}{} | {} | {:.4f} | {} | {} | {} | {} | {} | {:,} / {:,} | {:.1f} min | {:.2e} |".format(
                os.path.basename(os.path.normpath(run_dir)), s, lv["g_level"], lv["state"],
                " (time limit)" if lv.get("time_limit") else "",
                "{:.4f}".format(lv["onset_time_s"]) if failed and lv.get("onset_time_s") is not None else "–",
                lv["level_time_s"],
                lv.get("start_zone") or "–" if failed else "–",
                "{:,} ({:.1f} %)".format(lv["particles"], 100 * lv["volume_share"]) if failed else "–",
                "{:.2f} / {:.2f}".format(1e3 * lv["mean_displacement_m"], 1e3 * lv["max_displacement_m"]),
                ",".join(str(b) for b in lv["benches_crossed"]) if failed else "–",
                "{:.1f}".format(1e3 * lv["runout_model_m"]) if failed else "–",
                r["foundation"]["particles"], r["slope_particles"], r["wall_seconds"] / 60,
                r["particle_steps_per_s"])


def main(argv):
    if len(argv) < 2:
        print(__doc__.strip(), file=sys.stderr)
        return 2
    print("| run | s | g | state | onset (s) | level time (s) | starts at | sliding particles (vol.) "
          "| mass displacement mean / max (mm) | benches | runout (model mm) | foundation / slope "
          "particles | wall | particle-steps/s |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|")
    for d in argv[1:]:
        for row in rows(d):
            print(row)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
