#!/usr/bin/env bash
# The test suite: formatting, lints, then every test (release build, since
# the physics tests run real dynamics).
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/ensure-deps.sh
cargo fmt --all -- --check
cargo clippy --all-targets --release --quiet -- -D warnings
cargo test --release
