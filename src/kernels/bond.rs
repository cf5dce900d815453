//! Bond force: spring, multibody volume term and damping (docs/model.md).
//!
//! `F = k (r0 - r) + a (D_ij - r / r0) - gamma (n . dv)` with
//! `D_ij = ((V_i + V_j) / (V0_i + V0_j))^(1/3)`; positive `F` pushes the
//! atoms apart. The multibody term has no potential; the reported energy is
//! the spring proxy `k (r - r0)^2 / 2`.

use super::fault::{Fault, ForcePass, COLLAPSED_BELOW, OVERSTRETCHED_ABOVE};
use super::isa::Isa;
use super::tally::{apply_pair_force_in_run, Ownership, RunningSum, Tally};
use super::{dot, sub, Separation};

/// Coefficients of one bond type.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BondCoeffs {
    /// Spring stiffness `k_B` (k units).
    pub k: f64,
    /// Multibody strength `a_B` (k d units); 0 switches the volume term off.
    pub a: f64,
    /// Damping `Gamma` (sqrt(k m) units); 0 switches velocity terms off.
    pub gamma: f64,
}

impl BondCoeffs {
    /// Whether every coefficient is zero (no bond forces at all).
    pub fn is_zero(&self) -> bool {
        self.k == 0.0 && self.a == 0.0 && self.gamma == 0.0
    }
}

/// One bond: two atom indices and a 1-based type.
///
/// The layout is that of a row of LAMMPS's `neighbor->bondlist`
/// (`int[3]`), so the plugin hands its list over without a copy.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct BondEntry {
    /// First atom (local index).
    pub i: i32,
    /// Second atom (local index).
    pub j: i32,
    /// Bond type, 1-based: coefficients are `coeffs[ty - 1]`.
    pub ty: i32,
}

/// Scalar bond force magnitude along `+n` on atom `i`.
#[inline(always)]
pub fn bond_force_magnitude(r: f64, r0: f64, dilation: f64, n_dot_dv: f64, c: &BondCoeffs) -> f64 {
    c.k * (r0 - r) + c.a * (dilation - r * reciprocal(r0)) - c.gamma * n_dot_dv
}

/// Local volumetric dilation `D_ij` of a bond from the volume proxies.
#[inline(always)]
pub fn dilation(vi: f64, vj: f64, v0i: f64, v0j: f64) -> f64 {
    cube_root((vi + vj) * reciprocal(v0i + v0j))
}

/// `1 / x`. The multibody term divides by the reference length and the
/// reference volume sum as products with their reciprocals, which an
/// engine that keeps its bonds can compute once instead of every step
/// (the native engine's bond rows); every kernel uses the same form, so
/// all give the same bits.
#[inline(always)]
pub fn reciprocal(x: f64) -> f64 {
    1.0 / x
}

/// Cube root of a positive finite `q`, within 2 ulp of `f64::cbrt`.
///
/// The platform `cbrt` is a generic software routine and dominated the cost
/// of the multibody term. The dilation ratio is nearly always close to 1:
/// for `|q - 1| <= 1/32` a degree-9 Taylor series of `(1 + x)^(1/3)` is
/// exact to round-off by itself (no division, a short dependency chain);
/// for `|q - 1| <= 1/4` a degree-7 series (error below 3e-7) is refined by
/// one Halley step (cubic convergence: below 1e-19), one division in all.
/// Elsewhere a bit-level guess (exponent divided by 3, error below 4%) takes
/// two Halley steps and one Newton step. Non-positive or non-finite `q` goes to `f64::cbrt`.
#[inline(always)]
pub fn cube_root(q: f64) -> f64 {
    let x = q - 1.0;
    if x.abs() <= CLOSE_TO_ONE {
        return cube_root_near_one(x);
    }
    let y = if x.abs() <= SERIES_AND_STEP_UP_TO {
        series_to_degree_7(x)
    } else if q > f64::MIN_POSITIVE && q < 1e300 {
        let mut y = f64::from_bits(q.to_bits() / 3 + 0x2A9F_7893_782D_A1CE);
        for _ in 0..2 {
            y = halley_cbrt_step(y, q);
        }
        return y - (y * y * y - q) / (3.0 * y * y);
    } else {
        return q.cbrt();
    };
    halley_cbrt_step(y, q)
}

