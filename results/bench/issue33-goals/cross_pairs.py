"""Counts, in a scene's state, the unbonded pairs within the pair cutoff
plus skin (the neighbour list's pairs) that join particles of the two
halves of the numbering (the two threads' halves), and the particles of
the upper half that such pairs reach. Brute force over a cell grid; no
numpy. The late-compaction state is the one `../issue33-fused-kick/run.sh`
makes: python3 cross_pairs.py $TMPDIR/issue33-fused-kick/compress-5.json
"""
import json
import sys
from collections import defaultdict

scene = json.load(open(sys.argv[1]))
box = scene["box"]
length, lo = box["lengths"][0], box["lo"][0]
assert box["lengths"] == [length] * 3 and box["tilt"] == [0.0] * 3, "a cubic box"
x = scene["particles"]["positions"]
n = len(x)
ff = scene["force_field"]
reach = ff["pair"]["d"] + ff["skin"]
bonded = set(tuple(sorted(p)) for p in scene["bonds"]["pairs"])
cells_per_side = int(length // reach)
side = length / cells_per_side
cells = defaultdict(list)
for i, p in enumerate(x):
    cells[tuple(int(((p[d] - lo) % length) // side) % cells_per_side for d in range(3))].append(i)
pairs = set()
for (cx, cy, cz), members in cells.items():
    for dx in (-1, 0, 1):
        for dy in (-1, 0, 1):
            for dz in (-1, 0, 1):
                other = cells.get(((cx + dx) % cells_per_side, (cy + dy) % cells_per_side, (cz + dz) % cells_per_side), [])
                for i in members:
                    for j in other:
                        if j <= i or (i, j) in bonded:
                            continue
                        d = [x[i][k] - x[j][k] for k in range(3)]
                        d = [v - length * round(v / length) for v in d]
                        if d[0] ** 2 + d[1] ** 2 + d[2] ** 2 < reach * reach:
                            pairs.add((i, j))
half = n // 2
cross = [(i, j) for i, j in pairs if (i < half) != (j < half)]
print(f"{n} particles, {len(bonded)} bonds, {len(pairs)} unbonded pairs within {reach}")
print(f"pairs joining the two halves: {len(cross)}")
print(f"particles of the upper half reached from the lower: {len(set(j for _, j in cross))} of {n - half}")
