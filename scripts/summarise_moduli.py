#!/usr/bin/env python3
"""Prints K and G from the main job's compression and shear reports.

K is the least-squares slope of pressure against volumetric strain, G of
-P_xy against shear strain (MODEL.md "Calibration"). These are first looks
at L = 10 d; the calibration study proper (sizes, seeds, rates) is its own job.
"""
import json
import math
import sys
from pathlib import Path


def slope(x, y):
    mx, my = sum(x) / len(x), sum(y) / len(y)
    sxx = sum((a - mx) ** 2 for a in x)
    return sum((a - mx) * (b - my) for a, b in zip(x, y)) / sxx


def series(path):
    report = json.loads(Path(path).read_text())
    stage = report["stages"][0]
    cols = {c: i for i, c in enumerate(stage["columns"])}
    rows = stage["rows"]
    return report, {c: [r[i] for r in rows] for c, i in cols.items()}


def main(folder):
    folder = Path(folder)
    print(f"{'a_B':>6} {'K':>8} {'G':>8} {'G/K':>7} {'nu':>7}   paper fits: {'K':>6} {'G/K':>6}")
    for a_b in ("0", "-0.5"):
        _, c = series(folder / f"bulk-L10-aB{a_b}-compress.out.json")
        v0 = c["lx"][0] * c["ly"][0] * c["lz"][0]
        eps_v = [(v0 - a * b * d) / v0 for a, b, d in zip(c["lx"], c["ly"], c["lz"])]
        k = slope(eps_v, c["pressure"])
        _, s = series(folder / f"bulk-L10-aB{a_b}-shear.out.json")
        gamma = [t / ly for t, ly in zip(s["xy"], s["ly"])]
        g = slope(gamma, [-p for p in s["pxy"]])
        nu = (3 * k - 2 * g) / (2 * (3 * k + g))
        a = float(a_b)
        k_fit = 1.365 - 0.14 / (a + 1.168)
        gk_fit = 0.6 + 0.475 * a
        print(f"{a:>6.2f} {k:>8.4f} {g:>8.4f} {g / k:>7.3f} {nu:>7.3f}   {'':>11} {k_fit:>6.3f} {gk_fit:>6.3f}")
        if not all(math.isfinite(v) for v in (k, g)):
            sys.exit("non-finite modulus")


if __name__ == "__main__":
    main(sys.argv[1] if len(sys.argv) > 1 else "results/main")
