#!/usr/bin/env python3
"""Convert an `x y z r` packing (metres, one sphere per line) into a LAMMPS /
LIGGGHTS data file for atom_style sphere (LAMMPS) or granular (LIGGGHTS).

Both codes read the same Atoms line layout:
    atom-ID atom-type diameter density x y z

The lateral box is the benchmark's wall box (default x, y in [0, 0.0126] m);
the box's lower z bound is the floor (z = 0) and the upper bound is the top of
the packing plus a margin (the input scripts use `boundary f f fm`, so the top
may still grow if a particle rises).

Standard library only.  Usage:
    python3 xyzr_to_data.py packing.xyzr out.data [--density 2633]
            [--lx 0.0126] [--ly 0.0126] [--ztop-margin 0.004]
Prints one summary line: particles, radius range, packing height.
"""
import argparse
import sys


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("packing")
    ap.add_argument("out")
    ap.add_argument("--density", type=float, default=2633.0)
    ap.add_argument("--lx", type=float, default=0.0126)
    ap.add_argument("--ly", type=float, default=0.0126)
    ap.add_argument("--ztop-margin", type=float, default=0.004)
    a = ap.parse_args(argv)

    spheres = []
    with open(a.packing) as f:
        for ln, line in enumerate(f, 1):
            s = line.split("#", 1)[0].split()
            if not s:
                continue
            if len(s) < 4:
                sys.exit("%s:%d: expected 'x y z r'" % (a.packing, ln))
            x, y, z, r = (float(v) for v in s[:4])
            if r <= 0.0:
                sys.exit("%s:%d: non-positive radius" % (a.packing, ln))
            spheres.append((x, y, z, r))
    if not spheres:
        sys.exit("no spheres in %s" % a.packing)

    n = len(spheres)
    rmin = min(s[3] for s in spheres)
    rmax = max(s[3] for s in spheres)
    ztop = max(s[2] + s[3] for s in spheres)
    bad = [i for i, (x, y, z, r) in enumerate(spheres)
           if not (0.0 < x < a.lx and 0.0 < y < a.ly and z > 0.0)]
    if bad:
        sys.exit("%d sphere centres lie outside the wall box (first: line %d)"
                 % (len(bad), bad[0] + 1))
    zhi = ztop + a.ztop_margin

    with open(a.out, "w") as o:
        o.write("centridem benchmark packing from %s (x y z r in m)\n\n" % a.packing)
        o.write("%d atoms\n1 atom types\n\n" % n)
        o.write("0.0 %.9e xlo xhi\n" % a.lx)
        o.write("0.0 %.9e ylo yhi\n" % a.ly)
        o.write("0.0 %.9e zlo zhi\n\n" % zhi)
        o.write("Atoms\n\n")
        for i, (x, y, z, r) in enumerate(spheres, 1):
            o.write("%d 1 %.9e %.6g %.9e %.9e %.9e\n" % (i, 2.0 * r, a.density, x, y, z))
    print("xyzr_to_data: particles=%d rmin=%.4e rmax=%.4e top=%.4e zhi=%.4e -> %s"
          % (n, rmin, rmax, ztop, zhi, a.out))


if __name__ == "__main__":
    main()
