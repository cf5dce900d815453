#!/usr/bin/env python3
"""Markdown table rows of `bpm hertz` results: one row per hertz.json.

    scripts/hertz-table.py results/hertz/*/hertz.json

Columns: folder, a_B, nu, E_eff, squeezes, the ensemble mean's relative rms
deviation from Hertz over delta/R in [0.02, 0.25] and log-log slope, and the
mean's deviation from Hertz at delta/R = 0.05, 0.10, ..., 0.25 (read off the
ensemble grid, step 0.0025).
"""
import json
import sys

POINTS = [0.05, 0.10, 0.15, 0.20, 0.25]

print("| run | a_B | nu | E_eff | squeezes | rel. rms | slope | "
      + " | ".join(f"{p:.2f}" for p in POINTS) + " |")
print("| --- " * (7 + len(POINTS)) + "|")
for path in sys.argv[1:]:
    with open(path) as f:
        r = json.load(f)
    e = r["ensemble"]
    dev = e["deviation"] or {}
    cells = []
    for p in POINTS:
        k = min(range(len(e["overlap_over_r"])),
                key=lambda i: abs(e["overlap_over_r"][i] - p))
        m = e["mean"][k]
        cells.append("" if m is None else f"{100 * (m / p ** 1.5 - 1):+.1f}%")
    name = path.rsplit("/", 2)[-2]
    print(f"| {name} | {r['options']['a_b']} | {r['options']['moduli']['nu']:.2f} "
          f"| {r['e_eff']:.3f} | {len(r['squeezes'])} "
          f"| {100 * dev.get('rms_relative', float('nan')):.1f}% "
          f"| {dev.get('loglog_slope', float('nan')):.3f} | " + " | ".join(cells) + " |")
