#!/usr/bin/env bash
# The main job: build the bulk solid and run the built-in scenes on the
# native engine (compression and shear of the L = 10 d solid at a_B = 0 and
# -0.5), writing scenes and reports under results/main/.
# (The LAMMPS-versus-native cross-check joins here with the plugin.)
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/ensure-deps.sh
cargo build --release --quiet
bpm=target/release/bpm
out=results/main
mkdir -p "$out"
for a_b in 0 -0.5; do
  for protocol in compress shear; do
    scene="$out/bulk-L10-aB${a_b}-${protocol}.json"
    "$bpm" build bulk --size 10 --seed 1 --a-b "$a_b" --protocol "$protocol" -o "$scene"
    "$bpm" run "$scene" -o "${scene%.json}.out.json"
  done
done
python3 scripts/summarise_moduli.py "$out"