/// `|q - 1|` up to which [`cube_root_near_one`] is exact to round-off.
pub(super) const CLOSE_TO_ONE: f64 = 1.0 / 32.0;

/// `|q - 1|` up to which [`cube_root`] refines the degree-7 series by one
/// Halley step.
pub(super) const SERIES_AND_STEP_UP_TO: f64 = 0.25;

/// `(1 + x)^(1/3)` for `|x| <= 1/32`, the common case (volume strains of a
/// few percent): degree 9, truncation error below 1.1e-17, no division and
/// no branch.
#[inline(always)]
fn cube_root_near_one(x: f64) -> f64 {
    let x4 = (x * x) * (x * x);
    series_to_degree_7(x) + (x4 * x4) * (CBRT_SERIES[8] + CBRT_SERIES[9] * x)
}

/// Binomial coefficients C(1/3, n), n = 0 .. 9: the series of `(1 + x)^(1/3)`.
pub(super) const CBRT_SERIES: [f64; 10] = [
    1.0,
    1.0 / 3.0,
    -1.0 / 9.0,
    5.0 / 81.0,
    -10.0 / 243.0,
    22.0 / 729.0,
    -154.0 / 6561.0,
    374.0 / 19683.0,
    -935.0 / 59049.0,
    21505.0 / 1594323.0,
];

/// The series of `(1 + x)^(1/3)` to degree 7 by Estrin's scheme:
/// independent pairs keep the dependency chain short (the baseline x86-64
/// target has no fused multiply-add).
#[inline(always)]
fn series_to_degree_7(x: f64) -> f64 {
    let c = &CBRT_SERIES;
    let x2 = x * x;
    let x4 = x2 * x2;
    let p01 = c[0] + c[1] * x;
    let p23 = c[2] + c[3] * x;
    let p45 = c[4] + c[5] * x;
    let p67 = c[6] + c[7] * x;
    (p01 + x2 * p23) + x4 * (p45 + x2 * p67)
}

#[inline(always)]
fn halley_cbrt_step(y: f64, q: f64) -> f64 {
    let y3 = y * y * y;
    y * (y3 + 2.0 * q) / (2.0 * y3 + q)
}

/// The dilation `cbrt((V_i + V_j) / (V0_i + V0_j))` of each lane, from
/// the sums `vsum` and `v0sum`, as [`dilation`] forms it. The division is
/// here, lane by lane, not in a gather: there it would be a scalar
/// division per bond on the critical path.
// Lane loops index several per-lane arrays at once; that form vectorises.
#[allow(clippy::needless_range_loop)]
#[inline(always)]
pub(super) fn dilations(vsum: &[f64; LANES], v0sum: &[f64; LANES]) -> [f64; LANES] {
    let mut q = [0.0; LANES];
    for l in 0..LANES {
        q[l] = vsum[l] * reciprocal(v0sum[l]);
    }
    cube_roots(&q)
}

