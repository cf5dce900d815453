//! Bonds that break and yield over a LAMMPS bond list: the plugin's
//! `bpm/spring/rs` and `bpm/spring/plastic/rs` styles.
//!
//! The rules are those of [`super::bond_failure`], applied bond by bond in
//! list order, as LAMMPS's own bond styles walk `neighbor->bondlist`. A
//! bond that breaks gets type 0 in the list, which later passes over the
//! same list skip (LAMMPS's convention for a broken bond until the list is
//! rebuilt), and its index is reported so that the caller can take it out
//! of its atoms' arrays. The multibody term's volumes are those of the
//! intact bonds, and the reference volumes those of their rest lengths
//! `r_eq = (1 + e_p) r0`, as in the native engine.
//!
//! The passes go through the list in blocks of [`LANES`] bonds, as the
//! elastic pass does: gather by index, arithmetic lane by lane with every
//! rule a select (so the compiler keeps many bonds' square roots and
//! divisions in flight in vector instructions), scatter in list order.
//! Each lane evaluates what [`failing_bond_force`] evaluates, operation by
//! operation, so every build and block size gives the same bits as a loop
//! bond by bond.

use super::bond::{dilations, BondCoeffs, BondEntry, LANES};
use super::bond_failure::{plastic_strain_after, smoothing, BondFailure};
use super::fault::{Fault, ForcePass, COLLAPSED_BELOW, OVERSTRETCHED_ABOVE};
use super::isa::Isa;
use super::tally::{apply_pair_force_in_run, Ownership, RunningSum, Tally};
use super::{dot, sub, Separation};

/// Everything a pass over a failing bond list reads.
#[derive(Clone, Copy, Debug)]
pub struct FailingListInputs<'a> {
    /// Positions of owned and ghost atoms.
    pub x: &'a [[f64; 3]],
    /// Velocities; `None` drops the damping term.
    pub v: Option<&'a [[f64; 3]]>,
    /// First length `r0` of each bond, aligned with the list.
    pub r0: &'a [f64],
    /// Coefficients per bond type (`coeffs[ty - 1]`).
    pub coeffs: &'a [BondCoeffs],
    /// How bonds of each type break and yield (`rules[ty - 1]`).
    pub rules: &'a [BondFailure],
    /// Whether a bond may break in this pass (LAMMPS's plastic style lets
    /// none break while it sets a run up).
    pub may_break: bool,
    /// `(V, V0)` per atom from [`accumulate_intact_volumes`]; `None` drops
    /// the multibody term.
    pub volumes: Option<(&'a [f64], &'a [f64])>,
    /// Whether to sum energy and virial.
    pub tally: bool,
}

/// What a pass over a failing bond list found.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ListFailures {
    /// Energy, virial and the first bond out of range.
    pub pass: ForcePass,
    /// Bonds that broke in this pass: their list indices are the first
    /// `broken` entries of the caller's buffer.
    pub broken: usize,
    /// Bonds whose plastic strain changed in this pass.
    pub yielded: usize,
}

/// Adds the forces of the intact bonds of `bonds` (type above 0) to `f`.
///
/// `plastic` holds each bond's plastic strain `e_p` (read, and written
/// where it yields); it may be empty when no rule yields. A bond that
/// breaks gets type 0 and its list index goes to `broken`, which must hold
/// a slot per bond (an `i32`, as the list's atom indices).
///
/// Runs on the widest instruction set this processor has; every build
/// gives the same forces, sums and breaks bit for bit.
///
/// # Panics
/// If a slice is shorter than the list needs, an index is out of range
/// (of any entry, broken ones too; `f` and the volumes cover every index,
/// ghosts included, whatever the ownership) or a type has no coefficients
/// or rule (the C ABI checks these first).
pub fn failing_list_forces<S: Separation>(
    sep: &S,
    inputs: &FailingListInputs,
    bonds: &mut [BondEntry],
    plastic: &mut [f64],
    own: Ownership,
    f: &mut [[f64; 3]],
    broken: &mut [i32],
) -> ListFailures {
    failing_list_forces_on(Isa::detect(), sep, inputs, bonds, plastic, own, f, broken)
}

