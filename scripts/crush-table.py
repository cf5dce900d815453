#!/usr/bin/env python3
"""Markdown table rows of `bpm crush` results: one row per a_B per crush.json.

    scripts/crush-table.py results/crush/R*-eps0.1/crush.json

Columns: folder, R (d), particles, a_B, nu, squeezes, crushed, the first
break's delta/R, the crushing force F_c / (E_eff R^2) and its delta/R, the
bonds broken at the end, fragments of at least 1% of the grain and the
largest fragment's share, each a mean +- sample sd over the squeezes (as
crush.json's case summaries), and the mean relative rms deviation from
Hertz before the first break.
"""
import json
import os
import sys


def show(stat, digits=3, percent=False):
    if stat is None:
        return "-"
    scale = 100.0 if percent else 1.0
    unit = "%" if percent else ""
    return f"{scale * stat['mean']:.{digits}f}{unit} +- {scale * stat['sd']:.{digits}f}{unit}"


def main(paths):
    print("| run | R (d) | particles | a_B | nu | squeezes | crushed | first break delta/R "
          "| F_c / (E_eff R^2) | delta/R at F_c | bonds broken at the end "
          "| fragments >= 1% | largest fragment | Hertz rel. rms before the first break |")
    print("| --- " * 14 + "|")
    for path in paths:
        report = json.load(open(path))
        radius = report["squeeze"]["radius"]
        folder = os.path.basename(os.path.dirname(path))
        for case in report["cases"]:
            crushes = case["crushes"]
            rms = [c["hertz_before_break"]["rms_relative"] for c in crushes
                   if c.get("hertz_before_break")]
            hertz = f"{100 * sum(rms) / len(rms):.1f}%" if rms else "-"
            print(f"| {folder} | {radius:g} | {crushes[0]['particles']:,} | {case['a_b']:g} "
                  f"| {case['moduli']['nu']:.2f} | {len(crushes)} | {case['crushed']} "
                  f"| {show(case['first_break_overlap'])} | {show(case['crushing_force'])} "
                  f"| {show(case['crushing_overlap'])} "
                  f"| {show(case['broken_fraction'], 1, True)} "
                  f"| {show(case['large_fragments'], 1)} "
                  f"| {show(case['largest_fragment'], 0, True)} | {hertz} |")


if __name__ == "__main__":
    main(sys.argv[1:])
