#!/bin/bash
# The neighbour build on the thread team (d555405) against the build before
# it (7240e34), on a bulk solid whose list is rebuilt at every step.
#
#   git worktree add /tmp/oldbin 7240e34 && (cd /tmp/oldbin && cargo build --release --bin bpm)
#   OLD=/tmp/oldbin/target/release/bpm NEW=target/release/bpm results/bench/neighbour-build/run.sh
#
# The scene: `bpm build bulk --size 24 --seed 1 --protocol relax --steps 400
# --time-scale 0.05` (16,897 particles), with skin 0 and velocities of rms
# 0.03 d/tau set at the stage start, 300 steps: 301 builds. Runs interleave
# old and new, one and two threads, three rounds; each line is round,
# binary, threads, stage wall seconds, and the seconds of the stage's
# `neighbours` timer (wrap, displacement check and build).
set -euo pipefail
OLD=${OLD:?the binary before the change}
NEW=${NEW:-target/release/bpm}
work=$(mktemp -d)
"$NEW" build bulk --size 24 --seed 1 --protocol relax --steps 400 --time-scale 0.05 -o "$work/bulk.json" > /dev/null
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
    for b in old new; do
      bin=$OLD; [ $b = new ] && bin=$NEW
      "$bin" --threads $t run "$work/skin0.json" -o "$work/$b$t.json" > /dev/null
      python3 -c "
import json; s = json.load(open('$work/$b$t.json'))['stages'][0]
print($round, '$b', $t, round(s['wall_seconds'], 3), round(s['timers']['neighbours'], 3), s['neighbour_builds'])"
    done
  done
done
rm -rf "$work"