/// [`failing_list_forces`] compiled for `isa` (the portable build when
/// this processor lacks it).
// One argument per array the pass reads or writes, as its C ABI passes them.
#[allow(clippy::too_many_arguments)]
pub fn failing_list_forces_on<S: Separation>(
    isa: Isa,
    sep: &S,
    inputs: &FailingListInputs,
    bonds: &mut [BondEntry],
    plastic: &mut [f64],
    own: Ownership,
    f: &mut [[f64; 3]],
    broken: &mut [i32],
) -> ListFailures {
    let yields = inputs.rules.iter().any(|r| r.plastic_strain.is_some());
    assert!(
        inputs.r0.len() >= bonds.len()
            && (!yields || plastic.len() >= bonds.len())
            && broken.len() >= bonds.len(),
        "failing bond list of {} bonds with {} lengths, {} plastic strains, {} broken slots",
        bonds.len(),
        inputs.r0.len(),
        plastic.len(),
        broken.len()
    );
    let mut out = ListOut {
        bonds,
        plastic,
        f,
        broken,
    };
    #[cfg(target_arch = "x86_64")]
    if isa == Isa::Avx2 && Isa::Avx2.available() {
        // SAFETY: the processor has AVX2 and FMA (checked just above).
        return unsafe { failing_list_avx2(sep, inputs, own, &mut out) };
    }
    let _ = isa;
    failing_list_terms(sep, inputs, own, &mut out)
}

/// What a pass over a failing list writes.
struct ListOut<'a> {
    bonds: &'a mut [BondEntry],
    plastic: &'a mut [f64],
    f: &'a mut [[f64; 3]],
    broken: &'a mut [i32],
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
unsafe fn failing_list_avx2<S: Separation>(
    sep: &S,
    inputs: &FailingListInputs,
    own: Ownership,
    out: &mut ListOut,
) -> ListFailures {
    failing_list_terms(sep, inputs, own, out)
}

/// The choice of terms is made once here, not per bond: each combination
/// is its own monomorphised loop.
#[inline(always)]
fn failing_list_terms<S: Separation>(
    sep: &S,
    inputs: &FailingListInputs,
    own: Ownership,
    out: &mut ListOut,
) -> ListFailures {
    match (inputs.volumes.is_some(), inputs.v.is_some(), inputs.tally) {
        (true, true, true) => failing_blocks::<S, true, true, true>(sep, inputs, own, out),
        (true, true, false) => failing_blocks::<S, true, true, false>(sep, inputs, own, out),
        (true, false, true) => failing_blocks::<S, true, false, true>(sep, inputs, own, out),
        (true, false, false) => failing_blocks::<S, true, false, false>(sep, inputs, own, out),
        (false, true, true) => failing_blocks::<S, false, true, true>(sep, inputs, own, out),
        (false, true, false) => failing_blocks::<S, false, true, false>(sep, inputs, own, out),
        (false, false, true) => failing_blocks::<S, false, false, true>(sep, inputs, own, out),
        (false, false, false) => failing_blocks::<S, false, false, false>(sep, inputs, own, out),
    }
}

/// One block's bonds, lane by lane: the bond, its coefficients, its rule
/// as numbers and flags, and the results.
struct FailingBlock {
    n: [usize; LANES],
    i: [usize; LANES],
    j: [usize; LANES],
    /// Lanes without a bond to compute: type 0 or below, or past the list.
    idle: [bool; LANES],
    dx: [f64; LANES],
    dy: [f64; LANES],
    dz: [f64; LANES],
    r0: [f64; LANES],
    k: [f64; LANES],
    a: [f64; LANES],
    gamma: [f64; LANES],
    /// `eps_c` where the bond may break in this pass, infinity elsewhere.
    critical: [f64; LANES],
    smooth: [bool; LANES],
    inverse_critical: [f64; LANES],
    yields: [bool; LANES],
    eps_p: [f64; LANES],
    normalize: [bool; LANES],
    /// `e_p` on entry (0 where the rule does not yield), then after.
    e_p: [f64; LANES],
    e_p_before: [f64; LANES],
    /// `V_i + V_j` and `V0_i + V0_j`.
    vsum: [f64; LANES],
    v0sum: [f64; LANES],
    del_dot_dv: [f64; LANES],
    broke: [bool; LANES],
    r: [f64; LANES],
    fpair: [f64; LANES],
    energy: [f64; LANES],
}

