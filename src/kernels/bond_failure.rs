//! Bonds that break and yield (docs/model.md, "Breaking and yielding").
//!
//! A bond keeps its first length `r0` and a plastic strain `e_p`; its rest
//! length is `r_eq = (1 + e_p) r0` and its strain `e = (r - r0) / r0`.
//!
//! - **Breaking**: a bond with `|e| > eps_c` breaks. It exerts no force in
//!   the step it breaks, and its two particles interact through the contact
//!   law from the next step on (already, if the contacts are overlaid on
//!   the bonds).
//! - **Smoothing**: the whole bond force (spring, multibody term and
//!   damping) is multiplied by `w = 1 - (e / eps_c)^8`, which falls to 0
//!   at the critical strain, so a bond lets go without a jump in force.
//! - **Yielding**: `e_p` moves so that `|e - e_p| <= eps_p`. The spring is
//!   `k (r_eq - r)`, or `-k (e - e_p)` with `normalize`, and the multibody
//!   term `a (D - r / r_eq)`; under steady stretching the spring force
//!   levels off at `k eps_p r0`.
//!
//! These are the rules of upstream LAMMPS's `bpm/spring` and
//! `bpm/spring/plastic` bond styles; the multibody term with yielding is
//! ours (upstream's plastic style has no volume term). A bond whose `e_p`
//! is 0 gets, bit for bit, the force of the elastic kernels times `w`.

use super::bond::{cube_root, reciprocal, BondCoeffs};
use super::bond_rows::{
    gather_by_particle, settle_checked_row, BondRows, LaneTally, RowForce, RowInputs, AS_J,
};
use super::fault::{ForcePass, COLLAPSED_BELOW, OVERSTRETCHED_ABOVE};
use super::isa::Isa;
use super::plastic_rows::{rest_length, Band, PlasticRows, PlasticSection, RawPlastic};
use super::Separation;
use std::ops::Range;

/// How bonds of one type break and yield; absent, they do neither.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BondFailure {
    /// Critical strain `eps_c` (dimensionless, > 0): a bond breaks when
    /// `|r - r0| / r0` exceeds it; also the scale of the smoothing.
    pub critical_strain: f64,
    /// Whether bonds break (upstream's `break`); default true.
    #[serde(default = "yes")]
    pub breaks: bool,
    /// Whether the bond force is smoothed to 0 at the critical strain
    /// (upstream's `smooth`); default true. Needs `breaks`.
    #[serde(default = "yes")]
    pub smooth: bool,
    /// Plastic strain `eps_p` (dimensionless, 0 < eps_p < eps_c): the rest
    /// length follows the bond so that `|e - e_p| <= eps_p`; absent, bonds
    /// stay elastic.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub plastic_strain: Option<f64>,
    /// The spring in strain, `-k (e - e_p)`, instead of in length,
    /// `-k (r - r_eq)` (upstream's `normalize`); default false.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub normalize: bool,
}

fn yes() -> bool {
    true
}

/// A [`BondFailure`] the model cannot use, naming the value.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum BondFailureError {
    /// `eps_c` not positive and finite, or so small its reciprocal is not.
    #[error("the critical strain eps_c = {0} must be positive and finite (and above 1e-300)")]
    CriticalStrain(f64),
    /// `eps_p` not positive and finite.
    #[error("the plastic strain eps_p = {0} must be positive and finite")]
    PlasticStrain(f64),
    /// `eps_p >= eps_c`: the bond would break before it yields.
    #[error(
        "the plastic strain eps_p = {plastic} must be below the critical strain eps_c = \
         {critical}: a bond would break before it yields"
    )]
    YieldsAfterBreaking {
        /// `eps_p`.
        plastic: f64,
        /// `eps_c`.
        critical: f64,
    },
    /// Smoothing asked for without breaking (upstream refuses it too).
    #[error(
        "smoothing needs breaking: with breaks false, set smooth false too (beyond eps_c \
         the smoothing factor turns negative and grows: the force would reverse)"
    )]
    SmoothWithoutBreaking,
}

impl BondFailure {
    /// Upstream's defaults for a critical strain: bonds break, smoothed,
    /// elastic until they break.
    pub fn breaking(critical_strain: f64) -> Self {
        Self {
            critical_strain,
            breaks: true,
            smooth: true,
            plastic_strain: None,
            normalize: false,
        }
    }

    /// The first value the model cannot use.
    pub fn check(&self) -> Result<(), BondFailureError> {
        let eps_c = self.critical_strain;
        if !(eps_c.is_finite() && eps_c > 0.0 && (1.0 / eps_c).is_finite()) {
            return Err(BondFailureError::CriticalStrain(eps_c));
        }
        if let Some(eps_p) = self.plastic_strain {
            if !(eps_p.is_finite() && eps_p > 0.0) {
                return Err(BondFailureError::PlasticStrain(eps_p));
            }
            if self.breaks && eps_p >= eps_c {
                return Err(BondFailureError::YieldsAfterBreaking {
                    plastic: eps_p,
                    critical: eps_c,
                });
            }
        }
        if self.smooth && !self.breaks {
            return Err(BondFailureError::SmoothWithoutBreaking);
        }
        Ok(())
    }

    /// Whether bonds behave differently from elastic ones at all: they
    /// break, yield or have a spring in strain.
    pub fn is_live(&self) -> bool {
        self.breaks || self.plastic_strain.is_some() || self.normalize
    }
}