/// [`cube_root`] of each lane of `q`, as the bond passes need it: the
/// series for `|q - 1| <= 1/32` in every lane, and the other ranges only
/// if some lane needs them.
// Lane loops index several per-lane arrays at once; that form vectorises.
#[allow(clippy::needless_range_loop)]
#[inline(always)]
fn cube_roots(q: &[f64; LANES]) -> [f64; LANES] {
    let mut far = false;
    let mut roots = [0.0; LANES];
    for l in 0..LANES {
        let x = q[l] - 1.0;
        far |= x.abs() > CLOSE_TO_ONE;
        roots[l] = cube_root_near_one(x);
    }
    if !far {
        return roots;
    }
    // The second range of `cube_root` in every lane, kept where a lane
    // lies in it: a select the compiler can vectorise, instead of a branch
    // per lane that a squeeze of a percent or more mispredicts.
    let mut beyond = false;
    for l in 0..LANES {
        let x = q[l] - 1.0;
        let stepped = halley_cbrt_step(series_to_degree_7(x), q[l]);
        if x.abs() > CLOSE_TO_ONE {
            roots[l] = stepped;
        }
        beyond |= x.abs() > SERIES_AND_STEP_UP_TO;
    }
    if beyond {
        for l in 0..LANES {
            if (q[l] - 1.0).abs() > SERIES_AND_STEP_UP_TO {
                roots[l] = cube_root(q[l]);
            }
        }
    }
    roots
}

/// Everything a bond-force pass reads.
#[derive(Clone, Copy, Debug)]
pub struct BondInputs<'a> {
    /// Positions of owned and ghost atoms.
    pub x: &'a [[f64; 3]],
    /// Velocities; `None` drops the damping term (as if every gamma were 0).
    pub v: Option<&'a [[f64; 3]]>,
    /// The bonds.
    pub bonds: &'a [BondEntry],
    /// Reference length of each bond, aligned with `bonds`.
    pub r0: &'a [f64],
    /// Coefficients per bond type (`coeffs[ty - 1]`).
    pub coeffs: &'a [BondCoeffs],
    /// `(V, V0)` per atom; `None` drops the multibody term (as if every a_B were 0).
    pub volumes: Option<(&'a [f64], &'a [f64])>,
    /// Whether to sum energy and virial (LAMMPS's `eflag_global ||
    /// vflag_global`); steps that record nothing skip it.
    pub tally: bool,
}

/// Adds the bond forces of `inputs.bonds` to `f` and returns energy and
/// virial, and the first bond outside the model's range ([`Fault`]).
///
/// Runs on the widest instruction set this processor has ([`Isa::detect`]);
/// every instruction set gives the same result bit for bit.
pub fn bond_forces<S: Separation>(
    sep: &S,
    inputs: &BondInputs,
    own: Ownership,
    f: &mut [[f64; 3]],
) -> ForcePass {
    bond_forces_on(Isa::detect(), sep, inputs, own, f)
}

