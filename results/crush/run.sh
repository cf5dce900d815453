#!/usr/bin/env bash
# Regenerates results/crush: grains of breakable (and yielding) bonds
# squeezed past failure (`bpm crush`, docs/protocols.md "Grain crushing").
# One thread each, one run at a time; about 26 minutes on a shared
# two-core machine. BPM defaults to target/release/bpm.
set -euo pipefail
cd "$(dirname "$0")/../.."
BPM=${BPM:-target/release/bpm}
grains=results/hertz/sweep-smoother/grains
run() {
    local out=$1
    shift
    mkdir -p "$out"
    "$BPM" --threads 1 crush "$@" --quiet -o "$out" > "$out/stdout.txt"
}
# The paper's grain size, three rotations, the paper's Poisson range.
run results/crush/R10-eps0.1 --grain $grains/smoother-R10-s1.json --radius 10 \
    --a-b -0.8,0,3 --critical-strain 0.1 --rotations 3 --compare-at 0.5
# Size trend: the sweep's grains of R = 4, 6, 8 d, the same squeezes.
for r in 4 6 8; do
    run results/crush/R$r-eps0.1 --grain $grains/smoother-R$r-s1.json --radius $r \
        --a-b -0.8,0,3 --critical-strain 0.1 --rotations 3 --compare-at 0.5
done
# A smaller critical strain, and bonds that yield before they break.
run results/crush/R10-eps0.05 --grain $grains/smoother-R10-s1.json --radius 10 \
    --a-b -0.8,0,3 --critical-strain 0.05 --rotations 1 --compare-at 0.5
run results/crush/R10-eps0.1-plastic0.05 --grain $grains/smoother-R10-s1.json --radius 10 \
    --a-b -0.8,0,3 --critical-strain 0.1 --plastic-strain 0.05 --rotations 1 --compare-at 0.5
