#!/usr/bin/env python3
"""The compaction size trend: phi_c and the pressure exponent against the
grain radius R, from folders written by `bpm compact`.

For every run it prints three estimates of the jamming point:
  - the study's own fit (phi_c and exponent free, `analysis::jamming`);
  - the bracket the states give: the last state with no force network
    (Z = 0) and the first with one;
  - phi_c with the exponent held at 3/2: (P/E)^(2/3) fitted linearly
    against phi over the jammed states within 0.1 of it;
  - the bracket's midpoint.
Then the weighted least-squares fit phi_c = phi_inf - b d/R of each
estimate over the runs with the most common grain number (each R weighted
by the standard error of its seeds' mean; an R with fewer than three seeds
takes the mean spread of the R that have three or more: the spread of two
values has one degree of freedom and can come out near 0 by chance, which
would give that R all the weight). Runs with other grain numbers are
listed beside the runs of their R with the common number, which separates
grain number from grain size.

    python3 scripts/size-trend.py results/compaction/native results/compaction/seeds \
        results/compaction/size-trend/R4 results/compaction/size-trend/R4-seed2 \
        results/compaction/size-trend/R6 results/compaction/size-trend/R6-seed2
"""

import json
import statistics
import sys


# Seeds an R needs for its own spread to weight it.
MIN_SEEDS_FOR_SPREAD = 3


def fixed_exponent_phi_c(states, exponent=1.5, window=0.1):
    """phi_c with P/E = A (phi - phi_c)^exponent, by a line through
    (P/E)^(1/exponent) against phi over the jammed states within `window`."""
    jammed = [(s["phi_mc"], s["p_over_e_eff"]) for s in states if s["z_force"] > 0]
    phi_c = jammed[0][0] - 0.01
    for _ in range(20):
        points = [(p, y ** (1.0 / exponent)) for p, y in jammed if p - phi_c <= window]
        n = len(points)
        mx = sum(p for p, _ in points) / n
        my = sum(y for _, y in points) / n
        sxy = sum((p - mx) * (y - my) for p, y in points)
        sxx = sum((p - mx) ** 2 for p, _ in points)
        slope = sxy / sxx
        new = mx - my / slope
        if abs(new - phi_c) < 1e-9:
            break
        phi_c = new
    return phi_c, n


def bracket(states):
    """The last state without a force network before the first with one."""
    below = None
    for s in states:
        if s["z_force"] > 0:
            return below, s["phi_mc"]
        below = s["phi_mc"]
    return below, None


def weighted_line(points):
    """phi_c = phi_inf - b / R through (R, phi_c, sd): phi_inf, b, their errors."""
    w = [1.0 / sd**2 for _, _, sd in points]
    x = [1.0 / r for r, _, _ in points]
    y = [p for _, p, _ in points]
    sw = sum(w)
    mx = sum(wi * xi for wi, xi in zip(w, x)) / sw
    my = sum(wi * yi for wi, yi in zip(w, y)) / sw
    sxx = sum(wi * (xi - mx) ** 2 for wi, xi in zip(w, x))
    slope = sum(wi * (xi - mx) * (yi - my) for wi, xi, yi in zip(w, x, y)) / sxx
    intercept = my - slope * mx
    err_slope = (1.0 / sxx) ** 0.5
    err_intercept = (1.0 / sw + mx**2 / sxx) ** 0.5
    return intercept, -slope, err_intercept, err_slope


def main(folders):
    runs = []
    for folder in folders:
        study = json.load(open(f"{folder}/compaction.json"))
        build = study["options"]["source"]["build"]
        radius, grains = build["radius"], build["grains"]
        for run in study["runs"]:
            fit = run["fits"]["pressure"]
            lo, hi = bracket(run["states"])
            fixed, points = fixed_exponent_phi_c(run["states"])
            runs.append(
                {
                    "R": radius,
                    "grains": grains,
                    "seed": run["seed"],
                    "particles": run["particles"],
                    "run_s": run["run_seconds"],
                    "fit": fit["phi_c"],
                    "exponent": fit["exponent"],
                    "error": fit.get("exponent_error", float("nan")),
                    "bracket": (lo, hi),
                    "fixed": fixed,
                    "midpoint": 0.5 * (lo + hi),
                    "fixed_points": points,
                    "folder": folder,
                }
            )
    print("| R (d) | grains | seed | particles | run s | phi_c (free fit) | P exponent | Z = 0 until | Z > 0 from | phi_c (exponent 3/2) |")
    print("| ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |")
    for r in sorted(runs, key=lambda r: (r["R"], r["grains"], r["seed"])):
        lo, hi = r["bracket"]
        print(
            f"| {r['R']:g} | {r['grains']} | {r['seed']} | {r['particles']:,} | {r['run_s']:.0f} | {r['fit']:.4f} | "
            f"{r['exponent']:.2f} +- {r['error']:.2f} | {lo:.4f} | {hi:.4f} | {r['fixed']:.4f} |"
        )
    counts = [r["grains"] for r in runs]
    common = max(set(counts), key=counts.count)
    others = [r for r in runs if r["grains"] != common]
    runs = [r for r in runs if r["grains"] == common]
    print(f"\nThe fits below take the {len(runs)} runs of {common} grains.")
    radii = sorted({r["R"] for r in runs})
    estimates = [("fit", "free fit"), ("fixed", "exponent 3/2"), ("midpoint", "bracket midpoint")]
    for key, name in estimates:
        by_r = {R: [r[key] for r in runs if r["R"] == R] for R in radii}
        spreads = [statistics.stdev(v) for v in by_r.values() if len(v) >= MIN_SEEDS_FOR_SPREAD]
        pooled = statistics.mean(spreads)
        points = []
        print(f"\nphi_c ({name}) per R: mean, sd of the seeds, seeds")
        for R, values in by_r.items():
            own = len(values) >= MIN_SEEDS_FOR_SPREAD
            sd = statistics.stdev(values) if own else pooled
            mean = statistics.mean(values)
            note = "" if own else f"; pooled sd used, the seeds' own: {statistics.stdev(values):.4f}" if len(values) > 1 else "; pooled sd"
            print(f"  R = {R:g}: {mean:.4f} sd {sd:.4f} ({len(values)} seeds{note})")
            points.append((R, mean, sd / len(values) ** 0.5))
        phi_inf, b, e_inf, e_b = weighted_line(points)
        at10 = phi_inf - b / 10.0
        print(
            f"  fit phi_c = phi_inf - b d/R: phi_inf {phi_inf:.4f} +- {e_inf:.4f}, "
            f"b {b:.3f} +- {e_b:.3f}; R = 10: {at10:.4f} (paper 0.5979)"
        )
        for o in others:
            mean = statistics.mean(by_r[o["R"]]) if o["R"] in by_r else float("nan")
            print(
                f"  {o['grains']} grains, R = {o['R']:g}, seed {o['seed']}: {o[key]:.4f} "
                f"({common} grains at this R: mean {mean:.4f})"
            )


if __name__ == "__main__":
    if len(sys.argv) < 2:
        sys.exit(__doc__)
    main(sys.argv[1:])