/// [`bond_forces`] compiled for `isa` (the portable build when this
/// processor lacks it): for benchmarks and for the test that the builds
/// agree.
pub fn bond_forces_on<S: Separation>(
    isa: Isa,
    sep: &S,
    inputs: &BondInputs,
    own: Ownership,
    f: &mut [[f64; 3]],
) -> ForcePass {
    #[cfg(target_arch = "x86_64")]
    if isa == Isa::Avx2 && Isa::Avx2.available() {
        // SAFETY: the processor has AVX2 and FMA (checked just above).
        return unsafe { bond_forces_avx2(sep, inputs, own, f) };
    }
    let _ = isa;
    bond_terms(sep, inputs, own, f)
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
unsafe fn bond_forces_avx2<S: Separation>(
    sep: &S,
    inputs: &BondInputs,
    own: Ownership,
    f: &mut [[f64; 3]],
) -> ForcePass {
    bond_terms(sep, inputs, own, f)
}

/// The choice of terms (multibody, damping, tally, ownership) is made once
/// here, not per bond: each combination is its own monomorphised loop.
#[inline(always)]
fn bond_terms<S: Separation>(
    sep: &S,
    inputs: &BondInputs,
    own: Ownership,
    f: &mut [[f64; 3]],
) -> ForcePass {
    let flags = (inputs.volumes.is_some(), inputs.v.is_some(), inputs.tally);
    if own.newton {
        match flags {
            (true, true, true) => bond_blocks::<S, true, true, true, true>(sep, inputs, own, f),
            (true, false, true) => bond_blocks::<S, true, false, true, true>(sep, inputs, own, f),
            (false, true, true) => bond_blocks::<S, false, true, true, true>(sep, inputs, own, f),
            (false, false, true) => bond_blocks::<S, false, false, true, true>(sep, inputs, own, f),
            (true, true, false) => bond_blocks::<S, true, true, false, true>(sep, inputs, own, f),
            (true, false, false) => bond_blocks::<S, true, false, false, true>(sep, inputs, own, f),
            (false, true, false) => bond_blocks::<S, false, true, false, true>(sep, inputs, own, f),
            (false, false, false) => {
                bond_blocks::<S, false, false, false, true>(sep, inputs, own, f)
            }
        }
    } else {
        // Plugin runs with `newton_bond off`: always tallied, rarely hot.
        match flags {
            (true, true, _) => bond_blocks::<S, true, true, true, false>(sep, inputs, own, f),
            (true, false, _) => bond_blocks::<S, true, false, true, false>(sep, inputs, own, f),
            (false, true, _) => bond_blocks::<S, false, true, true, false>(sep, inputs, own, f),
            (false, false, _) => bond_blocks::<S, false, false, true, false>(sep, inputs, own, f),
        }
    }
}

/// Bonds computed together. The loop over a block's bonds runs in three
/// passes: gather (scalar loads by index into per-lane arrays), arithmetic
/// (lane by lane over plain arrays, with no loads by index and no branch,
/// so the compiler uses vector instructions and many bonds' square roots
/// and divisions are in flight at once), scatter (scalar). The arithmetic
/// is the same expression per bond as a scalar loop would evaluate, in
/// the same order, so results do not depend on the vector width.
pub(super) const LANES: usize = 8;

/// One block's bonds, lane by lane.
struct BondBlock {
    i: [usize; LANES],
    j: [usize; LANES],
    dx: [f64; LANES],
    dy: [f64; LANES],
    dz: [f64; LANES],
    r0: [f64; LANES],
    k: [f64; LANES],
    a: [f64; LANES],
    gamma: [f64; LANES],
    /// `V_i + V_j` and `V0_i + V0_j`.
    vsum: [f64; LANES],
    v0sum: [f64; LANES],
    /// `n . dv` times r (the dot product of the separation and the
    /// velocity difference).
    del_dot_dv: [f64; LANES],
    /// Outputs: force over distance, and the spring energy proxy.
    fpair: [f64; LANES],
    energy: [f64; LANES],
}

impl BondBlock {
    fn new() -> Self {
        Self {
            i: [0; LANES],
            j: [0; LANES],
            dx: [0.0; LANES],
            dy: [0.0; LANES],
            dz: [0.0; LANES],
            r0: [0.0; LANES],
            k: [0.0; LANES],
            a: [0.0; LANES],
            gamma: [0.0; LANES],
            vsum: [0.0; LANES],
            v0sum: [0.0; LANES],
            del_dot_dv: [0.0; LANES],
            fpair: [0.0; LANES],
            energy: [0.0; LANES],
        }
    }
}

// Lane loops index several per-lane arrays at once; that form vectorises.
#[allow(clippy::needless_range_loop)]
#[inline(always)]
fn bond_blocks<
    S: Separation,
    const MULTIBODY: bool,
    const DAMPED: bool,
    const TALLY: bool,
    const NEWTON: bool,
>(
    sep: &S,
    inputs: &BondInputs,
    own: Ownership,
    f: &mut [[f64; 3]],
) -> ForcePass {
    let x = inputs.x;
    let (vol, vol0) = inputs.volumes.unwrap_or((&[], &[]));
    let v = inputs.v.unwrap_or(&[]);
    let mut tally = Tally::default();
    let mut fault = None;
    let mut b = BondBlock::new();
    let mut run = RunningSum::new();
    // One bond type (the usual case): its coefficients fill every lane once
    // here instead of being looked up bond by bond.
    let single_type = inputs.coeffs.len() == 1;
    if let [c] = inputs.coeffs {
        b.k = [c.k; LANES];
        b.a = [c.a; LANES];
        b.gamma = [c.gamma; LANES];
    }
    let n = inputs.bonds.len().min(inputs.r0.len());
    let mut start = 0;
    while start < n {
        let lanes = LANES.min(n - start);
        // Gather. Unused lanes of the last block keep a harmless bond (unit
        // length, unit volume ratio, no velocity: zero force, finite
        // arithmetic) and are not scattered.
        for l in 0..LANES {
            if l >= lanes {
                b.dx[l] = 1.0;
                b.dy[l] = 0.0;
                b.dz[l] = 0.0;
                b.r0[l] = 1.0;
                b.vsum[l] = 1.0;
                b.v0sum[l] = 1.0;
                b.del_dot_dv[l] = 0.0;
                continue;
            }
            let bond = &inputs.bonds[start + l];
            let (i, j) = (bond.i as usize, bond.j as usize);
            let del = sep.delta(&x[i], &x[j]);
            b.i[l] = i;
            b.j[l] = j;
            b.dx[l] = del[0];
            b.dy[l] = del[1];
            b.dz[l] = del[2];
            b.r0[l] = inputs.r0[start + l];
            debug_assert!(!single_type || bond.ty == 1, "bond type {}", bond.ty);
            if !single_type {
                let c = &inputs.coeffs[(bond.ty - 1) as usize];
                b.k[l] = c.k;
                b.a[l] = c.a;
                b.gamma[l] = c.gamma;
            }
            if MULTIBODY {
                b.vsum[l] = vol[i] + vol[j];
                b.v0sum[l] = vol0[i] + vol0[j];
            }
            if DAMPED {
                b.del_dot_dv[l] = dot(&del, &sub(&v[i], &v[j]));
            }
        }
        // Arithmetic, lane by lane.
        let dilation = if MULTIBODY {
            dilations(&b.vsum, &b.v0sum)
        } else {
            [0.0; LANES]
        };
        let mut out_of_range = false;
        for l in 0..LANES {
            let rsq = b.dx[l] * b.dx[l] + b.dy[l] * b.dy[l] + b.dz[l] * b.dz[l];
            let r = rsq.sqrt();
            let rinv = 1.0 / r;
            let dstretch = r - b.r0[l];
            let mut fmag = -b.k[l] * dstretch;
            if MULTIBODY {
                fmag += b.a[l] * (dilation[l] - r * (1.0 / b.r0[l]));
            }
            if DAMPED {
                fmag -= b.gamma[l] * b.del_dot_dv[l] * rinv;
            }
            b.fpair[l] = fmag * rinv;
            if TALLY {
                b.energy[l] = 0.5 * b.k[l] * dstretch * dstretch;
            }
            // Written so that NaN fails it too.
            let in_range = r > COLLAPSED_BELOW * b.r0[l]
                && r < OVERSTRETCHED_ABOVE * b.r0[l]
                && b.fpair[l].abs() < f64::INFINITY;
            out_of_range |= !in_range;
        }
        if out_of_range && fault.is_none() {
            fault = (0..lanes).find_map(|l| {
                let r = (b.dx[l] * b.dx[l] + b.dy[l] * b.dy[l] + b.dz[l] * b.dz[l]).sqrt();
                Fault::of_bond(start + l, b.i[l], b.j[l], r, b.r0[l], b.fpair[l])
            });
        }
        // Scatter.
        for l in 0..lanes {
            let (i, j) = (b.i[l], b.j[l]);
            let del = [b.dx[l], b.dy[l], b.dz[l]];
            let (on_i, on_j, frac) = if NEWTON {
                (true, true, 1.0)
            } else {
                own.split(i, j)
            };
            apply_pair_force_in_run(&mut run, f, i, j, on_i, on_j, &del, b.fpair[l]);
            if TALLY {
                tally.add(frac, b.energy[l], &del, b.fpair[l]);
            }
        }
        start += lanes;
    }
    run.finish(f);
    ForcePass { tally, fault }
}
