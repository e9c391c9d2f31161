#!/usr/bin/env python3
"""Test costs from a `make test` log (docs/results/tests.md "Longest tests first").

  python3 scripts/ctest_costs.py LOG                  # per pass: in declaration order vs longest first
  python3 scripts/ctest_costs.py LOG --pass 0 --write tests/ctest_costs_release.txt
  python3 scripts/ctest_costs.py LOG --pass 1 --write tests/ctest_costs_asan.txt

LOG is the output of `make test` (or `bash .ci/run`): pass 0 is the Release unit tests, pass 1 the
sanitizer run. The written file is ctest's own cost format (Testing/Temporary/CTestCostData.txt:
"NAME RUNS SECONDS" per line, then "---"), which the Makefile copies into a fresh build folder so
that ctest starts the longest tests first. The makespans replay the tests' own times on two workers
(ctest -j2), each test going to the worker that frees first.
"""
import argparse
import re


def passes(text):
    out = []
    for part in text.split("Test project ")[1:]:
        tests = {}
        for m in re.finditer(r"Test\s+#(\d+): (\S+) \.+\s+Passed\s+([\d.]+) sec", part):
            tests[int(m.group(1))] = (m.group(2), float(m.group(3)))
        out.append([tests[k] for k in sorted(tests)])
    return out


def makespan(seq, workers=2):
    w = [0.0] * workers
    for _, t in seq:
        i = w.index(min(w))
        w[i] += t
    return max(w)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("log")
    ap.add_argument("--pass", dest="which", type=int, default=None, help="0: Release, 1: sanitizers")
    ap.add_argument("--write", help="write the pass's costs in ctest's format to this file")
    a = ap.parse_args()
    all_passes = passes(open(a.log, encoding="utf-8", errors="replace").read())
    for k, tests in enumerate(all_passes):
        if a.which is not None and k != a.which:
            continue
        total = sum(t for _, t in tests)
        longest = sorted(tests, key=lambda x: -x[1])
        print(f"pass {k}: {len(tests)} tests, {total:.0f} s in all; two workers: "
              f"declaration order {makespan(tests):.0f} s, longest first {makespan(longest):.0f} s")
        if a.write:
            with open(a.write, "w", encoding="utf-8") as f:
                for name, t in tests:
                    f.write(f"{name} 1 {t}\n")
                f.write("---\n")
            print(f"wrote {a.write}")


if __name__ == "__main__":
    main()
