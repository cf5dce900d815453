#!/bin/bash
# The compaction workload of `bpm bench` (the jammed packing of 32 grains
# of R = 3 d, the barostat's jam stage and a compression stage), timed by
# several binaries in turn. Each argument is LABEL=BINARY; the runs
# interleave the binaries over two rounds, and each prints the bench's
# packing lines.
#
# The binaries of timing.txt (93c8480, the kinetic sum on the calling
# thread; and this change, each thread summing its own share):
#
#   git worktree add /tmp/ab-old 93c8480 && (cd /tmp/ab-old && cargo build --release --bin bpm)
#   cargo build --release
#   results/bench/kinetic-sum/run.sh before=/tmp/ab-old/target/release/bpm \
#       after=target/release/bpm > results/bench/kinetic-sum/timing.txt
set -euo pipefail
if [ $# -eq 0 ]; then
  echo "usage: $0 LABEL=BINARY..." >&2
  exit 2
fi
for round in 1 2; do
  for pair in "$@"; do
    label=${pair%%=*}
    bin=${pair#*=}
    "$bin" bench --replicas 1 --steps 20 --liggghts-steps 0 2>&1 \
      | grep -E '^packing 32 grains R=3 a_B=' \
      | sed "s/^/$round $label /"
  done
done
