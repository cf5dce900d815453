#!/usr/bin/env bash
# Regenerates results/compaction/breakable: the packing of
# results/compaction/native (32 smoother grains of R = 3 d, a_B = 0)
# compressed by the same (default) protocol with bonds that break (eps_c = 0.1),
# with bonds that only yield (eps_p = 0.05) and, for comparison, elastic, to 60%
# volumetric strain of the box (the plastic run stops on the way) and, the
# next two, to 25%; the yielding and elastic runs again with the contact law
# overlaid on the bonds (--overlay-pair), to 60%; each then unloaded (the box
# expanded back to its jammed size at 1e-4 per tau, and rested as long).
# Native engine, one thread, about 30 minutes on a shared two-core machine.
# BPM defaults to target/release/bpm; CASES picks folders by name (all by
# default).
set -euo pipefail
cd "$(dirname "$0")/../../.."
BPM=${BPM:-target/release/bpm}
packing=results/compaction/native/seed-1/packing.data
for case in "eps0.1 --critical-strain 0.1" "plastic0.05 --no-break --plastic-strain 0.05" \
    "elastic --moduli-states 0" \
    "plastic0.05-v0.25 --no-break --plastic-strain 0.05 --volumetric-strain 0.25" \
    "elastic-v0.25 --moduli-states 0 --volumetric-strain 0.25" \
    "plastic0.05-overlay --no-break --plastic-strain 0.05 --overlay-pair" \
    "elastic-overlay --moduli-states 0 --overlay-pair"; do
    set -- $case
    name=$1
    shift
    if [ -n "${CASES:-}" ] && [[ " $CASES " != *" $name "* ]]; then
        continue
    fi
    out=results/compaction/breakable/$name
    mkdir -p "$out"
    "$BPM" --threads 1 compact --packing $packing --unload-rate 1e-4 "$@" --quiet -o "$out" \
        > "$out/stdout.txt"
done