/// A bond's plastic strain after it reaches strain `e`, from `e_p`: moved
/// just enough that `|e - e_p| <= eps_p`.
#[inline(always)]
pub fn plastic_strain_after(e: f64, e_p: f64, eps_p: f64) -> f64 {
    if e > e_p + eps_p {
        e - eps_p
    } else if e < e_p - eps_p {
        e + eps_p
    } else {
        e_p
    }
}

/// The smoothing factor `1 - (e / eps_c)^8`, from `1 / eps_c` (a product
/// where upstream divides: the same to round-off, and cheaper).
#[inline(always)]
pub fn smoothing(e: f64, inverse_critical_strain: f64) -> f64 {
    let s = e * inverse_critical_strain;
    let s2 = s * s;
    let s4 = s2 * s2;
    1.0 - s4 * s4
}

/// One bond's force magnitude along `+n` on atom `i` (positive pushes
/// apart), or `None` if it breaks at length `r`; updates its plastic
/// strain `e_p` first. `dilation` is `D_ij` if the multibody term is on;
/// `damping` is the damping force `Gamma (n . dv)`, formed by the caller as
/// its elastic kernel forms it, so that an unyielded, unsmoothed bond gets
/// that kernel's force bit for bit.
#[inline(always)]
pub fn failing_bond_force(
    r: f64,
    r0: f64,
    e_p: &mut f64,
    dilation: Option<f64>,
    damping: f64,
    c: &BondCoeffs,
    rule: &BondFailure,
) -> Option<f64> {
    let e = (r - r0) * reciprocal(r0);
    // A bond to a particle gone to infinity is a blow-up to report, not a
    // break.
    if rule.breaks && e.abs() > rule.critical_strain && r < f64::INFINITY {
        return None;
    }
    if let Some(eps_p) = rule.plastic_strain {
        *e_p = plastic_strain_after(e, *e_p, eps_p);
    }
    let r_eq = r0 * (1.0 + *e_p);
    let mut f = if rule.normalize {
        -c.k * (e - *e_p)
    } else {
        -c.k * (r - r_eq)
    };
    if let Some(d) = dilation {
        f += c.a * (d - r * reciprocal(r_eq));
    }
    f -= damping;
    if rule.smooth {
        f *= smoothing(e, 1.0 / rule.critical_strain);
    }
    Some(f)
}

/// A failing bond's spring-proxy energy at length `r`: `k (r - r_eq)^2 / 2`,
/// over `r0` with `normalize` (the energy of the spring in strain).
#[inline(always)]
pub fn failing_bond_energy(r: f64, r0: f64, e_p: f64, c: &BondCoeffs, rule: &BondFailure) -> f64 {
    let stretch = r - r0 * (1.0 + e_p);
    let energy = 0.5 * c.k * stretch * stretch;
    if rule.normalize {
        energy / r0
    } else {
        energy
    }
}

/// What a pass over failing bonds found besides forces.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct FailurePass {
    /// Energy, virial and the first row out of range.
    pub pass: ForcePass,
    /// Rows that broke in this pass (marked in their force rows).
    pub broken: usize,
    /// Rows whose plastic strain changed in this pass.
    pub yielded: usize,
}

impl FailurePass {
    /// This pass followed by `later`.
    pub fn merged(&self, later: &Self) -> Self {
        Self {
            pass: self.pass.merged(&later.pass),
            broken: self.broken + later.broken,
            yielded: self.yielded + later.yielded,
        }
    }
}

/// Whether a force row from [`failing_row_forces`] belongs to a bond that
/// broke in that pass.
#[inline(always)]
pub fn row_broke(row: &[f64; 4]) -> bool {
    row[3].is_nan()
}

/// A strain no bond within reaches a fault: half the reference length
/// either way lies well inside [`COLLAPSED_BELOW`] and
/// [`OVERSTRETCHED_ABOVE`], rounding and all.
const CALM_STRAIN: f64 = 0.5;
const _: () = assert!(1.0 - CALM_STRAIN > 1.01 * COLLAPSED_BELOW);
const _: () = assert!(1.01 * (1.0 + CALM_STRAIN) < OVERSTRETCHED_ABOVE);

/// The strain within which no bond of `rule` breaks or reaches a fault.
fn calm_strain(rule: &BondFailure) -> f64 {
    if rule.breaks {
        rule.critical_strain.min(CALM_STRAIN)
    } else {
        CALM_STRAIN
    }
}

/// The band of a rule that yields.
fn band_of(rule: &BondFailure) -> Option<Band> {
    rule.plastic_strain.map(|plastic_strain| Band {
        plastic_strain,
        calm_strain: calm_strain(rule),
    })
}

/// The methods of [`PlasticRows`] that take the rule.
impl PlasticRows {
    /// Whether the bands are `rule`'s.
    pub fn banded_for(&self, rule: &BondFailure) -> bool {
        self.band().is_some() && self.band() == band_of(rule)
    }

    /// Draws the bands for `rule`, unless they are drawn for it.
    ///
    /// # Panics
    /// If `rule` does not yield.
    pub fn band_for(&mut self, rule: &BondFailure) {
        if !self.banded_for(rule) {
            self.draw(band_of(rule).expect("bands are drawn for a rule that yields"));
        }
    }
}

