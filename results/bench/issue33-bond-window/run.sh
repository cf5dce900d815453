#!/bin/sh
# Regenerates trials.txt (from the repository root's results/bench/issue33-bond-window):
#   sh run.sh > trials.txt
# The R = 10 d case reads the scene of the committed size-trend run, which
# its command in ../../compaction/size-trend/README.md writes.
set -e
bin=../../../target/release/examples/bond_window
for threads in 1 2; do
  for a_b in 0 -0.5; do
    $bin 2 $a_b $threads 300 4
    $bin 4 $a_b $threads 40 4
    $bin 7 $a_b $threads 8 4
  done
  $bin ../../compaction/size-trend/R10/seed-1/scene.json 0 $threads 40 4
done
