use std::time::Instant;
#[inline(never)]
fn old(a: &[[f64; 3]], b: &[[f64; 3]]) -> f64 {
    let mut max_sq: f64 = 0.0;
    for (p, q) in a.iter().zip(b) {
        let d = [p[0] - q[0], p[1] - q[1], p[2] - q[2]];
        max_sq = max_sq.max(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
    }
    max_sq.sqrt()
}
#[inline(never)]
fn new(a: &[[f64; 3]], b: &[[f64; 3]]) -> f64 {
    const LANES: usize = 4;
    let larger = |m: f64, d: f64| if d > m { d } else { m };
    let distance_sq = |p: &[f64; 3], q: &[f64; 3]| {
        let d = [p[0] - q[0], p[1] - q[1], p[2] - q[2]];
        d[0] * d[0] + d[1] * d[1] + d[2] * d[2]
    };
    let n = a.len().min(b.len());
    let whole = n / LANES * LANES;
    let mut lanes = [0.0f64; LANES];
    for (p, q) in a[..whole].chunks_exact(LANES).zip(b[..whole].chunks_exact(LANES)) {
        for l in 0..LANES {
            lanes[l] = larger(lanes[l], distance_sq(&p[l], &q[l]));
        }
    }
    let max_sq = a[whole..n].iter().zip(&b[whole..n])
        .fold(lanes.into_iter().fold(0.0, larger), |m, (p, q)| larger(m, distance_sq(p, q)));
    max_sq.sqrt()
}
fn main() {
    for n in [4464usize, 163664] {
        let mut s = 12345u64;
        let mut r = || { s ^= s << 13; s ^= s >> 7; s ^= s << 17; (s >> 11) as f64 / (1u64 << 53) as f64 };
        let a: Vec<[f64; 3]> = (0..n).map(|_| [r() * 18.0, r() * 18.0, r() * 18.0]).collect();
        let b: Vec<[f64; 3]> = a.iter().map(|p| [p[0] + 0.01 * r(), p[1] + 0.01 * r(), p[2] - 0.01 * r()]).collect();
        let reps = 20_000_000 / n;
        let mut ratios = vec![];
        for _round in 0..7 {
            let t = Instant::now(); let mut acc = 0.0;
            for _ in 0..reps { acc += old(std::hint::black_box(&a), &b); }
            let to = t.elapsed().as_secs_f64() / (reps * n) as f64 * 1e9;
            let t = Instant::now(); let mut acc2 = 0.0;
            for _ in 0..reps { acc2 += new(std::hint::black_box(&a), &b); }
            let tn = t.elapsed().as_secs_f64() / (reps * n) as f64 * 1e9;
            assert_eq!(acc.to_bits(), acc2.to_bits());
            ratios.push(to / tn);
            println!("n {n}: old {to:.3} ns, new {tn:.3} ns per particle: {:.2}x", to / tn);
        }
        ratios.sort_by(|a, b| a.partial_cmp(b).unwrap());
        println!("n {n}: median {:.2}x", ratios[3]);
    }
}