impl FailingBlock {
    fn new() -> Self {
        Self {
            n: [0; LANES],
            i: [0; LANES],
            j: [0; LANES],
            idle: [true; LANES],
            dx: [1.0; LANES],
            dy: [0.0; LANES],
            dz: [0.0; LANES],
            r0: [1.0; LANES],
            k: [0.0; LANES],
            a: [0.0; LANES],
            gamma: [0.0; LANES],
            critical: [f64::INFINITY; LANES],
            smooth: [false; LANES],
            inverse_critical: [0.0; LANES],
            yields: [false; LANES],
            eps_p: [0.0; LANES],
            normalize: [false; LANES],
            e_p: [0.0; LANES],
            e_p_before: [0.0; LANES],
            vsum: [1.0; LANES],
            v0sum: [1.0; LANES],
            del_dot_dv: [0.0; LANES],
            broke: [false; LANES],
            r: [1.0; LANES],
            fpair: [0.0; LANES],
            energy: [0.0; LANES],
        }
    }

    /// Lane `l` gets a bond type's coefficients and rule.
    #[inline(always)]
    fn set_type(&mut self, l: usize, c: &BondCoeffs, rule: &BondFailure, may_break: bool) {
        self.k[l] = c.k;
        self.a[l] = c.a;
        self.gamma[l] = c.gamma;
        self.critical[l] = if rule.breaks && may_break {
            rule.critical_strain
        } else {
            f64::INFINITY
        };
        self.smooth[l] = rule.smooth;
        self.inverse_critical[l] = 1.0 / rule.critical_strain;
        self.yields[l] = rule.plastic_strain.is_some();
        self.eps_p[l] = rule.plastic_strain.unwrap_or(0.0);
        self.normalize[l] = rule.normalize;
    }

    /// Lane `l` idles: a harmless bond (unit length, unit volume ratio, no
    /// velocity: zero force, finite arithmetic) that is never scattered.
    #[inline(always)]
    fn idle(&mut self, l: usize) {
        self.idle[l] = true;
        self.dx[l] = 1.0;
        self.dy[l] = 0.0;
        self.dz[l] = 0.0;
        self.r0[l] = 1.0;
        self.e_p[l] = 0.0;
        self.vsum[l] = 1.0;
        self.v0sum[l] = 1.0;
        self.del_dot_dv[l] = 0.0;
    }
}