/// [`super::row_forces`] for bonds that break and yield.
///
/// With a rule that yields, `plastic` holds the plastic strains of the
/// rows `range` (banded for the rule, [`PlasticRows::band_for`]), which
/// the pass reads and moves; without, it must be `None`. A row whose bond
/// breaks gets zero force and `NaN` in its fourth value ([`row_broke`]);
/// the others get 0 there. The engine removes broken rows before the next
/// pass. With the multibody term, the rows' reference volumes are those of
/// the rest lengths ([`gather_rest_volumes`],
/// [`BondRows::set_reference_volumes`]). Runs on the widest instruction set
/// this processor has; every build gives the same rows, strains and sums
/// bit for bit.
pub fn failing_row_forces<S: Separation>(
    sep: &S,
    rows: &BondRows,
    range: Range<usize>,
    inputs: &RowInputs,
    rule: &BondFailure,
    plastic: Option<PlasticSection<'_>>,
    out: &mut [[f64; 4]],
) -> FailurePass {
    failing_row_forces_on(Isa::detect(), sep, rows, range, inputs, rule, plastic, out)
}

/// [`failing_row_forces`] compiled for `isa` (the portable build when this
/// processor lacks it).
#[allow(clippy::too_many_arguments)]
pub fn failing_row_forces_on<S: Separation>(
    isa: Isa,
    sep: &S,
    rows: &BondRows,
    range: Range<usize>,
    inputs: &RowInputs,
    rule: &BondFailure,
    plastic: Option<PlasticSection<'_>>,
    out: &mut [[f64; 4]],
) -> FailurePass {
    rows.check_inputs(&range, out.len(), inputs);
    match (&plastic, band_of(rule)) {
        (Some(section), Some(band)) => {
            assert_eq!(section.len(), range.len(), "one plastic strain per row");
            assert!(
                section.band == band,
                "plastic rows banded for another rule: call PlasticRows::band_for"
            );
        }
        (None, None) => {}
        (Some(_), None) => panic!("plastic strains given with a rule that does not yield"),
        (None, Some(_)) => panic!("a rule that yields needs the rows' plastic strains"),
    }
    let mut pass = FailingPass {
        sep,
        rows,
        inputs,
        rule,
        plastic,
    };
    let flags = (
        inputs.multibody.is_some(),
        inputs.v.is_some(),
        inputs.tally,
        rule.plastic_strain.is_some(),
    );
    macro_rules! dispatch {
        ($($mb:literal, $damped:literal, $tally:literal, $plastic:literal);*) => {
            match flags {
                $(($mb, $damped, $tally, $plastic) => {
                    pass.rows_on::<$mb, $damped, $tally, $plastic>(isa, range, out)
                })*
            }
        };
    }
    dispatch!(
        true, true, true, true; true, true, false, true; true, false, true, true;
        true, false, false, true; false, true, true, true; false, true, false, true;
        false, false, true, true; false, false, false, true;
        true, true, true, false; true, true, false, false; true, false, true, false;
        true, false, false, false; false, true, true, false; false, true, false, false;
        false, false, true, false; false, false, false, false
    )
}

/// What a failing pass reads, and the plastic strains it moves.
struct FailingPass<'a, S> {
    sep: &'a S,
    rows: &'a BondRows,
    inputs: &'a RowInputs<'a>,
    rule: &'a BondFailure,
    plastic: Option<PlasticSection<'a>>,
}

/// One intact row: its force and its new plastic strain.
struct IntactRow {
    force: RowForce,
    e_p: f64,
}

