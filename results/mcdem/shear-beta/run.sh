#!/bin/sh
# Regenerates results/mcdem/shear-beta: the shear study's exponent beta
# against system size and shear rate (issue 34). Each call of mc-shear
# reuses finished runs under its folder's runs/, so an interrupted study
# resumes where it stopped. Run from the repository root after
# `cargo build --release`.
set -eu
BPM=${BPM:-target/release/bpm}
OUT=results/mcdem/shear-beta
# System size: 1024 and 2048 spheres (the study: about 2000), default rates.
$BPM mc-shear --laws hertz,advanced --frictions 0 --poissons 0.25 --spheres 1024 -o $OUT/spheres-1024
$BPM mc-shear --laws advanced --frictions 0.5 --poissons 0.5 --spheres 1024 -o $OUT/spheres-1024-mu0.5
$BPM mc-shear --laws hertz,advanced --frictions 0 --poissons 0.25 --spheres 2048 -o $OUT/spheres-2048
# Shear rate: four times faster than the default, 256 spheres.
$BPM mc-shear --laws hertz,advanced --frictions 0,0.5 --poissons 0.25,0.5 --rate 8e-3 -o $OUT/rate-8e-3
# Shear rate: 16 times faster, 4 and 16 times slower than the default.
$BPM mc-shear --laws hertz,advanced --frictions 0,0.5 --poissons 0.25,0.5 --rate 3.2e-2 -o $OUT/rate-3.2e-2
$BPM mc-shear --laws hertz,advanced --frictions 0,0.5 --poissons 0.25,0.5 --rate 5e-4 -o $OUT/rate-5e-4
$BPM mc-shear --laws hertz --frictions 0 --poissons 0.25 --rate 1.25e-4 -o $OUT/rate-1.25e-4
$BPM mc-shear --laws advanced --frictions 0 --poissons 0.25 --rate 1.25e-4 -o $OUT/rate-1.25e-4-advanced
# A second packing (seed 2) at the default rate, for the scatter.
$BPM mc-shear --laws hertz,advanced --frictions 0,0.5 --poissons 0.25,0.5 --seed 2 -o $OUT/seed-2
# The trend across all of them and the default study.
$BPM mc-shear-trend results/mcdem/shear $OUT/seed-2 $OUT/spheres-1024 $OUT/spheres-1024-mu0.5 \
    $OUT/spheres-2048 $OUT/rate-3.2e-2 $OUT/rate-8e-3 $OUT/rate-5e-4 $OUT/rate-1.25e-4 \
    $OUT/rate-1.25e-4-advanced -o $OUT
