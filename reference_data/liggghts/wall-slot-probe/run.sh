#!/usr/bin/env bash
# The wall-slot probes: four two-sphere runs of LIGGGHTS 3.8 (Debian) that show
# its per-atom slots of a primitive wall aliasing (README). Writes in.NAME and
# NAME.data here, runs each in a scratch folder with the hydrogel tutorial's lid
# mesh, and keeps LIGGGHTS's lid force and the per-atom forces in NAME.txt.
#
#   ./run.sh            # about 2 s in all
#
# Sphere B (diameter 0.02 m) sits at (0.10, 0.10, 0.0099) between the floor
# (z = 0, a primitive wall) and the lid mesh (z = 0.0198), pressed by each by
# 1e-4 m. Sphere A (diameter 0.01 m) at (0.03, 0.03, ZA) touches nothing.
#   far_AB   A has id 1, 7 mm above the floor: outside the floor's list
#   near_AB  A has id 1, gap 1.5 mm: in the list, within half the skin (a slot)
#   band_AB  A has id 1, gap 3 mm: between half the skin and the skin (no slot)
#   band_BA  as band_AB, but A has id 2 (no sphere after it to alias)
set -euo pipefail
HERE=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
SRC=${SRC:-/usr/share/doc/liggghts/examples/LIGGGHTS/Tutorials_public/hydrogel_multicontact}
WORK=${WORK:-/tmp/liggghts-wall-slot-probe}
LIGGGHTS=${LIGGGHTS:-$(command -v liggghts)}

probe() {
    local name=$1 za=$2 order=$3 a b
    a="0.01 11.5 0.03 0.03 $za"
    b="0.02 11.5 0.10 0.10 0.0099"
    local first second
    if [[ $order == AB ]]; then first="1 1 $a"; second="2 1 $b"; else first="1 1 $b"; second="2 1 $a"; fi
    cat > "$HERE/$name.data" <<DATA
probe $name (wall-slot probe, run.sh)

 2  atoms

 2  atom types

 -0.0101 0.1701 xlo xhi
 -0.0101 0.1701 ylo yhi
 -0.0101 0.4101 zlo zhi

Atoms

$first
$second

Velocities

1 0 0 0 0 0 0
2 0 0 0 0 0 0
DATA
    cat > "$HERE/in.$name" <<DECK
# wall-slot probe $name (run.sh): the hydrogel tutorial's materials, contact model
# and closure, a primitive floor and the lid mesh, skin 0.004 m as shipped.
atom_style	sphere
atom_modify	map array
atom_modify	sort 0 0.0
boundary	f f f
newton		off
soft_particles yes
communicate	single vel yes
processors * 1 1
units		si
read_data $name.data
neighbor	0.004 bin
neigh_modify	delay 0
fix 		m1 all property/global youngsModulus peratomtype 23.3e3 5e7
fix 		m2 all property/global poissonsRatio peratomtype 0.5 0.5
fix 		m3 all property/global coefficientRestitution peratomtypepair 2 0.95 0.95 0.95 0.95
fix 		m4 all property/global coefficientFriction peratomtypepair 2 0.03 0.03 0.03 0.03
pair_style gran model hertz tangential history surface multicontact
pair_coeff	* *
timestep  0.00001
fix wall_bottom all wall/gran model hertz tangential history surface multicontact primitive type 2 zplane 0.0
fix piston_m    all mesh/surface/stress file meshes/piston_hydrogel.stl type 2 move 0. 0. 0.0198
fix piston      all wall/gran model hertz tangential history surface multicontact mesh   n_meshes 1   meshes piston_m
fix mc all multicontact/halfspace geometric_prefactor 1.125
thermo_style	custom step f_piston_m[1] f_piston_m[2] f_piston_m[3]
thermo_modify	format float %.17g
thermo		1
dump forces all custom 1 $name.dump id fx fy fz
dump_modify forces sort id format "%d %.17g %.17g %.17g"
run		5
DECK
    rm -rf "$WORK/$name"; mkdir -p "$WORK/$name/meshes"
    cp "$SRC/meshes/piston_hydrogel.stl"* "$WORK/$name/meshes/"
    [[ -f "$WORK/$name/meshes/piston_hydrogel.stl.gz" ]] && gunzip -f "$WORK/$name/meshes/piston_hydrogel.stl.gz"
    cp "$HERE/in.$name" "$HERE/$name.data" "$WORK/$name/"
    (cd "$WORK/$name" && "$LIGGGHTS" -in "in.$name" -log log > stdout.txt)
    {
        echo "# LIGGGHTS 3.8.0 (Debian), probe $name (in.$name): lid force fz [N] per step, then per-atom forces [N]"
        echo "# step lid_fz"
        awk '/^ *Step/ { on = 1; next } /^Loop time/ { on = 0 } on && NF == 4 { print $1, $4 }' "$WORK/$name/log"
        echo "# per-atom forces: step id fx fy fz"
        awk '/^ITEM: TIMESTEP/ { getline s; step = s; next } /^ITEM:/ { next } NF == 4 { print step, $0 }' "$WORK/$name/$name.dump"
    } > "$HERE/$name.txt"
}

probe far_AB 0.012 AB
probe near_AB 0.0065 AB
probe band_AB 0.008 AB
probe band_BA 0.008 BA
echo "wrote $HERE/{far_AB,near_AB,band_AB,band_BA}.txt"