impl<S: Separation> FailingPass<'_, S> {
    /// Rows `range` into `out`: blocks of four with their energy and
    /// virial summed in lanes (as the elastic pass does), then the last
    /// rows one by one.
    #[inline(always)]
    fn rows_on<const MB: bool, const DAMPED: bool, const TALLY: bool, const PLASTIC: bool>(
        &mut self,
        isa: Isa,
        range: Range<usize>,
        out: &mut [[f64; 4]],
    ) -> FailurePass {
        let full = range.len() / 4 * 4;
        let mut lanes = LaneTally::default();
        let blocks = range.start..range.start + full;
        let mut result =
            self.blocks::<MB, DAMPED, TALLY, PLASTIC>(isa, blocks, &mut out[..full], &mut lanes);
        if TALLY {
            result.pass.tally = lanes.total();
        }
        for (k, out) in out.iter_mut().enumerate().skip(full) {
            self.settle::<MB, DAMPED, TALLY>(range.start, k, out, &mut result);
        }
        result
    }

    /// Row `k` of the range from `first` into `out` (its plastic strain
    /// read and moved in the pass's section), counted in `result`
    /// (tallied there with `TALLY`); returns its force if it held.
    #[inline(always)]
    fn settle<const MB: bool, const DAMPED: bool, const TALLY: bool>(
        &mut self,
        first: usize,
        k: usize,
        out: &mut [f64; 4],
        result: &mut FailurePass,
    ) -> Option<RowForce> {
        let row = first + k;
        let e_p = self.plastic.as_ref().map_or(0.0, |p| p.strain(k));
        let Some(intact) = self.row::<MB, DAMPED>(row, e_p) else {
            *out = BROKEN_ROW;
            result.broken += 1;
            return None;
        };
        let r0 = self.rows.r0(row);
        settle_checked_row::<TALLY>(self.rows, row, r0, &intact.force, &mut result.pass, out);
        if intact.e_p != e_p {
            result.yielded += 1;
            if let Some(plastic) = &mut self.plastic {
                plastic.set(k, r0, intact.e_p);
            }
        }
        Some(intact.force)
    }

    #[inline(always)]
    fn blocks<const MB: bool, const DAMPED: bool, const TALLY: bool, const PLASTIC: bool>(
        &mut self,
        isa: Isa,
        range: Range<usize>,
        out: &mut [[f64; 4]],
        lanes: &mut LaneTally,
    ) -> FailurePass {
        #[cfg(target_arch = "x86_64")]
        if isa == Isa::Avx2 && Isa::Avx2.available() {
            // SAFETY: the processor has AVX2; indices were checked by the
            // layout and lengths by the caller.
            return unsafe {
                avx2::failing_blocks::<S, MB, DAMPED, TALLY, PLASTIC>(self, range, out, lanes)
            };
        }
        let _ = isa;
        let mut result = FailurePass::default();
        for (k, out) in out.iter_mut().enumerate() {
            let force = self.settle::<MB, DAMPED, false>(range.start, k, out, &mut result);
            if let Some(force) = force.filter(|_| TALLY) {
                lanes.add(k % 4, &force);
            }
        }
        result
    }

    /// The fault of intact row `row`, whose plastic strain the pass left
    /// at `e_p`: the row settled again, on a copy, which gives the pass's
    /// force again (a yield sets `e_p` to `e -/+ eps_p`, where the rule
    /// leaves it).
    #[cfg(target_arch = "x86_64")]
    #[cold]
    #[inline(never)]
    fn fault_of<const MB: bool, const DAMPED: bool>(
        &self,
        row: usize,
        e_p: f64,
    ) -> Option<super::fault::Fault> {
        let intact = self.row::<MB, DAMPED>(row, e_p)?;
        let r0 = self.rows.r0(row);
        let mut probe = ForcePass::default();
        settle_checked_row::<false>(self.rows, row, r0, &intact.force, &mut probe, &mut [0.0; 4]);
        probe.fault
    }

    /// Row `row` with plastic strain `e_p`, or `None` if it breaks.
    #[inline(always)]
    fn row<const MB: bool, const DAMPED: bool>(&self, row: usize, e_p: f64) -> Option<IntactRow> {
        let (rows, inputs) = (self.rows, self.inputs);
        let (i, j) = rows.atoms(row);
        let r0 = rows.r0(row);
        let c = &inputs.coeffs;
        let x = inputs.x;
        let del = self.sep.delta(&x[i], &x[j]);
        let r = match inputs.multibody {
            Some((_, lengths)) if MB => lengths[row][0],
            _ => (del[0] * del[0] + del[1] * del[1] + del[2] * del[2]).sqrt(),
        };
        let rinv = 1.0 / r;
        let dilation = if MB {
            let vol = inputs.multibody.map_or(&[][..], |m| m.0);
            Some(cube_root((vol[i] + vol[j]) * rows.inv_v0sum(row)))
        } else {
            None
        };
        let damping = if DAMPED {
            let v = inputs.v.unwrap_or(&[]);
            let dv = [v[i][0] - v[j][0], v[i][1] - v[j][1], v[i][2] - v[j][2]];
            let del_dot_dv = del[0] * dv[0] + del[1] * dv[1] + del[2] * dv[2];
            c.gamma * del_dot_dv * rinv
        } else {
            0.0
        };
        let mut e_p = e_p;
        let fmag = failing_bond_force(r, r0, &mut e_p, dilation, damping, c, self.rule)?;
        let stretch = r - rest_length(r0, e_p);
        let mut energy = 0.5 * c.k * stretch * stretch;
        if self.rule.normalize {
            energy *= rows.inv_r0[row];
        }
        Some(IntactRow {
            force: RowForce {
                del,
                r,
                fpair: fmag * rinv,
                energy,
            },
            e_p,
        })
    }
}

/// The force row of a bond that broke ([`row_broke`]).
const BROKEN_ROW: [f64; 4] = [0.0, 0.0, 0.0, f64::NAN];

/// Sets `vol0[p]` for each particle `p` of `particles` (`vol0` holds
/// exactly those) to the sum of its rows' `r_eq^3`, with each row's rest
/// length from `plastic`, in row order.
pub fn gather_rest_volumes(
    rows: &BondRows,
    particles: Range<usize>,
    plastic: &PlasticRows,
    vol0: &mut [f64],
) {
    assert!(
        particles.end <= rows.particles()
            && vol0.len() == particles.len()
            && plastic.len() == rows.len(),
        "rest volumes of particles {particles:?} into {} from {} rows",
        vol0.len(),
        plastic.len()
    );
    let strains = plastic.strains();
    let term = |e: u32| {
        let row = (e & !AS_J) as usize;
        let r_eq = rest_length(rows.r0(row), strains[row]);
        r_eq * r_eq * r_eq
    };
    gather_by_particle(rows, particles, vol0, term);
}

#[cfg(target_arch = "x86_64")]
mod avx2 {
    //! Four rows at a time, as the elastic pass's vector build; the rule's
    //! choices are blends, so every lane computes what
    //! [`failing_bond_force`] computes, operation by operation.

    use super::super::bond_rows::avx2::{
        cube_roots, damping_term, in_range, note_rejected, tally_terms, to_rows_with, Geometry,
        AHEAD_BLOCKS,
    };
    use super::*;
    use std::arch::x86_64::*;

