#!/usr/bin/env python3
"""Markdown table rows of `bpm crush` results: one row per a_B per crush.json.

    scripts/crush-table.py results/crush/R*-eps0.1/crush.json

Columns: folder, R (d), particles, a_B, nu, squeezes, crushed, the first
break's delta/R, the crushing force F_c / (E_eff R^2) and its delta/R, the
bonds broken at the end, fragments of at least 1% of the grain and the
largest fragment's share, each a mean +- sample sd over the squeezes (as
crush.json's case summaries), and the mean relative rms deviation from
Hertz before the first break.

A second table compares the sizes at one overlap, the report's
`compare_at` (`--compare-at`, the same delta/R for every R): the squeezes
that reached it, the bonds broken, the fragments and the largest fragment
there, beside the squeezes' mean overlap at their end, where the first
table counts.
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


def counted(case):
    """How many squeezes were counted at compare_at ("-": not counted)."""
    if "compared_broken_fraction" not in case:
        return "-"
    stat = case["compared_broken_fraction"] or {"count": 0}
    return f"{stat['count']} of {len(case['crushes'])}"


def cases(paths):
    """(folder, report, case) for every a_B of every crush.json."""
    for path in paths:
        report = json.load(open(path))
        folder = os.path.basename(os.path.dirname(path))
        for case in report["cases"]:
            yield folder, report, case


def main(paths):
    print("| run | R (d) | particles | a_B | nu | squeezes | crushed | first break delta/R "
          "| F_c / (E_eff R^2) | delta/R at F_c | bonds broken at the end "
          "| fragments >= 1% | largest fragment | Hertz rel. rms before the first break |")
    print("| --- " * 14 + "|")
    for folder, report, case in cases(paths):
        crushes = case["crushes"]
        rms = [c["hertz_before_break"]["rms_relative"] for c in crushes
               if c.get("hertz_before_break")]
        hertz = f"{100 * sum(rms) / len(rms):.1f}%" if rms else "-"
        print(f"| {folder} | {report['squeeze']['radius']:g} | {crushes[0]['particles']:,} "
              f"| {case['a_b']:g} "
              f"| {case['moduli']['nu']:.2f} | {len(crushes)} | {case['crushed']} "
              f"| {show(case['first_break_overlap'])} | {show(case['crushing_force'])} "
              f"| {show(case['crushing_overlap'])} "
              f"| {show(case['broken_fraction'], 1, True)} "
              f"| {show(case['large_fragments'], 1)} "
              f"| {show(case['largest_fragment'], 0, True)} | {hertz} |")
    print()
    print("| run | R (d) | a_B | nu | compared at delta/R | squeezes there | bonds broken there "
          "| fragments >= 1% there | largest fragment there | delta/R at the end "
          "| bonds broken at the end |")
    print("| --- " * 11 + "|")
    for folder, report, case in cases(paths):
        options = report["options"]
        at = options.get("compare_at")
        if at is None:  # the default: 0.5, or the end of a shorter squeeze
            at = min(0.5, options["max_overlap"] + 0.05)
        ends = [c["curve"]["overlap_over_r"][-1] for c in case["crushes"]
                if c["curve"]["overlap_over_r"]]
        end = f"{sum(ends) / len(ends):.2f}" if ends else "-"
        print(f"| {folder} | {report['squeeze']['radius']:g} | {case['a_b']:g} "
              f"| {case['moduli']['nu']:.2f} | {at:g} "
              f"| {counted(case)} "
              f"| {show(case.get('compared_broken_fraction'), 1, True)} "
              f"| {show(case.get('compared_large_fragments'), 1)} "
              f"| {show(case.get('compared_largest_fragment'), 0, True)} "
              f"| {end} | {show(case['broken_fraction'], 1, True)} |")

if __name__ == "__main__":
    main(sys.argv[1:])
