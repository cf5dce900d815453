//! Bond force: spring, multibody volume term and damping (docs/model.md).
//!
//! `F = k (r0 - r) + a (D_ij - r / r0) - gamma (n . dv)` with
//! `D_ij = ((V_i + V_j) / (V0_i + V0_j))^(1/3)`; positive `F` pushes the
//! atoms apart. The multibody term has no potential; the reported energy is
//! the spring proxy `k (r - r0)^2 / 2`.

use super::tally::{apply_pair_force, Ownership, Tally};
use super::{dot, sub, Separation};

/// Coefficients of one bond type.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BondCoeffs {
    /// Spring stiffness `k_B` (k units).
    pub k: f64,
    /// Multibody strength `a_B` (k d units); 0 switches the volume term off.
    pub a: f64,
    /// Damping `Gamma` (sqrt(k m) units); 0 switches velocity terms off.
    pub gamma: f64,
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
    c.k * (r0 - r) + c.a * (dilation - r / r0) - c.gamma * n_dot_dv
}

/// Local volumetric dilation `D_ij` of a bond from the volume proxies.
#[inline(always)]
pub fn dilation(vi: f64, vj: f64, v0i: f64, v0j: f64) -> f64 {
    cube_root((vi + vj) / (v0i + v0j))
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
    if x.abs() <= 1.0 / 32.0 {
        // The common case (volume strains of a few percent): degree 9,
        // truncation error below 1.1e-17, no division at all.
        let x4 = (x * x) * (x * x);
        return series_to_degree_7(x) + (x4 * x4) * (CBRT_SERIES[8] + CBRT_SERIES[9] * x);
    }
    let y = if x.abs() <= 0.25 {
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

/// Binomial coefficients C(1/3, n), n = 0 .. 9: the series of `(1 + x)^(1/3)`.
const CBRT_SERIES: [f64; 10] = [
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
    /// Whether to sum energy and virial (LAMMPS's `eflag || vflag`); steps
    /// that record nothing skip it.
    pub tally: bool,
}

/// Adds the bond forces of `inputs.bonds` to `f` and returns energy and virial.
///
/// The choice of terms (multibody, damping) is made once here, not per bond:
/// each combination is its own monomorphised loop.
pub fn bond_forces<S: Separation>(
    sep: &S,
    inputs: &BondInputs,
    own: Ownership,
    f: &mut [[f64; 3]],
) -> Tally {
    let flags = (inputs.volumes.is_some(), inputs.v.is_some(), ());
    match (flags, inputs.tally) {
        ((true, true, _), true) => bond_loop::<S, true, true, true>(sep, inputs, own, f),
        ((true, false, _), true) => bond_loop::<S, true, false, true>(sep, inputs, own, f),
        ((false, true, _), true) => bond_loop::<S, false, true, true>(sep, inputs, own, f),
        ((false, false, _), true) => bond_loop::<S, false, false, true>(sep, inputs, own, f),
        ((true, true, _), false) => bond_loop::<S, true, true, false>(sep, inputs, own, f),
        ((true, false, _), false) => bond_loop::<S, true, false, false>(sep, inputs, own, f),
        ((false, true, _), false) => bond_loop::<S, false, true, false>(sep, inputs, own, f),
        ((false, false, _), false) => bond_loop::<S, false, false, false>(sep, inputs, own, f),
    }
}

#[inline(always)]
fn bond_loop<S: Separation, const MULTIBODY: bool, const DAMPED: bool, const TALLY: bool>(
    sep: &S,
    inputs: &BondInputs,
    own: Ownership,
    f: &mut [[f64; 3]],
) -> Tally {
    if own.newton {
        bond_loop_owned::<S, MULTIBODY, DAMPED, TALLY, true>(sep, inputs, own, f)
    } else {
        bond_loop_owned::<S, MULTIBODY, DAMPED, TALLY, false>(sep, inputs, own, f)
    }
}

#[inline(always)]
fn bond_loop_owned<
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
) -> Tally {
    let x = inputs.x;
    let (vol, vol0) = inputs.volumes.unwrap_or((&[], &[]));
    let v = inputs.v.unwrap_or(&[]);
    let mut tally = Tally::default();
    for (bond, &r0) in inputs.bonds.iter().zip(inputs.r0) {
        let (i, j) = (bond.i as usize, bond.j as usize);
        let c = &inputs.coeffs[(bond.ty - 1) as usize];
        let del = sep.delta(&x[i], &x[j]);
        let rsq = dot(&del, &del);
        let r = rsq.sqrt();
        let rinv = 1.0 / r;
        let dstretch = r - r0;
        let mut fmag = -c.k * dstretch;
        if MULTIBODY {
            let d = dilation(vol[i], vol[j], vol0[i], vol0[j]);
            fmag += c.a * (d - r / r0);
        }
        if DAMPED {
            let dv = sub(&v[i], &v[j]);
            fmag -= c.gamma * dot(&del, &dv) * rinv;
        }
        let fpair = fmag * rinv;
        let (on_i, on_j, frac) = if NEWTON {
            (true, true, 1.0)
        } else {
            own.split(i, j)
        };
        apply_pair_force(f, i, j, on_i, on_j, &del, fpair);
        if TALLY {
            tally.add(frac, 0.5 * c.k * dstretch * dstretch, &del, fpair);
        }
    }
    tally
}