    /// The lanes whose bonds break: beyond the critical strain, and finite.
    ///
    /// # Safety
    /// AVX2.
    #[target_feature(enable = "avx2")]
    #[inline]
    unsafe fn breaking_lanes(breaks: bool, e: __m256d, r: __m256d, critical: __m256d) -> __m256d {
        if breaks {
            let magnitude = _mm256_castsi256_pd(_mm256_set1_epi64x(i64::MAX));
            _mm256_and_pd(
                _mm256_cmp_pd::<_CMP_GT_OQ>(_mm256_and_pd(e, magnitude), critical),
                _mm256_cmp_pd::<_CMP_LT_OQ>(r, _mm256_set1_pd(f64::INFINITY)),
            )
        } else {
            _mm256_setzero_pd()
        }
    }

    /// Moves the plastic strains of the rows `k..k + 4` of `plastic` that
    /// yield at strains `e` (and do not break, `broken`), counted in
    /// `yielded`.
    ///
    /// # Safety
    /// AVX2; rows `k..k + 4` within `plastic`, and `r0s` holds their `r0`.
    #[target_feature(enable = "avx2")]
    #[inline]
    unsafe fn yield_block(
        plastic: RawPlastic,
        k: usize,
        r0s: &[f64],
        e: __m256d,
        broken: __m256d,
        yielded: &mut usize,
    ) {
        let band = _mm256_set1_pd(plastic.band.plastic_strain);
        let before = _mm256_loadu_pd(plastic.e_p.add(k));
        let above = _mm256_cmp_pd::<_CMP_GT_OQ>(e, _mm256_add_pd(before, band));
        let below = _mm256_cmp_pd::<_CMP_LT_OQ>(e, _mm256_sub_pd(before, band));
        let mut e_p = _mm256_blendv_pd(before, _mm256_sub_pd(e, band), above);
        e_p = _mm256_blendv_pd(e_p, _mm256_add_pd(e, band), below);
        let moved = _mm256_andnot_pd(broken, _mm256_cmp_pd::<_CMP_NEQ_OQ>(e_p, before));
        let moved = _mm256_movemask_pd(moved);
        if moved != 0 {
            let mut strains = [0.0; 4];
            _mm256_storeu_pd(strains.as_mut_ptr(), e_p);
            for (lane, e_p) in strains.into_iter().enumerate() {
                if moved & (1 << lane) != 0 {
                    plastic.set(k + lane, r0s[lane], e_p);
                }
            }
            *yielded += moved.count_ones() as usize;
        }
    }