// Lane loops index several per-lane arrays at once; that form vectorises.
#[allow(clippy::needless_range_loop)]
#[inline(always)]
fn failing_blocks<S: Separation, const MULTIBODY: bool, const DAMPED: bool, const TALLY: bool>(
    sep: &S,
    inputs: &FailingListInputs,
    own: Ownership,
    out: &mut ListOut,
) -> ListFailures {
    let x = inputs.x;
    let (vol, vol0) = inputs.volumes.unwrap_or((&[], &[]));
    let v = inputs.v.unwrap_or(&[]);
    let mut result = ListFailures::default();
    let mut tally = Tally::default();
    let mut b = FailingBlock::new();
    let mut run = RunningSum::new();
    // One bond type (the usual case): its coefficients and rule fill every
    // lane once here instead of being looked up bond by bond.
    let single_type = inputs.coeffs.len() == 1;
    if single_type && !out.bonds.is_empty() {
        for l in 0..LANES {
            b.set_type(l, &inputs.coeffs[0], &inputs.rules[0], inputs.may_break);
        }
    }
    let n = out.bonds.len();
    let mut start = 0;
    while start < n {
        let lanes = LANES.min(n - start);
        // Gather.
        for l in 0..LANES {
            let bond = match out.bonds.get(start + l) {
                Some(bond) if l < lanes && bond.ty > 0 => *bond,
                _ => {
                    b.idle(l);
                    continue;
                }
            };
            let (i, j) = (bond.i as usize, bond.j as usize);
            let ty = (bond.ty - 1) as usize;
            if single_type {
                assert!(ty == 0, "bond type {} has no coefficients", bond.ty);
            } else {
                b.set_type(l, &inputs.coeffs[ty], &inputs.rules[ty], inputs.may_break);
            }
            let del = sep.delta(&x[i], &x[j]);
            b.n[l] = start + l;
            b.i[l] = i;
            b.j[l] = j;
            b.idle[l] = false;
            b.dx[l] = del[0];
            b.dy[l] = del[1];
            b.dz[l] = del[2];
            b.r0[l] = inputs.r0[start + l];
            b.e_p[l] = if b.yields[l] {
                out.plastic[start + l]
            } else {
                0.0
            };
            if MULTIBODY {
                b.vsum[l] = vol[i] + vol[j];
                b.v0sum[l] = vol0[i] + vol0[j];
            }
            if DAMPED {
                b.del_dot_dv[l] = dot(&del, &sub(&v[i], &v[j]));
            }
        }
        // Arithmetic, lane by lane: failing_bond_force with its branches
        // as selects.
        b.e_p_before = b.e_p;
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
            let e = (r - b.r0[l]) * (1.0 / b.r0[l]);
            // A bond to a particle gone to infinity is a blow-up to report,
            // not a break.
            b.broke[l] = e.abs() > b.critical[l] && r < f64::INFINITY;
            let yielded = plastic_strain_after(e, b.e_p[l], b.eps_p[l]);
            let e_p = if b.yields[l] { yielded } else { b.e_p[l] };
            let r_eq = b.r0[l] * (1.0 + e_p);
            let stretch = r - r_eq;
            let mut fmag = if b.normalize[l] {
                -b.k[l] * (e - e_p)
            } else {
                -b.k[l] * stretch
            };
            if MULTIBODY {
                fmag += b.a[l] * (dilation[l] - r * (1.0 / r_eq));
            }
            if DAMPED {
                fmag -= b.gamma[l] * b.del_dot_dv[l] * rinv;
            }
            let smoothed = fmag * smoothing(e, b.inverse_critical[l]);
            if b.smooth[l] {
                fmag = smoothed;
            }
            b.e_p[l] = e_p;
            b.r[l] = r;
            b.fpair[l] = fmag * rinv;
            if TALLY {
                let energy = 0.5 * b.k[l] * stretch * stretch;
                b.energy[l] = if b.normalize[l] {
                    energy / b.r0[l]
                } else {
                    energy
                };
            }
            // Written so that NaN fails it too.
            let in_range = r > COLLAPSED_BELOW * b.r0[l]
                && r < OVERSTRETCHED_ABOVE * b.r0[l]
                && b.fpair[l].abs() < f64::INFINITY;
            out_of_range |= !in_range && !b.broke[l] && !b.idle[l];
        }
        if out_of_range && result.pass.fault.is_none() {
            result.pass.fault = (0..lanes)
                .filter(|&l| !b.broke[l] && !b.idle[l])
                .find_map(|l| Fault::of_bond(b.n[l], b.i[l], b.j[l], b.r[l], b.r0[l], b.fpair[l]));
        }
        // Scatter, in list order.
        for l in 0..lanes {
            if b.idle[l] {
                continue;
            }
            let (n, i, j) = (b.n[l], b.i[l], b.j[l]);
            if b.broke[l] {
                out.bonds[n].ty = 0;
                out.broken[result.broken] = n as i32;
                result.broken += 1;
                continue;
            }
            if b.e_p[l] != b.e_p_before[l] {
                out.plastic[n] = b.e_p[l];
                result.yielded += 1;
            }
            let del = [b.dx[l], b.dy[l], b.dz[l]];
            let (on_i, on_j, frac) = own.split(i, j);
            apply_pair_force_in_run(&mut run, out.f, i, j, on_i, on_j, &del, b.fpair[l]);
            if TALLY {
                tally.add(frac, b.energy[l], &del, b.fpair[l]);
            }
        }
        start += lanes;
    }
    run.finish(out.f);
    result.pass.tally = tally;
    result
}

/// Adds `r^3` of each intact bond (type above 0) to `vol` and `r_eq^3`,
/// with `r_eq = (1 + e_p) r0` from its first length and plastic strain,
/// to `vol0` (`plastic` empty: `e_p = 0`).
///
/// Runs on the widest instruction set this processor has; every build
/// gives the same volumes bit for bit.
///
/// # Panics
/// If an index of any entry (broken ones too) is outside `x`, `vol` or
/// `vol0` (which cover every index, ghosts included, whatever the
/// ownership), or `r0` is shorter than the list.
pub fn accumulate_intact_volumes<S: Separation>(
    sep: &S,
    x: &[[f64; 3]],
    bonds: &[BondEntry],
    lengths: (&[f64], &[f64]),
    own: Ownership,
    volumes: (&mut [f64], &mut [f64]),
) {
    accumulate_intact_volumes_on(Isa::detect(), sep, x, bonds, lengths, own, volumes)
}

