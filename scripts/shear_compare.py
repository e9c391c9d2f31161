#!/usr/bin/env python3
"""Paired comparison of two `centridem shear` run folders (e.g. dry against humid sand).

Usage: python3 scripts/shear_compare.py DRY_DIR HUMID_DIR

For every normal pressure finished in both folders (shear_<kPa>kPa.json), prints as markdown:
1. peak and residual shear stress of each (kPa) and their differences;
2. the difference of the mean shear stress over six equal windows of the shear strain (from the
   shear_<kPa>kPa.csv curves);
3. the Mohr-Coulomb fits (tau = c + sigma tan(phi), least squares, as `centridem shear` fits
   them) of each folder's peaks and residuals over those common pressures. Least squares is
   linear, so the difference of the two fits is the fit of the differences.
With specimens packed the same way (docs/shear.md "Preparation") the differences are the effect
of what differs between the two scenarios alone.
Standard library only.
"""
import csv, glob, json, math, os, sys


def runs(d):
    out = {}
    for f in glob.glob(os.path.join(d, 'shear_*kPa.json')):
        j = json.load(open(f))
        j['csv_path'] = f[:-len('.json')] + '.csv'
        out[j['normal_stress_target_Pa']] = j
    return out


def fit(s, t):
    """c [Pa], phi [deg], R^2 of tau = c + sigma tan(phi); needs two pressures or more."""
    n = len(s)
    ms, mt = sum(s) / n, sum(t) / n
    sxx = sum((x - ms) ** 2 for x in s)
    sxt = sum((x - ms) * (y - mt) for x, y in zip(s, t))
    slope = sxt / sxx
    c = mt - slope * ms
    stt = sum((y - mt) ** 2 for y in t)
    sse = sum((y - c - slope * x) ** 2 for x, y in zip(s, t))
    return c, math.degrees(math.atan(slope)), 1 - sse / stt if stt > 0 else 1.0


def curve(j):
    """(shear strain, shear stress [Pa]) of a run's curve CSV."""
    with open(j['csv_path']) as f:
        rows = csv.DictReader(f)
        missing = {'shear_strain', 'shear_stress_Pa'} - set(rows.fieldnames or [])
        if missing:
            print('{}: no column {} (expected the header centridem shear writes)'.format(
                j['csv_path'], ', '.join(sorted(missing))), file=sys.stderr)
            sys.exit(2)
        return [(float(r['shear_strain']), float(r['shear_stress_Pa'])) for r in rows]


def window_means(c, edges):
    m = []
    for lo, hi in zip(edges, edges[1:]):
        v = [t for e, t in c if lo <= e < hi or (hi == edges[-1] and e == hi)]
        m.append(sum(v) / len(v) if v else float('nan'))
    return m


if len(sys.argv) != 3:
    sys.exit(__doc__)
a, b = runs(sys.argv[1]), runs(sys.argv[2])
common = sorted(set(a) & set(b))
if not common:
    sys.exit('no normal pressure finished in both {} and {}'.format(sys.argv[1], sys.argv[2]))
na, nb = os.path.basename(sys.argv[1].rstrip('/')), os.path.basename(sys.argv[2].rstrip('/'))
print('| σn (kPa) | peak τ {0} (kPa) | peak τ {1} (kPa) | Δ peak (kPa) | residual τ {0} (kPa) | '
      'residual τ {1} (kPa) | Δ residual (kPa) |'.format(na, nb))
print('|---|---|---|---|---|---|---|')
for s in common:
    pa, pb = a[s]['peak_shear_stress_Pa'], b[s]['peak_shear_stress_Pa']
    ra, rb = a[s]['residual_shear_stress_Pa'], b[s]['residual_shear_stress_Pa']
    print('| {:g} | {:.2f} | {:.2f} | {:+.2f} | {:.2f} | {:.2f} | {:+.2f} |'.format(
        s / 1e3, pa / 1e3, pb / 1e3, (pb - pa) / 1e3, ra / 1e3, rb / 1e3, (rb - ra) / 1e3))
print()



curves = {s: (curve(a[s]), curve(b[s])) for s in common}
final = min(min(ca[-1][0], cb[-1][0]) for ca, cb in curves.values())
edges = [final * k / 6 for k in range(7)]
print('Difference ({} − {}) of the mean τ over windows of the shear strain (kPa):'.format(nb, na))
print()
print('| σn (kPa) | ' + ' | '.join('{:.1f}–{:.1f} %'.format(100 * lo, 100 * hi)
                                    for lo, hi in zip(edges, edges[1:])) + ' |')
print('|---|' + '---|' * 6)
for s in common:
    ma, mb = (window_means(c, edges) for c in curves[s])
    print('| {:g} | '.format(s / 1e3) + ' | '.join('{:+.2f}'.format((y - x) / 1e3)
                                                    for x, y in zip(ma, mb)) + ' |')
print()
if len(common) < 2:
    print('one common pressure: no Mohr-Coulomb fit')
    sys.exit(0)
print('Mohr-Coulomb fits over the {} common pressures ({} kPa):'.format(
    len(common), ', '.join('{:g}'.format(s / 1e3) for s in common)))
for key in ('peak_shear_stress_Pa', 'residual_shear_stress_Pa'):
    fa = fit(common, [a[s][key] for s in common])
    fb = fit(common, [b[s][key] for s in common])
    print('- {:8s} {}: c = {:.2f} kPa, phi = {:.2f} deg, R^2 = {:.4f}; {}: c = {:.2f} kPa, phi = '
          '{:.2f} deg, R^2 = {:.4f}; difference: c {:+.2f} kPa, phi {:+.2f} deg'.format(
              key.split('_')[0], na, fa[0] / 1e3, fa[1], fa[2], nb, fb[0] / 1e3, fb[1], fb[2],
              (fb[0] - fa[0]) / 1e3, fb[1] - fa[1]))