    /// # Safety
    /// As [`super::super::bond_rows::avx2::row_forces`]: AVX2; whole
    /// blocks of four within the rows, as many in `out`; the inputs
    /// checked by `BondRows::check_inputs`, and the plastic section by
    /// [`failing_row_forces_on`]; `MB` and `DAMPED` only with the multibody
    /// term and the velocities in the inputs, `PLASTIC` only with a rule
    /// that yields.
    #[target_feature(enable = "avx2")]
    pub(super) unsafe fn failing_blocks<
        S: Separation,
        const MB: bool,
        const DAMPED: bool,
        const TALLY: bool,
        const PLASTIC: bool,
    >(
        pass: &mut FailingPass<'_, S>,
        range: Range<usize>,
        out: &mut [[f64; 4]],
        lanes: &mut LaneTally,
    ) -> FailurePass {
        let FailingPass {
            sep,
            rows,
            inputs,
            rule,
            ref mut plastic,
        } = *pass;
        // Everything the loop reads, in locals: the rows are written
        // through raw pointers, which the compiler must otherwise assume
        // may alias the rule, the inputs and the layout, reloading them
        // (and re-testing the rule's flags) every block.
        debug_assert!(range.len() % 4 == 0 && out.len() == range.len());
        debug_assert!((!MB || inputs.multibody.is_some()) && (!DAMPED || inputs.v.is_some()));
        debug_assert!(!PLASTIC || plastic.as_ref().is_some_and(|p| p.len() >= range.len()));
        let (breaks, smooth, normalize) = (rule.breaks, rule.smooth, rule.normalize);
        let (r0s, inv_r0s, inv_v0sums) = (&rows.r0[..], &rows.inv_r0[..], &rows.inv_v0sum[..]);
        let v = inputs.v.unwrap_or(&[]);
        let (vol, lengths) = inputs.multibody.unwrap_or((&[], &[]));
        let mut ahead = [[_mm256_setzero_pd(); 4]; AHEAD_BLOCKS];
        let mut geometry = Geometry::new(sep, rows, range.end, inputs.x, lengths, &mut ahead);
        let c = &inputs.coeffs;
        let (neg_k, a, gamma, half_k) = (
            _mm256_set1_pd(-c.k),
            _mm256_set1_pd(c.a),
            _mm256_set1_pd(c.gamma),
            _mm256_set1_pd(0.5 * c.k),
        );
        let one = _mm256_set1_pd(1.0);
        let critical = _mm256_set1_pd(rule.critical_strain);
        let inverse_critical = _mm256_set1_pd(1.0 / rule.critical_strain);
        let calm_strain = _mm256_set1_pd(calm_strain(rule));
        // The section's arrays, read and moved in the loop through these
        // pointers alone.
        let bands = plastic.as_mut().map(PlasticSection::raw);
        let (lowers, uppers, rests, strains) = bands.map_or(
            (
                std::ptr::null_mut(),
                std::ptr::null_mut(),
                std::ptr::null_mut(),
                std::ptr::null_mut(),
            ),
            |p| (p.lower, p.upper, p.rest, p.e_p),
        );
        let magnitude = _mm256_castsi256_pd(_mm256_set1_epi64x(i64::MAX));
        let infinity = _mm256_set1_pd(f64::INFINITY);
        let all = _mm256_castsi256_pd(_mm256_set1_epi64x(-1));
        let (mut broken_rows, mut yielded_rows) = (0, 0);
        // The first row out of range, reported after the loop: a fault
        // carried through the loop would be moved about every block.
        let mut first_rejected = None;
        let mut sums = [_mm256_setzero_pd(); 7];
        if TALLY {
            for (sum, lane) in sums.iter_mut().zip(&lanes.sums) {
                *sum = _mm256_loadu_pd(lane.as_ptr());
            }
        }
        for k in (0..range.len()).step_by(4) {
            let row = range.start + k;
            // In bounds: the caller checked the range against the layout
            // and the outputs, and the lengths against the rows.
            let (i, j) = geometry.atoms(row);
            let (del, r) = geometry.block::<MB>(row, k / 4);
            let r0 = _mm256_loadu_pd(r0s.as_ptr().add(row));
            let inv_r0 = _mm256_loadu_pd(inv_r0s.as_ptr().add(row));
            let elongation = _mm256_sub_pd(r, r0);
            let e = _mm256_mul_pd(elongation, inv_r0);
            // Strains within the calm strain: no bond that breaks, and
            // without the multibody term, with yielding, also none that
            // yields (within its band). The rows that yield are moved
            // first, so that the rest lengths below are theirs; and before
            // the damping term, whose values would otherwise be held across
            // this branch.
            let calm = _mm256_cmp_pd::<_CMP_LE_OQ>(_mm256_and_pd(e, magnitude), calm_strain);
            let calm_strains = if PLASTIC && !MB {
                let inside = _mm256_movemask_pd(_mm256_and_pd(
                    _mm256_cmp_pd::<_CMP_LE_OQ>(_mm256_loadu_pd(lowers.add(k)), e),
                    _mm256_cmp_pd::<_CMP_LE_OQ>(e, _mm256_loadu_pd(uppers.add(k))),
                ));
                if inside != 0b1111 {
                    let broken = breaking_lanes(breaks, e, r, critical);
                    // PLASTIC comes with a section.
                    let bands = bands.unwrap_unchecked();
                    yield_block(bands, k, &r0s[row..row + 4], e, broken, &mut yielded_rows);
                }
                inside
            } else {
                _mm256_movemask_pd(calm)
            };
            let rinv = _mm256_div_pd(one, r);
            // The damping term before the spring (damping_term says why).
            let damping = if DAMPED {
                damping_term(v, i, j, &del, gamma, rinv)
            } else {
                _mm256_setzero_pd()
            };
            // Without yielding, e_p stays 0: the rest length is r0, bit for
            // bit what (1 + 0) r0 gives.
            let (e_p, rest, stretch) = if PLASTIC && !MB {
                let rest = _mm256_loadu_pd(rests.add(k));
                // The spring in length reads no plastic strain: one stream
                // fewer.
                let e_p = if normalize {
                    _mm256_loadu_pd(strains.add(k))
                } else {
                    _mm256_setzero_pd()
                };
                (e_p, rest, _mm256_sub_pd(r, rest))
            } else if PLASTIC {
                // With the multibody term, upstream's yield test itself,
                // after the damping term: the bands' test before it ran
                // slower here (the bench README's fifth step). PLASTIC
                // comes with a section.
                let mut e_p = _mm256_loadu_pd(strains.add(k));
                let band = _mm256_set1_pd(bands.unwrap_unchecked().band.plastic_strain);
                let above = _mm256_cmp_pd::<_CMP_GT_OQ>(e, _mm256_add_pd(e_p, band));
                let below = _mm256_cmp_pd::<_CMP_LT_OQ>(e, _mm256_sub_pd(e_p, band));
                if _mm256_movemask_pd(_mm256_or_pd(above, below)) != 0 {
                    let broken = breaking_lanes(breaks, e, r, critical);
                    let bands = bands.unwrap_unchecked();
                    yield_block(bands, k, &r0s[row..row + 4], e, broken, &mut yielded_rows);
                    e_p = _mm256_loadu_pd(strains.add(k));
                }
                let rest = _mm256_mul_pd(r0, _mm256_add_pd(one, e_p));
                (e_p, rest, _mm256_sub_pd(r, rest))
            } else {
                (_mm256_setzero_pd(), r0, elongation)
            };
            let mut fmag = if normalize {
                _mm256_mul_pd(neg_k, _mm256_sub_pd(e, e_p))
            } else {
                _mm256_mul_pd(neg_k, stretch)
            };
            if MB {
                let idx_i = _mm_loadu_si128(i.as_ptr() as *const __m128i);
                let idx_j = _mm_loadu_si128(j.as_ptr() as *const __m128i);
                let vsum = _mm256_add_pd(
                    _mm256_i32gather_pd::<8>(vol.as_ptr(), idx_i),
                    _mm256_i32gather_pd::<8>(vol.as_ptr(), idx_j),
                );
                let inv_v0sum = _mm256_loadu_pd(inv_v0sums.as_ptr().add(row));
                let q = _mm256_mul_pd(vsum, inv_v0sum);
                let dilation = cube_roots(q, _mm256_sub_pd(q, one));
                let inv_rest = if PLASTIC {
                    _mm256_div_pd(one, rest)
                } else {
                    inv_r0
                };
                fmag = _mm256_add_pd(
                    fmag,
                    _mm256_mul_pd(a, _mm256_sub_pd(dilation, _mm256_mul_pd(r, inv_rest))),
                );
            }
            if DAMPED {
                fmag = _mm256_sub_pd(fmag, damping);
            }
            if smooth {
                let s = _mm256_mul_pd(e, inverse_critical);
                let s2 = _mm256_mul_pd(s, s);
                let s4 = _mm256_mul_pd(s2, s2);
                fmag = _mm256_mul_pd(fmag, _mm256_sub_pd(one, _mm256_mul_pd(s4, s4)));
            }
            let fpair = _mm256_mul_pd(fmag, rinv);
            let mut force = [
                _mm256_mul_pd(del[0], fpair),
                _mm256_mul_pd(del[1], fpair),
                _mm256_mul_pd(del[2], fpair),
            ];
            let mut fourth = _mm256_setzero_pd();
            let mut intact = all;
            // A calm block (every strain calm, every force finite) has no
            // bond that breaks and none out of range: one test stands for
            // both. Only the other blocks pay for them.
            let finite = _mm256_cmp_pd::<_CMP_LT_OQ>(_mm256_and_pd(fpair, magnitude), infinity);
            if calm_strains & _mm256_movemask_pd(finite) != 0b1111 {
                let broken = breaking_lanes(breaks, e, r, critical);
                let broken_lanes = _mm256_movemask_pd(broken);
                if broken_lanes != 0 {
                    broken_rows += broken_lanes.count_ones() as usize;
                    intact = _mm256_andnot_pd(broken, all);
                    // Broken rows: +0, as the scalar build writes them.
                    force = force.map(|f| _mm256_and_pd(f, intact));
                    fourth = _mm256_and_pd(_mm256_set1_pd(f64::NAN), broken);
                }
                let rejected = !_mm256_movemask_pd(in_range(r, r0, fpair)) & !broken_lanes & 0b1111;
                if rejected != 0 {
                    note_rejected(&mut first_rejected, k, rejected);
                }
            }
            let dst = out.as_mut_ptr().add(k) as *mut f64;
            let force_rows = to_rows_with(force[0], force[1], force[2], fourth);
            for (l, fr) in force_rows.into_iter().enumerate() {
                _mm256_storeu_pd(dst.add(4 * l), fr);
            }
            if TALLY {
                let mut energy = _mm256_mul_pd(_mm256_mul_pd(half_k, stretch), stretch);
                if normalize {
                    energy = _mm256_mul_pd(energy, inv_r0);
                }
                // Broken lanes add +0 (their force is masked, and so is
                // the product with a separation that may not be finite).
                for (sum, term) in sums.iter_mut().zip(tally_terms(energy, &force, &del)) {
                    *sum = _mm256_add_pd(*sum, _mm256_and_pd(term, intact));
                }
            }
        }
        if TALLY {
            for (sum, lane) in sums.iter().zip(lanes.sums.iter_mut()) {
                _mm256_storeu_pd(lane.as_mut_ptr(), *sum);
            }
        }
        let mut result = FailurePass {
            broken: broken_rows,
            yielded: yielded_rows,
            ..FailurePass::default()
        };
        // The lanes' test rejects a length exactly at a limit, which is no
        // fault (as on the portable build): scan on to the first that is.
        if let Some(first) = first_rejected {
            let pass = &*pass;
            let strain = |k: usize| pass.plastic.as_ref().map_or(0.0, |p| p.strain(k));
            result.pass.fault = (first..out.len())
                .filter(|&k| !row_broke(&out[k]))
                .find_map(|k| pass.fault_of::<MB, DAMPED>(range.start + k, strain(k)));
        }
        result
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::kernels::{bond_force_magnitude, dilation as bond_dilation};

    const COEFFS: BondCoeffs = BondCoeffs {
        k: 2.0,
        a: -0.5,
        gamma: 0.3,
    };

    fn rule(eps_c: f64, eps_p: Option<f64>) -> BondFailure {
        BondFailure {
            plastic_strain: eps_p,
            ..BondFailure::breaking(eps_c)
        }
    }

    #[test]
    fn an_unyielded_unsmoothed_bond_has_the_elastic_force_bit_for_bit() {
        let elastic = BondFailure {
            smooth: false,
            ..rule(0.5, None)
        };
        for r in [0.8, 0.97, 1.0, 1.03, 1.4] {
            let d = bond_dilation(1.1, 0.9, 1.0, 1.0);
            let mut e_p = 0.0;
            let f = failing_bond_force(r, 1.0, &mut e_p, Some(d), 0.3 * 0.2, &COEFFS, &elastic);
            assert_eq!(
                f,
                Some(bond_force_magnitude(r, 1.0, d, 0.2, &COEFFS)),
                "r = {r}"
            );
        }
    }

    #[test]
    fn a_bond_breaks_just_beyond_the_critical_strain_in_both_directions() {
        let rule = rule(0.1, None);
        let mut e_p = 0.0;
        for (r, breaks) in [
            (1.0999, false),
            (1.1001, true),
            (0.9001, false),
            (0.8999, true),
        ] {
            let f = failing_bond_force(r, 1.0, &mut e_p, None, 0.0, &COEFFS, &rule);
            assert_eq!(f.is_none(), breaks, "r = {r}");
        }
        let unbreakable = BondFailure {
            breaks: false,
            smooth: false,
            ..rule
        };
        assert!(failing_bond_force(2.0, 1.0, &mut e_p, None, 0.0, &COEFFS, &unbreakable).is_some());
    }

    #[test]
    fn the_yield_test_compares_e_with_the_rounded_band_edges_as_upstream() {
        // e - e_p rounds above eps_p, but e does not exceed the rounded
        // e_p + eps_p: upstream's compares (and so ours) see no yield.
        let (e, e_p, eps_p) = (0.13131872997951222, 0.0813187299795122, 0.05);
        assert!(e - e_p > eps_p);
        assert_eq!(plastic_strain_after(e, e_p, eps_p), e_p);
        assert_eq!(plastic_strain_after(-e, -e_p, eps_p), -e_p);
        // One ulp further out, it yields to e -+ eps_p.
        let beyond = e_p + eps_p + f64::EPSILON / 8.0;
        assert!(beyond > e_p + eps_p);
        assert_eq!(plastic_strain_after(beyond, e_p, eps_p), beyond - eps_p);
        assert_eq!(plastic_strain_after(-beyond, -e_p, eps_p), -beyond + eps_p);
    }

    #[test]
    fn smoothing_scales_the_whole_force_and_vanishes_at_the_critical_strain() {
        let smooth = rule(0.1, None);
        let plain = BondFailure {
            smooth: false,
            ..smooth
        };
        let r = 1.05;
        let (mut a, mut b) = (0.0, 0.0);
        let d = Some(1.01);
        let fs = failing_bond_force(r, 1.0, &mut a, d, 0.4, &COEFFS, &smooth).unwrap();
        let fp = failing_bond_force(r, 1.0, &mut b, d, 0.4, &COEFFS, &plain).unwrap();
        let w = 1.0 - 0.5f64.powi(8);
        assert!((fs / fp - w).abs() < 1e-14, "{fs} / {fp} against {w}");
        assert!(smoothing(0.1, 10.0).abs() < 1e-15 && smoothing(-0.1, 10.0).abs() < 1e-15);
    }

    #[test]
    fn a_stretched_plastic_bond_levels_off_at_k_eps_p_r0_and_unloads_elastically() {
        let rule = BondFailure {
            smooth: false,
            breaks: false,
            ..rule(0.5, Some(0.02))
        };
        let c = BondCoeffs {
            a: 0.0,
            gamma: 0.0,
            ..COEFFS
        };
        let r0 = 1.3;
        let mut e_p = 0.0;
        let mut last = 0.0;
        for step in 1..=100 {
            let r = r0 * (1.0 + 0.001 * step as f64);
            last = failing_bond_force(r, r0, &mut e_p, None, 0.0, &c, &rule).unwrap();
        }
        assert!((last + c.k * 0.02 * r0).abs() < 1e-12, "plateau {last}");
        assert!((e_p - 0.08).abs() < 1e-12, "plastic strain {e_p}");
        let rest = r0 * (1.0 + e_p);
        let f = failing_bond_force(rest, r0, &mut e_p, None, 0.0, &c, &rule).unwrap();
        assert!(f.abs() < 1e-12, "force at the new rest length {f}");
        // Compressed back by less than eps_p: elastic, e_p unchanged.
        let f = failing_bond_force(rest - 0.01 * r0, r0, &mut e_p, None, 0.0, &c, &rule).unwrap();
        assert!((e_p - 0.08).abs() < 1e-12 && (f - c.k * 0.01 * r0).abs() < 1e-12);
    }

    #[test]
    fn the_normalized_spring_is_the_length_spring_over_r0() {
        let length = BondFailure {
            smooth: false,
            breaks: false,
            ..rule(0.5, Some(0.02))
        };
        let strain = BondFailure {
            normalize: true,
            ..length
        };
        let c = BondCoeffs {
            a: 0.0,
            gamma: 0.0,
            ..COEFFS
        };
        let (mut a, mut b) = (0.01, 0.01);
        let fl = failing_bond_force(2.1, 2.0, &mut a, None, 0.0, &c, &length).unwrap();
        let fs = failing_bond_force(2.1, 2.0, &mut b, None, 0.0, &c, &strain).unwrap();
        assert!((fs - fl / 2.0).abs() < 1e-14, "{fs} against {fl} / 2");
    }

    #[test]
    fn bad_values_are_refused_naming_them() {
        let cases = [
            (rule(0.0, None), "eps_c = 0"),
            (rule(f64::NAN, None), "eps_c = NaN"),
            (
                rule(0.1, Some(0.1)),
                "eps_p = 0.1 must be below the critical strain eps_c = 0.1",
            ),
            (rule(0.1, Some(-0.01)), "eps_p = -0.01"),
            (
                BondFailure {
                    breaks: false,
                    ..rule(0.1, None)
                },
                "smoothing needs breaking",
            ),
        ];
        for (rule, expected) in cases {
            let message = rule.check().unwrap_err().to_string();
            assert!(message.contains(expected), "{message}");
        }
        assert_eq!(rule(0.1, Some(0.05)).check(), Ok(()));
    }
}
