#!/usr/bin/env python3
"""One markdown table row per finished pressure of `centridem shear` run folders.

Usage: python3 scripts/shear_table.py RUN_DIR [RUN_DIR ...]

Reads RUN_DIR/shear_<kPa>kPa.json and prints: run, target and consolidated normal stress (kPa),
consolidated height (mm), consolidated porosity, peak (kPa, angle), strain at the peak, residual (kPa, angle), worst
normal-stress deviation while shearing, particles lost, consolidation + shear steps, wall time and
throughput. Standard library only.
"""
import json, glob, os, sys, math
print('| run | σn target (kPa) | σn consolidated (kPa) | height (mm) | porosity | peak τ (kPa) | strain at peak | residual τ (kPa) | worst σn deviation | lost | steps | wall | particle-steps/s |')
print('|---|---|---|---|---|---|---|---|---|---|---|---|---|')
for d in sys.argv[1:]:
    for f in sorted(glob.glob(os.path.join(d, 'shear_*kPa.json')), key=lambda p: float(p.split('_')[-1][:-8])):
        j = json.load(open(f))
        print("| {} | {:g} | {:.1f} | {:.2f} | {} | {:.1f} ({:.1f}°) | {:.3f} | {:.1f} ({:.1f}°) | {:.2f} % | {} | {:,} + {:,} | {:.0f} min | {:.2e} |".format(
            os.path.basename(d), j['normal_stress_target_Pa']/1e3, j['consolidated_normal_stress_Pa']/1e3,
            j['consolidated_height_m']*1e3,
            '{:.3f}'.format(j['consolidated_porosity']) if 'consolidated_porosity' in j else '–',
            j['peak_shear_stress_Pa']/1e3, j['peak_friction_angle_deg'], j['peak_strain'],
            j['residual_shear_stress_Pa']/1e3, j['residual_friction_angle_deg'], 100*j['worst_normal_stress_deviation'],
            j['particles_lost'], j['consolidation_steps'], j['shear_steps'], j['wall_seconds']/60, j['particle_steps_per_s']))
