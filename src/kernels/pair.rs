//! Contact force between non-bonded particles (docs/model.md).
//!
//! For `r < d`: `F = k (d - r) + a (d - r)^3 - gamma (n . dv)`, repulsive
//! when positive. The conservative part derives from
//! `U = k (d - r)^2 / 2 + a (d - r)^4 / 4`.

use super::fault::{Fault, ForcePass};
use super::tally::{apply_pair_force, Ownership, Tally};
use super::{dot, sub, Separation, NEIGHMASK, SPECIAL_SHIFT};

/// Coefficients of one pair of atom types.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PairCoeffs {
    /// Harmonic stiffness `k_P` (k units).
    pub k: f64,
    /// Contact distance and cutoff `d` (d units), > 0.
    pub d: f64,
    /// Cubic repulsion `a_P` (k / d^2 units).
    pub a: f64,
    /// Damping `Gamma` (sqrt(k m) units).
    pub gamma: f64,
}

/// Scalar pair force magnitude along `+n` on atom `i`, for `r < d`.
#[inline(always)]
pub fn pair_force_magnitude(r: f64, n_dot_dv: f64, c: &PairCoeffs) -> f64 {
    let overlap = c.d - r;
    c.k * overlap + c.a * overlap * overlap * overlap - c.gamma * n_dot_dv
}

/// Conservative pair energy for `r < d`.
#[inline(always)]
pub fn pair_energy(r: f64, c: &PairCoeffs) -> f64 {
    let o2 = (c.d - r) * (c.d - r);
    0.5 * c.k * o2 + 0.25 * c.a * o2 * o2
}

/// Everything a pair-force pass reads.
#[derive(Clone, Copy, Debug)]
pub struct PairInputs<'a> {
    /// Positions of owned and ghost atoms.
    pub x: &'a [[f64; 3]],
    /// Velocities; `None` drops the damping term.
    pub v: Option<&'a [[f64; 3]]>,
    /// Per-atom 1-based types; `None` means every atom is type 1.
    pub types: Option<&'a [i32]>,
    /// Number of atom types: coefficients are `coeffs[(ti-1) * ntypes + (tj-1)]`.
    pub ntypes: usize,
    /// Coefficients per type pair, row-major, `ntypes * ntypes` entries.
    pub coeffs: &'a [PairCoeffs],
    /// Weights of the special classes (LAMMPS `special_lj`); index 0 is 1.
    pub special: [f64; 4],
    /// Whether to sum energy and virial.
    pub tally: bool,
    /// Whether the damping fades as `1 - (r / d)^8` towards the contact
    /// distance, as in upstream LAMMPS's `pair_style bpm/spring` (the
    /// plugin's drop-in `bpm/spring/rs`); the model's contact has none.
    pub damping_taper: bool,
}

/// Adds the contact forces of a half neighbour list to `f`.
///
/// `neighbours` yields `(i, js)`: atom `i` and its neighbours, each a LAMMPS
/// neighbour index (the top two bits name a special class, stripped with
/// [`NEIGHMASK`]). A pair with special weight 0 is skipped. Returns energy
/// and virial, and the first pair with a non-finite force ([`Fault`]).
pub fn pair_forces<'n, S, I>(
    sep: &S,
    inputs: &PairInputs,
    neighbours: I,
    own: Ownership,
    f: &mut [[f64; 3]],
) -> ForcePass
where
    S: Separation,
    I: Iterator<Item = (usize, &'n [i32])>,
{
    let taper = inputs.damping_taper;
    match (inputs.v.is_some(), inputs.tally) {
        (true, true) if taper => {
            pair_loop::<S, I, true, true, true>(sep, inputs, neighbours, own, f)
        }
        (true, false) if taper => {
            pair_loop::<S, I, true, false, true>(sep, inputs, neighbours, own, f)
        }
        (true, true) => pair_loop::<S, I, true, true, false>(sep, inputs, neighbours, own, f),
        (true, false) => pair_loop::<S, I, true, false, false>(sep, inputs, neighbours, own, f),
        (false, true) => pair_loop::<S, I, false, true, false>(sep, inputs, neighbours, own, f),
        (false, false) => pair_loop::<S, I, false, false, false>(sep, inputs, neighbours, own, f),
    }
}

#[inline(always)]
fn pair_loop<'n, S, I, const DAMPED: bool, const TALLY: bool, const TAPER: bool>(
    sep: &S,
    inputs: &PairInputs,
    neighbours: I,
    own: Ownership,
    f: &mut [[f64; 3]],
) -> ForcePass
where
    S: Separation,
    I: Iterator<Item = (usize, &'n [i32])>,
{
    let x = inputs.x;
    let n = inputs.ntypes;
    let mut tally = Tally::default();
    let mut fault = None;
    for (i, js) in neighbours {
        let ti = inputs.types.map_or(0, |t| (t[i] - 1) as usize);
        for &jraw in js {
            let j = (jraw & NEIGHMASK) as usize;
            let weight = inputs.special[(jraw as u32 >> SPECIAL_SHIFT) as usize];
            if weight == 0.0 {
                continue;
            }
            let tj = inputs.types.map_or(0, |t| (t[j] - 1) as usize);
            let c = &inputs.coeffs[ti * n + tj];
            let del = sep.delta(&x[i], &x[j]);
            let rsq = dot(&del, &del);
            if rsq >= c.d * c.d {
                continue;
            }
            let r = rsq.sqrt();
            let rinv = 1.0 / r;
            let mut n_dot_dv = if DAMPED {
                let v = inputs.v.unwrap_or(&[]);
                dot(&del, &sub(&v[i], &v[j])) * rinv
            } else {
                0.0
            };
            if TAPER {
                let s = rsq / (c.d * c.d);
                let s2 = s * s;
                n_dot_dv *= 1.0 - s2 * s2;
            }
            let fpair = weight * pair_force_magnitude(r, n_dot_dv, c) * rinv;
            if !fpair.is_finite() {
                fault = fault.or(Fault::of_pair(i, j, r, c.d, fpair));
            }
            let (on_i, on_j, frac) = own.split(i, j);
            apply_pair_force(f, i, j, on_i, on_j, &del, fpair);
            if TALLY {
                tally.add(frac, weight * pair_energy(r, c), &del, fpair);
            }
        }
    }
    ForcePass { tally, fault }
}
