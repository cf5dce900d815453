#!/bin/bash
# The neighbour build of several binaries, on a bulk solid whose list is
# rebuilt at every step. Each argument is LABEL=BINARY; the runs
# interleave the binaries, one and two threads, three rounds.
#
# The binaries of timing.txt (7240e34, before the build ran on the thread
# team; 3ed6369, on the team; and the stencil rework after it):
#
#   git worktree add /tmp/oldbin 7240e34 && (cd /tmp/oldbin && cargo build --release --bin bpm)
#   git worktree add /tmp/headbin 3ed6369 && (cd /tmp/headbin && cargo build --release --bin bpm)
#   results/bench/neighbour-build/run.sh old=/tmp/oldbin/target/release/bpm \
#       team=/tmp/headbin/target/release/bpm stencil=target/release/bpm > results/bench/neighbour-build/timing.txt
#
# The scene: `bpm build bulk --size 24 --seed 1 --protocol relax --steps 400
# --time-scale 0.05` (16,897 particles), with skin 0 and velocities of rms
# 0.03 d/tau set at the stage start, 300 steps: 301 builds. Each line is
# round, label, threads, stage wall seconds, seconds of the stage's
# `neighbours` timer (wrap, displacement check and build), builds.
set -euo pipefail
if [ $# -eq 0 ]; then
  echo "usage: $0 LABEL=BINARY..." >&2
  exit 2
fi
first=${1#*=}
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
"$first" build bulk --size 24 --seed 1 --protocol relax --steps 400 --time-scale 0.05 -o "$work/bulk.json" > /dev/null
python3 - "$work" <<'PY'
import json, sys
work = sys.argv[1]
d = json.load(open(f'{work}/bulk.json'))
d['force_field']['skin'] = 0.0
d['stages'][0]['set_velocities'] = {'rms_speed': 0.03}
d['stages'][0]['steps'] = 300
json.dump(d, open(f'{work}/skin0.json', 'w'))
PY
for round in 1 2 3; do
  for t in 1 2; do
    for pair in "$@"; do
      label=${pair%%=*}
      bin=${pair#*=}
      "$bin" --threads $t run "$work/skin0.json" -o "$work/$label$t.json" > /dev/null
      python3 -c "
import json; s = json.load(open('$work/$label$t.json'))['stages'][0]
print($round, '$label', $t, round(s['wall_seconds'], 3), round(s['timers']['neighbours'], 3), s['neighbour_builds'])"
    done
  done
done
