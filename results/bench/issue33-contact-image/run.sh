#!/bin/sh
# Regenerates trials.txt (run from this folder, after `cargo build --release`
# and `cargo build --release --examples`):  sh run.sh > trials.txt
# The late-compaction state: the default compaction's packing (seed 1) run
# through the jam and the first five compression stages, its final state
# written as a scene (about 2 minutes on two threads).
set -e
root=../../..
bpm=$root/target/release/bpm
work=${TMPDIR:-/tmp}/issue33-contact-image
mkdir -p "$work"
$bpm compact --threads 2 --seeds 1 --moduli-states 0 --quiet -o "$work"/compact > /dev/null
python3 - "$work" <<'PY'
import json, sys
work = sys.argv[1]
scene = json.load(open(f"{work}/compact/seed-1/scene.json"))
scene["stages"] = scene["stages"][:6]
json.dump(scene, open(f"{work}/early.json", "w"))
PY
$bpm run "$work"/early.json --threads 2 --quiet -o "$work"/early-out.json --final-scene "$work"/late.json > /dev/null
echo "# the state late in the compaction (after compress-4)"
$root/target/release/examples/contact_image "$work"/late.json 0 2000 6
echo "# the built packing, squeezed by 5% (linear), unrelaxed"
$root/target/release/examples/contact_image packing 0.05 2000 6
