#!/usr/bin/env python3
"""Markdown table rows of `bpm hertz` results: one row per hertz.json.

    scripts/hertz-table.py results/hertz/*/hertz.json
    scripts/hertz-table.py --pool results/hertz/sweep-smoother-R20*/R20-*/hertz.json

Columns: folder, a_B, nu, E_eff, squeezes, the ensemble mean's relative rms
deviation from Hertz over delta/R in [0.02, 0.25] and log-log slope, and the
mean's deviation from Hertz at delta/R = 0.05, 0.10, ..., 0.25 (read off the
ensemble grid, step 0.0025).

With --pool, the files of one a_B (several grains, say) are pooled into one
row: at each grid point the means weighted by their squeeze counts, then
the same columns, the rms and slope computed as `bpm hertz` does
(src/analysis/hertz.rs, `hertz_deviation`: points with a positive mean in
the window, Hertz = (delta/R)^(3/2)).
"""
import json
import math
import sys

POINTS = [0.05, 0.10, 0.15, 0.20, 0.25]
WINDOW = (0.02, 0.25)


def deviation(overlap, mean):
    window = [(d, f) for d, f in zip(overlap, mean)
              if f is not None and WINDOW[0] <= d <= WINDOW[1] and f > 0.0]
    if len(window) < 3:
        return float("nan"), float("nan")
    rms = math.sqrt(sum((f / d ** 1.5 - 1.0) ** 2 for d, f in window) / len(window))
    lx = [math.log(d) for d, _ in window]
    ly = [math.log(f) for _, f in window]
    mx, my = sum(lx) / len(lx), sum(ly) / len(ly)
    sxx = sum((x - mx) ** 2 for x in lx)
    slope = sum((x - mx) * (y - my) for x, y in zip(lx, ly)) / sxx
    return rms, slope


def cells(overlap, mean):
    out = []
    for p in POINTS:
        k = min(range(len(overlap)), key=lambda i: abs(overlap[i] - p))
        m = mean[k]
        out.append("" if m is None else f"{100 * (m / p ** 1.5 - 1):+.1f}%")
    return out


def row(name, a_b, nu, e_eff, squeezes, rms, slope, overlap, mean):
    return (f"| {name} | {a_b} | {nu:.2f} | {e_eff:.3f} | {squeezes} "
            f"| {100 * rms:.1f}% | {slope:.3f} | " + " | ".join(cells(overlap, mean)) + " |")


pool = sys.argv[1:2] == ["--pool"]
paths = sys.argv[2:] if pool else sys.argv[1:]
print("| run | a_B | nu | E_eff | squeezes | rel. rms | slope | "
      + " | ".join(f"{p:.2f}" for p in POINTS) + " |")
print("| --- " * (7 + len(POINTS)) + "|")
runs = []
for path in paths:
    with open(path) as f:
        runs.append((path, json.load(f)))
if not pool:
    for path, r in runs:
        e = r["ensemble"]
        dev = e["deviation"] or {}
        name = path.rsplit("/", 2)[-2]
        print(row(name, r["options"]["a_b"], r["options"]["moduli"]["nu"], r["e_eff"],
                  len(r["squeezes"]), dev.get("rms_relative", float("nan")),
                  dev.get("loglog_slope", float("nan")), e["overlap_over_r"], e["mean"]))
    sys.exit(0)
for a_b in sorted({r["options"]["a_b"] for _, r in runs}):
    group = [(p, r) for p, r in runs if r["options"]["a_b"] == a_b]
    overlap = group[0][1]["ensemble"]["overlap_over_r"]
    if any(r["ensemble"]["overlap_over_r"] != overlap for _, r in group):
        sys.exit(f"a_B = {a_b}: the ensembles' grids differ; cannot pool")
    mean = []
    for k in range(len(overlap)):
        terms = [(r["ensemble"]["mean"][k], r["ensemble"]["count"][k]) for _, r in group
                 if r["ensemble"]["mean"][k] is not None and r["ensemble"]["count"][k] > 0]
        weight = sum(c for _, c in terms)
        mean.append(sum(m * c for m, c in terms) / weight if weight > 0 else None)
    rms, slope = deviation(overlap, mean)
    first = group[0][1]
    name = "pooled: " + ", ".join(p.rsplit("/", 3)[-3] for p, _ in group)
    print(row(name, a_b, first["options"]["moduli"]["nu"], first["e_eff"],
              sum(len(r["squeezes"]) for _, r in group), rms, slope, overlap, mean))
