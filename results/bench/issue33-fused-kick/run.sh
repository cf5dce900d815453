#!/bin/sh
# The second half step with the deformation's remap and the barostat's
# kinetic sum in its pass, against the three passes apart: two builds
# alternated, 20,000 steps of the late-compaction stage compress-5 and of
# the jam (barostat), 1 and 2 threads, three rounds. Each build made with
# `cargo build --release` in a `git worktree` at its commit (give their
# absolute paths); run from this folder:
#   sh run.sh /path/to/bb5d91c/target/release/bpm /path/to/1828d5e/target/release/bpm > timing.txt
# The states: the default compaction (32 smoother grains of R = 3 d, seed
# 1) through its jam and compress-0 to compress-4, made with the first
# build (about 4 minutes on two threads); the jam from the built packing.
set -e
before=$1
after=$2
work=${TMPDIR:-/tmp}/issue33-fused-kick
mkdir -p "$work"
"$before" compact --threads 2 --seeds 1 --moduli-states 0 --quiet -o "$work/compact" > /dev/null
python3 - "$work" <<'PY'
import json, sys
work = sys.argv[1]
scene = json.load(open(f"{work}/compact/seed-1/scene.json"))
stages = scene["stages"]
jam = dict(scene, stages=[dict(stages[0], steps=20000)])
json.dump(jam, open(f"{work}/jam.json", "w"))
scene["stages"] = stages[:6]
json.dump(scene, open(f"{work}/early.json", "w"))
json.dump(dict(stages[6], steps=20000), open(f"{work}/compress-5-stage.json", "w"))
PY
"$before" run "$work/early.json" --threads 2 --quiet -o "$work/early-out.json" \
  --final-scene "$work/late.json" > /dev/null
python3 - "$work" <<'PY'
import json, sys
work = sys.argv[1]
scene = json.load(open(f"{work}/late.json"))
scene["stages"] = [json.load(open(f"{work}/compress-5-stage.json"))]
json.dump(scene, open(f"{work}/compress-5.json", "w"))
PY
echo "round scene threads build wall_s integrate_s bonds_s pairs_s"
for round in 1 2 3; do
  for scene in compress-5 jam; do
    for threads in 1 2; do
      for build in before after; do
        eval bin=\$$build
        "$bin" run "$work/$scene.json" --threads $threads --quiet -o "$work/out-$build.json" > /dev/null
        python3 - "$work/out-$build.json" $round $scene $threads $build <<'PY'
import json, sys
out, rnd, scene, threads, build = sys.argv[1:]
s = json.load(open(out))["stages"][0]
t = s["timers"]
print(rnd, scene, threads, build, f"{s['wall_seconds']:.3f}", f"{t['integrate']:.3f}", f"{t['bonds']:.3f}", f"{t['pairs']:.3f}")
PY
      done
      cmp -s "$work/out-before.json" "$work/out-after.json" || python3 - "$work" <<'PY'
import json, sys
w = sys.argv[1]
rows = lambda b: [(s["rows"], s["checkpoints"]) for s in json.load(open(f"{w}/out-{b}.json"))["stages"]]
print("   records", "equal" if rows("before") == rows("after") else "DIFFER")
PY
    done
  done
done
