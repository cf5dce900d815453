#!/bin/sh
# Whole runs from a late-compaction state: 20,000
# steps of the protocol's stage compress-5, two builds alternated four
# times on 2 and then 1 thread(s). whole-runs.txt holds two such
# comparisons, each build made with `cargo build --release` in a
# `git worktree` at its commit (run from this folder):
#   sh whole-runs.sh 4d929e6/target/release/bpm a38b1cb/target/release/bpm   (the remap)
#   sh whole-runs.sh a38b1cb/target/release/bpm 3694363/target/release/bpm   (the image)
# The state: the committed compaction packing (../../compaction/native/
# seed-1/packing.data, 4,336 particles) through the jam and compress-0 to
# compress-4, made with the first build (about 2 minutes).
set -e
before=$1
after=$2
work=${TMPDIR:-/tmp}/issue33-whole-runs
mkdir -p "$work"
"$before" compact --threads 2 --packing ../../compaction/native/seed-1/packing.data \
  --moduli-states 0 --quiet -o "$work/compact" > /dev/null
python3 - "$work" <<'PY'
import json, sys
work = sys.argv[1]
scene = json.load(open(f"{work}/compact/seed-1/scene.json"))
stages = scene["stages"]
scene["stages"] = stages[:6]
json.dump(scene, open(f"{work}/early.json", "w"))
stages[6]["steps"] = 20000
json.dump(stages[6], open(f"{work}/compress-5-stage.json", "w"))
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
for threads in 2 1; do
  for round in 1 2 3 4; do
    for build in before after; do
      eval bin=\$$build
      "$bin" run "$work/compress-5.json" --threads $threads --quiet -o "$work/$build.json" > /dev/null
      python3 -c "
import json
s = json.load(open('$work/$build.json'))['stages'][0]
t = s['timers']
print('$threads thread(s) $build: run %.3f s, integrate %.3f s, pairs %.3f s' % (s['wall_seconds'], t['integrate'], t['pairs']))"
    done
  done
done
