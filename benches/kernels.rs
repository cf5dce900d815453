//! Criterion benchmarks of the kernels alone, one id per kernel and term set.

use bpm::kernels::*;
use criterion::{criterion_group, criterion_main, Criterion};
use rand::{Rng, SeedableRng};

fn network(n: usize, l: f64) -> (Vec<[f64; 3]>, Vec<BondEntry>, Vec<f64>) {
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(1);
    let mut x: Vec<[f64; 3]> = (0..n)
        .map(|_| {
            [
                rng.gen::<f64>() * l,
                rng.gen::<f64>() * l,
                rng.gen::<f64>() * l,
            ]
        })
        .collect();
    x.sort_by(|a, b| {
        (a[2] as i64, a[1] as i64, a[0])
            .partial_cmp(&(b[2] as i64, b[1] as i64, b[0]))
            .unwrap()
    });
    let mut bonds = Vec::new();
    let mut r0 = Vec::new();
    for i in 0..n {
        for j in i + 1..n {
            let d: f64 = (0..3)
                .map(|k| (x[i][k] - x[j][k]).powi(2))
                .sum::<f64>()
                .sqrt();
            if d < 1.5 {
                bonds.push(BondEntry {
                    i: i as i32,
                    j: j as i32,
                    ty: 1,
                });
                r0.push(d * 1.001);
            }
        }
    }
    (x, bonds, r0)
}

fn kernels(c: &mut Criterion) {
    let (x, bonds, r0) = network(1500, 10.0);
    let v = vec![[0.01, -0.02, 0.005]; x.len()];
    let n = x.len();
    let own = Ownership::all(n);
    let mut vol = vec![0.0; n];
    let mut vol0 = vec![0.0; n];
    accumulate_reference_volumes(&bonds, &r0, own, &mut vol0);
    accumulate_volumes(&Unwrapped, &x, &bonds, own, &mut vol);
    let mut f = vec![[0.0; 3]; n];
    c.bench_function("bond::volumes", |b| {
        b.iter(|| {
            vol.fill(0.0);
            accumulate_volumes(&Unwrapped, &x, &bonds, own, &mut vol)
        })
    });
    for (name, a, tally) in [
        ("bond::spring", 0.0, false),
        ("bond::multibody", -0.5, false),
        ("bond::multibody_tally", -0.5, true),
    ] {
        let coeffs = [BondCoeffs {
            k: 1.0,
            a,
            gamma: 1.0,
        }];
        let inputs = BondInputs {
            x: &x,
            v: Some(&v),
            bonds: &bonds,
            r0: &r0,
            coeffs: &coeffs,
            volumes: (a != 0.0).then_some((&vol[..], &vol0[..])),
            tally,
        };
        c.bench_function(name, |b| {
            b.iter(|| bond_forces(&Unwrapped, &inputs, own, &mut f))
        });
    }
}

criterion_group!(benches, kernels);
criterion_main!(benches);
