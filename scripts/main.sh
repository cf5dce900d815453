#!/usr/bin/env bash
# The main job: the LAMMPS-plugin-versus-native cross-check on the built-in
# scenes (bpm crosscheck; non-zero exit on any failure), then compression
# and shear of the L = 10 d bulk solid at a_B = 0 and -0.5 on the native
# engine with K, G, G/K, nu against the paper's fits. Output: results/main/.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/ensure-deps.sh
cargo build --release --quiet
bpm=target/release/bpm
out=results/main
mkdir -p "$out"
"$bpm" crosscheck -o "$out/crosscheck.json"
for a_b in 0 -0.5; do
  for protocol in compress shear; do
    scene="$out/bulk-L10-aB${a_b}-${protocol}.json"
    "$bpm" build bulk --size 10 --seed 1 --a-b "$a_b" --protocol "$protocol" -o "$scene"
    "$bpm" run "$scene" -o "${scene%.json}.out.json"
  done
done
python3 scripts/summarise_moduli.py "$out"
