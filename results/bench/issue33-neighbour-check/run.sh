#!/bin/sh
# Regenerates timing.txt (run from this folder):  sh run.sh > timing.txt
# max_displacement.rs holds the neighbour list's displacement check before
# (`old`, as of 946d8e0) and after (`new`, as in src/engine/neighbor.rs)
# this change, timed in turn in one process on 4,464 and 163,664 random
# points, 7 rounds each; it asserts that both give the same result.
set -e
work=${TMPDIR:-/tmp}/issue33-neighbour-check
mkdir -p "$work/src"
cat > "$work/Cargo.toml" <<'TOML'
[package]
name = "max-displacement"
version = "0.1.0"
edition = "2021"
[profile.release]
debug = false
TOML
cp max_displacement.rs "$work/src/main.rs"
cargo run --quiet --release --manifest-path "$work/Cargo.toml"
