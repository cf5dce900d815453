//! The bond row pass and the scatter kernel (multibody term and damping,
//! best instruction set) on a random network
//! of 1,500 particles (the kernel benchmark's), scaled by `SCALE` about
//! the origin and jostled by up to `JITTER / 2` per coordinate, so that a
//! chosen share of the volume ratios leaves the cube root's series range
//! (`|q - 1| > 1/32`). Prints that share and the ns per bond over `REPS`
//! passes of the row pass and of the scatter kernel (the plugin's) on the
//! same bonds (`results/bench/cube-root/`).
//!
//!     cargo run --release --example cube_root_rows -- SCALE REPS [JITTER]

use bpm::kernels::*;
use rand::{Rng, SeedableRng};

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let number = |k: usize, default: Option<f64>| -> f64 {
        match (args.get(k), default) {
            (Some(text), _) => text.parse().unwrap_or_else(|_| usage()),
            (None, Some(d)) => d,
            (None, None) => usage(),
        }
    };
    let reps: usize = args
        .get(1)
        .and_then(|text| text.parse().ok())
        .unwrap_or_else(|| usage());
    let (scale, jitter) = (number(0, None), number(2, Some(0.0)));
    let (n, side) = (1500, 10.0);
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(1);
    let mut x: Vec<[f64; 3]> = (0..n)
        .map(|_| [(); 3].map(|_| rng.gen::<f64>() * side))
        .collect();
    let cell = |p: &[f64; 3]| (p[2] as i64, p[1] as i64);
    x.sort_by(|a, b| cell(a).cmp(&cell(b)).then(a[0].total_cmp(&b[0])));
    let mut rows_in = Vec::new();
    for i in 0..n {
        for j in i + 1..n {
            let d = (0..3)
                .map(|k| (x[i][k] - x[j][k]).powi(2))
                .sum::<f64>()
                .sqrt();
            if d < 1.5 {
                rows_in.push((i, j, d * 1.001, rows_in.len()));
            }
        }
    }
    let bonds: Vec<BondEntry> = rows_in
        .iter()
        .map(|r| BondEntry {
            i: r.0 as i32,
            j: r.1 as i32,
            ty: 1,
        })
        .collect();
    let r0: Vec<f64> = rows_in.iter().map(|r| r.2).collect();
    let mut vol0 = vec![0.0; n];
    accumulate_reference_volumes(&bonds, &r0, Ownership::all(n), &mut vol0);
    let rows = BondRows::new(n, rows_in.into_iter(), Some(&vol0)).expect("valid bonds");
    let squeezed: Vec<[f64; 3]> = x
        .iter()
        .map(|p| p.map(|c| c * scale + jitter * (rng.gen::<f64>() - 0.5)))
        .collect();
    let v = vec![[0.01, -0.02, 0.005]; n];
    let mut lengths = vec![[0.0; 2]; rows.len()];
    let mut vol = vec![0.0; n];
    let isa = Isa::detect();
    row_volumes_on(
        isa,
        &Unwrapped,
        &rows,
        0..rows.len(),
        &squeezed,
        &mut lengths,
    );
    gather_volumes(&rows, 0..n, &lengths, &mut vol);
    let beyond = bonds
        .iter()
        .filter(|b| {
            let (i, j) = (b.i as usize, b.j as usize);
            ((vol[i] + vol[j]) / (vol0[i] + vol0[j]) - 1.0).abs() > 1.0 / 32.0
        })
        .count();
    let inputs = RowInputs {
        x: &squeezed,
        v: Some(&v),
        coeffs: BondCoeffs {
            k: 1.0,
            a: -0.5,
            gamma: 1.0,
        },
        multibody: Some((&vol[..], &lengths[..])),
        tally: false,
    };
    let mut out = vec![[0.0; 4]; rows.len()];
    let start = std::time::Instant::now();
    for _ in 0..reps {
        row_forces_on(isa, &Unwrapped, &rows, 0..rows.len(), &inputs, &mut out);
        std::hint::black_box(&out);
    }
    let ns = start.elapsed().as_secs_f64() * 1e9 / (reps * rows.len()).max(1) as f64;
    // The scatter kernel (the plugin's bond style) on the same bonds.
    let coeffs = [inputs.coeffs];
    let scatter = BondInputs {
        x: &squeezed,
        v: Some(&v),
        bonds: &bonds,
        r0: &r0,
        coeffs: &coeffs,
        volumes: Some((&vol[..], &vol0[..])),
        tally: false,
    };
    let mut f = vec![[0.0; 3]; n];
    let start = std::time::Instant::now();
    for _ in 0..reps {
        bond_forces_on(isa, &Unwrapped, &scatter, Ownership::all(n), &mut f);
        std::hint::black_box(&f);
    }
    let scatter_ns = start.elapsed().as_secs_f64() * 1e9 / (reps * rows.len()).max(1) as f64;
    println!(
        "scale {scale} jitter {jitter}: {} bonds, {beyond} beyond 1/32 ({}): row pass {ns:.2}, scatter kernel {scatter_ns:.2} ns per bond",
        rows.len(),
        isa.name()
    );
}

fn usage() -> ! {
    eprintln!("usage: cube_root_rows SCALE REPS [JITTER]");
    std::process::exit(2)
}