/// [`accumulate_intact_volumes`] compiled for `isa` (the portable build
/// when this processor lacks it).
pub fn accumulate_intact_volumes_on<S: Separation>(
    isa: Isa,
    sep: &S,
    x: &[[f64; 3]],
    bonds: &[BondEntry],
    lengths: (&[f64], &[f64]),
    own: Ownership,
    volumes: (&mut [f64], &mut [f64]),
) {
    #[cfg(target_arch = "x86_64")]
    if isa == Isa::Avx2 && Isa::Avx2.available() {
        // SAFETY: the processor has AVX2 and FMA (checked just above).
        return unsafe { intact_volumes_avx2(sep, x, bonds, lengths, own, volumes) };
    }
    let _ = isa;
    intact_volume_blocks(sep, x, bonds, lengths, own, volumes)
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
unsafe fn intact_volumes_avx2<S: Separation>(
    sep: &S,
    x: &[[f64; 3]],
    bonds: &[BondEntry],
    lengths: (&[f64], &[f64]),
    own: Ownership,
    volumes: (&mut [f64], &mut [f64]),
) {
    intact_volume_blocks(sep, x, bonds, lengths, own, volumes)
}

/// Blocks of [`LANES`] bonds: separations and rest lengths gathered, the
/// cubes computed lane by lane, then added to the atoms in list order.
// Lane loops index several per-lane arrays at once; that form vectorises.
#[allow(clippy::needless_range_loop)]
#[inline(always)]
fn intact_volume_blocks<S: Separation>(
    sep: &S,
    x: &[[f64; 3]],
    bonds: &[BondEntry],
    (r0, plastic): (&[f64], &[f64]),
    own: Ownership,
    (vol, vol0): (&mut [f64], &mut [f64]),
) {
    let mut rsq = [0.0; LANES];
    let mut r_eq = [0.0; LANES];
    let mut r3 = [0.0; LANES];
    let mut r_eq3 = [0.0; LANES];
    let (mut run, mut run0) = (RunningSum::new(), RunningSum::new());
    for (block_start, block) in (0..).step_by(LANES).zip(bonds.chunks(LANES)) {
        for (l, bond) in block.iter().enumerate() {
            let n = block_start + l;
            let del = sep.delta(&x[bond.i as usize], &x[bond.j as usize]);
            rsq[l] = dot(&del, &del);
            r_eq[l] = r0[n] * (1.0 + plastic.get(n).copied().unwrap_or(0.0));
        }
        for l in 0..LANES {
            r3[l] = rsq[l] * rsq[l].sqrt();
            r_eq3[l] = r_eq[l] * r_eq[l] * r_eq[l];
        }
        for (l, bond) in block.iter().enumerate() {
            if bond.ty <= 0 {
                continue;
            }
            let (i, j) = (bond.i as usize, bond.j as usize);
            let (on_i, on_j, _) = own.split(i, j);
            let (vi, v0i) = (run.first(i, vol), run0.first(i, vol0));
            if on_i {
                *vi += r3[l];
                *v0i += r_eq3[l];
            }
            if on_j {
                *run.second(j, vol) += r3[l];
                *run0.second(j, vol0) += r_eq3[l];
            }
        }
    }
    run.finish(vol);
    run0.finish(vol0);
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::kernels::bond::dilation;
    use crate::kernels::bond_failure::{failing_bond_energy, failing_bond_force};
    use crate::kernels::tally::apply_pair_force;
    use crate::kernels::Unwrapped;
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    /// The pass bond by bond, as [`failing_bond_force`] states the rules:
    /// what the blocks must reproduce bit for bit.
    fn bond_by_bond(
        inputs: &FailingListInputs,
        bonds: &mut [BondEntry],
        plastic: &mut [f64],
        own: Ownership,
        f: &mut [[f64; 3]],
        broken: &mut [i32],
    ) -> ListFailures {
        let x = inputs.x;
        let mut out = ListFailures::default();
        let mut tally = Tally::default();
        for (n, bond) in bonds.iter_mut().enumerate() {
            if bond.ty <= 0 {
                continue;
            }
            let (i, j) = (bond.i as usize, bond.j as usize);
            let ty = (bond.ty - 1) as usize;
            let c = &inputs.coeffs[ty];
            let rule = BondFailure {
                breaks: inputs.rules[ty].breaks && inputs.may_break,
                ..inputs.rules[ty]
            };
            let r0 = inputs.r0[n];
            let del = sub(&x[i], &x[j]);
            let r = dot(&del, &del).sqrt();
            let rinv = 1.0 / r;
            let dil = inputs
                .volumes
                .map(|(vol, vol0)| dilation(vol[i], vol[j], vol0[i], vol0[j]));
            let damping = inputs
                .v
                .map_or(0.0, |v| c.gamma * dot(&del, &sub(&v[i], &v[j])) * rinv);
            let before = if rule.plastic_strain.is_some() {
                plastic[n]
            } else {
                0.0
            };
            let mut e_p = before;
            let Some(fmag) = failing_bond_force(r, r0, &mut e_p, dil, damping, c, &rule) else {
                bond.ty = 0;
                broken[out.broken] = n as i32;
                out.broken += 1;
                continue;
            };
            if e_p != before {
                plastic[n] = e_p;
                out.yielded += 1;
            }
            let fpair = fmag * rinv;
            if out.pass.fault.is_none() {
                out.pass.fault = Fault::of_bond(n, i, j, r, r0, fpair);
            }
            let (on_i, on_j, frac) = own.split(i, j);
            apply_pair_force(f, i, j, on_i, on_j, &del, fpair);
            if inputs.tally {
                tally.add(frac, failing_bond_energy(r, r0, e_p, c, &rule), &del, fpair);
            }
        }
        out.pass.tally = tally;
        out
    }

    /// A random list over `atoms` atoms on a jiggled line, stretched by up
    /// to `strain` around rest lengths near 1, with some idle entries.
    struct Scene {
        x: Vec<[f64; 3]>,
        v: Vec<[f64; 3]>,
        bonds: Vec<BondEntry>,
        r0: Vec<f64>,
        plastic: Vec<f64>,
        vol: Vec<f64>,
        vol0: Vec<f64>,
    }

    fn scene(seed: u64, nbonds: usize, types: i32, strain: f64) -> Scene {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let mut x = Vec::new();
        let mut r0 = Vec::new();
        let mut bonds = Vec::new();
        for n in 0..nbonds {
            let rest = rng.gen_range(0.9..1.1);
            let r = rest * (1.0 + rng.gen_range(-strain..strain));
            let dir = [rng.gen_range(-1.0..1.0), rng.gen_range(-1.0..1.0), 1.0];
            let norm = dot(&dir, &dir).sqrt();
            let origin = [3.0 * n as f64, 0.0, 0.0];
            x.push(origin);
            x.push([
                origin[0] + r * dir[0] / norm,
                origin[1] + r * dir[1] / norm,
                origin[2] + r * dir[2] / norm,
            ]);
            r0.push(rest);
            let ty = if rng.gen_bool(0.1) {
                0
            } else {
                rng.gen_range(1..=types)
            };
            // Either order, so that both ends are sometimes the ghost.
            let (i, j) = if rng.gen_bool(0.5) {
                (2 * n, 2 * n + 1)
            } else {
                (2 * n + 1, 2 * n)
            };
            bonds.push(BondEntry {
                i: i as i32,
                j: j as i32,
                ty,
            });
        }
        with_motion_and_volumes(x, bonds, r0, &mut rng)
    }

    /// A scene of `x` and its list, with random velocities and volumes
    /// (dilations from 3% to 40%: every range of the cube root) and
    /// plastic strains from -0.02 to 0.02.
    fn with_motion_and_volumes(
        x: Vec<[f64; 3]>,
        bonds: Vec<BondEntry>,
        r0: Vec<f64>,
        rng: &mut ChaCha8Rng,
    ) -> Scene {
        let atoms = x.len();
        let v = (0..atoms)
            .map(|_| [(); 3].map(|_| rng.gen_range(-0.1..0.1)))
            .collect();
        let vol0: Vec<f64> = (0..atoms).map(|_| rng.gen_range(5.0..7.0)).collect();
        let vol = vol0
            .iter()
            .enumerate()
            .map(|(n, v0)| v0 * (0.6 + 0.8 * (n % 7) as f64 / 6.0))
            .collect();
        let plastic = (0..bonds.len())
            .map(|n| 0.01 * ((n % 5) as f64 - 2.0))
            .collect();
        Scene {
            x,
            v,
            bonds,
            r0,
            plastic,
            vol,
            vol0,
        }
    }

    /// A list in LAMMPS's order: atoms on a jiggled line, each first atom
    /// bonded to the next three (runs of three entries sharing it), rest
    /// lengths within `strain` of the bonds' lengths, some entries idle.
    fn scene_in_runs(seed: u64, atoms: usize, types: i32, strain: f64) -> Scene {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let x: Vec<[f64; 3]> = (0..atoms)
            .map(|a| {
                [
                    0.9 * a as f64 + rng.gen_range(-0.1..0.1),
                    rng.gen_range(-0.2..0.2),
                    rng.gen_range(-0.2..0.2),
                ]
            })
            .collect();
        let (mut bonds, mut r0) = (Vec::new(), Vec::new());
        for i in 0..atoms {
            for j in i + 1..(i + 4).min(atoms) {
                let del = sub(&x[i], &x[j]);
                r0.push(dot(&del, &del).sqrt() / (1.0 + rng.gen_range(-strain..strain)));
                let ty = if rng.gen_bool(0.1) {
                    0
                } else {
                    rng.gen_range(1..=types)
                };
                bonds.push(BondEntry {
                    i: i as i32,
                    j: j as i32,
                    ty,
                });
            }
        }
        with_motion_and_volumes(x, bonds, r0, &mut rng)
    }

    const COEFFS: [BondCoeffs; 3] = [
        BondCoeffs {
            k: 2.0,
            a: -0.7,
            gamma: 0.3,
        },
        BondCoeffs {
            k: 1.0,
            a: 0.4,
            gamma: 0.0,
        },
        BondCoeffs {
            k: 3.0,
            a: 0.0,
            gamma: 1.0,
        },
    ];

    fn rules() -> [BondFailure; 3] {
        [
            BondFailure::breaking(0.04),
            BondFailure {
                plastic_strain: Some(0.02),
                normalize: true,
                ..BondFailure::breaking(0.05)
            },
            BondFailure {
                breaks: false,
                smooth: false,
                plastic_strain: Some(0.01),
                normalize: false,
                critical_strain: 0.03,
            },
        ]
    }

    /// Runs both passes on `s` and asserts the same bits everywhere.
    fn assert_blocks_match_bond_by_bond(
        isa: Isa,
        s: &Scene,
        types: usize,
        flags: [bool; 4],
        own: Ownership,
    ) {
        let [multibody, damped, tally, may_break] = flags;
        let rules = rules();
        let inputs = FailingListInputs {
            x: &s.x,
            v: damped.then_some(&s.v[..]),
            r0: &s.r0,
            coeffs: &COEFFS[..types],
            rules: &rules[..types],
            may_break,
            volumes: multibody.then_some((&s.vol[..], &s.vol0[..])),
            tally,
        };
        let n = s.bonds.len();
        let run = |blocks: bool| {
            let (mut bonds, mut plastic) = (s.bonds.clone(), s.plastic.clone());
            let (mut f, mut broken) = (vec![[0.0; 3]; s.x.len()], vec![-1; n]);
            let found = if blocks {
                failing_list_forces_on(
                    isa,
                    &Unwrapped,
                    &inputs,
                    &mut bonds,
                    &mut plastic,
                    own,
                    &mut f,
                    &mut broken,
                )
            } else {
                bond_by_bond(&inputs, &mut bonds, &mut plastic, own, &mut f, &mut broken)
            };
            let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
            let f_bits: Vec<u64> = f.iter().flatten().map(|x| x.to_bits()).collect();
            (found, bonds, bits(&plastic), f_bits, broken)
        };
        let (blocks, by_bond) = (run(true), run(false));
        assert_eq!(blocks.0.broken, by_bond.0.broken, "{isa:?} {flags:?}");
        assert_eq!(blocks.0.yielded, by_bond.0.yielded, "{isa:?} {flags:?}");
        assert_eq!(
            blocks.0.pass.fault, by_bond.0.pass.fault,
            "{isa:?} {flags:?}"
        );
        let sums = |t: &Tally| (t.energy.to_bits(), t.virial.map(f64::to_bits));
        assert_eq!(sums(&blocks.0.pass.tally), sums(&by_bond.0.pass.tally));
        assert_eq!(blocks.1, by_bond.1, "types after the pass");
        assert_eq!(blocks.2, by_bond.2, "plastic strains");
        assert_eq!(blocks.3, by_bond.3, "forces");
        assert_eq!(blocks.4, by_bond.4, "broken list");
    }

    #[test]
    fn the_blocks_give_the_bond_by_bond_rules_bit_for_bit() {
        for isa in [Isa::Portable, Isa::detect()] {
            for (seed, types) in [(1, 1), (2, 2), (3, 3)] {
                // 61 bonds: seven full blocks and a partial one; then 41
                // atoms' runs of three bonds under each first atom, the
                // last third of the atoms ghosts (runs of ghost first
                // atoms), with newton_bond off and on.
                let scenes = [
                    scene(seed, 61, types as i32, 0.08),
                    scene_in_runs(seed, 41, types as i32, 0.08),
                ];
                for s in &scenes {
                    for newton in [false, true] {
                        let own = Ownership {
                            n_owned: s.x.len() * 2 / 3,
                            newton,
                        };
                        for flags in 0..16u8 {
                            let flags = [0, 1, 2, 3].map(|b| flags & (1 << b) != 0);
                            assert_blocks_match_bond_by_bond(isa, s, types, flags, own);
                        }
                    }
                }
            }
        }
    }

    #[test]
    fn the_scene_exercises_breaks_yields_idle_entries_and_a_fault() {
        let mut s = scene(2, 61, 2, 0.08);
        let rules = rules();
        let inputs = FailingListInputs {
            x: &s.x,
            v: None,
            r0: &s.r0,
            coeffs: &COEFFS[..2],
            rules: &rules[..2],
            may_break: true,
            volumes: None,
            tally: true,
        };
        let (mut f, mut broken) = (vec![[0.0; 3]; s.x.len()], vec![-1; 61]);
        let own = Ownership::all(s.x.len());
        let mut bonds = s.bonds.clone();
        let found = failing_list_forces(
            &Unwrapped,
            &inputs,
            &mut bonds,
            &mut s.plastic,
            own,
            &mut f,
            &mut broken,
        );
        let idle = s.bonds.iter().filter(|b| b.ty == 0).count();
        assert!(
            found.broken > 3 && found.yielded > 3 && idle > 2,
            "{found:?}, {idle} idle"
        );
        for &n in &broken[..found.broken] {
            assert_eq!(bonds[n as usize].ty, 0, "a broken bond gets type 0");
            assert!(s.bonds[n as usize].ty > 0, "an idle entry does not break");
        }
        // One bond stretched fourfold without breaking is a fault, found
        // in its block as bond by bond.
        let mut s = scene(4, 61, 3, 0.02);
        let far = (0..61).rev().find(|&n| s.bonds[n].ty == 3).unwrap();
        let (i, j) = (s.bonds[far].i as usize, s.bonds[far].j as usize);
        for d in 0..3 {
            s.x[j][d] = s.x[i][d] + 4.0 * (s.x[j][d] - s.x[i][d]);
        }
        for isa in [Isa::Portable, Isa::detect()] {
            let own = Ownership::all(s.x.len());
            assert_blocks_match_bond_by_bond(isa, &s, 3, [true, true, true, true], own);
        }
        let inputs = FailingListInputs {
            x: &s.x,
            v: None,
            r0: &s.r0,
            coeffs: &COEFFS,
            rules: &rules,
            may_break: true,
            volumes: None,
            tally: false,
        };
        let mut bonds = s.bonds.clone();
        let found = failing_list_forces(
            &Unwrapped,
            &inputs,
            &mut bonds,
            &mut s.plastic,
            own,
            &mut f,
            &mut broken,
        );
        assert_eq!(found.pass.fault.map(|f| f.bond), Some(far as i64));
    }

    #[test]
    fn intact_volumes_match_bond_by_bond_sums() {
        let own = Ownership {
            n_owned: 80,
            newton: false,
        };
        let scenes = [scene(5, 61, 2, 0.05), scene_in_runs(5, 122, 2, 0.05)];
        for (s, isa) in scenes
            .iter()
            .flat_map(|s| [(s, Isa::Portable), (s, Isa::detect())])
        {
            for plastic in [&s.plastic[..], &[]] {
                let mut vol = vec![0.0; s.x.len()];
                let mut vol0 = vec![0.0; s.x.len()];
                accumulate_intact_volumes_on(
                    isa,
                    &Unwrapped,
                    &s.x,
                    &s.bonds,
                    (&s.r0, plastic),
                    own,
                    (&mut vol, &mut vol0),
                );
                let mut want = vec![0.0; s.x.len()];
                let mut want0 = vec![0.0; s.x.len()];
                for (n, b) in s.bonds.iter().enumerate().filter(|(_, b)| b.ty > 0) {
                    let (i, j) = (b.i as usize, b.j as usize);
                    let del = sub(&s.x[i], &s.x[j]);
                    let rsq = dot(&del, &del);
                    let r_eq = s.r0[n] * (1.0 + plastic.get(n).copied().unwrap_or(0.0));
                    for atom in [i, j].into_iter().filter(|&a| a < 80) {
                        want[atom] += rsq * rsq.sqrt();
                        want0[atom] += r_eq * r_eq * r_eq;
                    }
                }
                assert_eq!(vol, want);
                assert_eq!(vol0, want0);
                assert!(vol.iter().filter(|&&v| v > 0.0).count() > 40);
            }
        }
    }
}
