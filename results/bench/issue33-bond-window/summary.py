"""Medians of trials.txt per case: python3 summary.py < trials.txt"""
import re
import statistics
import sys

case, rows = None, {}
for line in sys.stdin:
    head = re.match(r"(\d+) particles, (\d+) bonds, a_B = (\S+), (\d) thread", line)
    if head:
        case = (int(head[1]), float(head[3]), int(head[4]))
        rows[case] = {"Never": [], "Always": []}
        continue
    m = re.match(r"round \d+ (\w+)\s+step\s+([\d.]+) ns, bonds\s+([\d.]+) ns", line)
    if m and case:
        rows[case][m[1]].append((float(m[2]), float(m[3])))
print("| particles | a_B | threads | step, full-size | step, windowed | bonds, full-size | bonds, windowed | step: windowed / full | bonds: windowed / full |")
print("| ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |")
for (n, a_b, threads), r in rows.items():
    med = lambda mode, k: statistics.median(x[k] for x in r[mode])
    print(
        f"| {n:,} | {a_b:g} | {threads} | {med('Never', 0):.1f} | {med('Always', 0):.1f} "
        f"| {med('Never', 1):.1f} | {med('Always', 1):.1f} "
        f"| {med('Always', 0) / med('Never', 0):.2f} | {med('Always', 1) / med('Never', 1):.2f} |"
    )
