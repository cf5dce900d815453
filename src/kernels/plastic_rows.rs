//! Each bond row's plastic strain, in row order beside the rows, with what
//! the failing pass derives from it.
//!
//! The pass reads, per row, the rest length `r_eq = (1 + e_p) r0` and the
//! strains `lower..=upper` within which the row neither yields nor can
//! break: `e_p -/+ eps_p` (rounded as the yield test rounds them), cut to
//! the calm strain of the pass (a strain no bond within can break at or
//! reach a fault with). Kept as arrays in row order, a block of four rows
//! reads each with one load, and (without the multibody term) one test of
//! `e` against both edges stands for the yield test and the strain part of
//! the break test. They change only where a row yields.

use super::bond_rows::{drop_rows, BondRows};
use std::marker::PhantomData;
use std::ops::Range;

/// The strains a rule's bands are drawn with.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(super) struct Band {
    /// `eps_p`.
    pub(super) plastic_strain: f64,
    /// The strain within which no bond breaks or reaches a fault.
    pub(super) calm_strain: f64,
}

impl Band {
    /// `(lower, upper)` for plastic strain `e_p`: the yield test's edges
    /// (`e > e_p + eps_p` and `e < e_p - eps_p` yield), within the calm
    /// strain either way.
    fn edges(&self, e_p: f64) -> (f64, f64) {
        (
            (e_p - self.plastic_strain).max(-self.calm_strain),
            (e_p + self.plastic_strain).min(self.calm_strain),
        )
    }
}

/// The plastic strains of a layout's rows ([`BondRows`]), which the failing
/// pass ([`super::failing_row_forces`]) reads and moves, once banded for
/// its rule ([`PlasticRows::band_for`], with the rule's other methods in
/// `bond_failure.rs`, which knows the rule).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct PlasticRows {
    band: Option<Band>,
    e_p: Vec<f64>,
    /// `r0 (1 + e_p)`.
    rest: Vec<f64>,
    lower: Vec<f64>,
    upper: Vec<f64>,
}

impl PlasticRows {
    /// Plastic strains `e_p` (one per row, in row order) of `rows`, not yet
    /// banded.
    ///
    /// # Panics
    /// If `e_p` has not one value per row.
    pub fn new(rows: &BondRows, e_p: Vec<f64>) -> Self {
        assert_eq!(e_p.len(), rows.len(), "one plastic strain per bond row");
        let rest = e_p
            .iter()
            .zip(&rows.r0)
            .map(|(e, r0)| rest_length(*r0, *e))
            .collect();
        let n = e_p.len();
        Self {
            band: None,
            e_p,
            rest,
            lower: vec![0.0; n],
            upper: vec![0.0; n],
        }
    }

    /// Each row's plastic strain.
    pub fn strains(&self) -> &[f64] {
        &self.e_p
    }

    /// Rows.
    pub fn len(&self) -> usize {
        self.e_p.len()
    }

    /// Whether there are no rows.
    pub fn is_empty(&self) -> bool {
        self.e_p.is_empty()
    }

    /// The band the rows are drawn with, if any.
    pub(super) fn band(&self) -> Option<Band> {
        self.band
    }

    /// Draws every row's band with `band`.
    pub(super) fn draw(&mut self, band: Band) {
        self.band = Some(band);
        for (k, &e_p) in self.e_p.iter().enumerate() {
            (self.lower[k], self.upper[k]) = band.edges(e_p);
        }
    }

    /// Drops rows `doomed` (increasing), as [`BondRows::remove_rows`] does.
    pub fn remove_rows(&mut self, doomed: &[usize]) {
        for values in [
            &mut self.e_p,
            &mut self.rest,
            &mut self.lower,
            &mut self.upper,
        ] {
            drop_rows(values, doomed);
        }
    }

    /// The rows `range`, for one pass.
    ///
    /// # Panics
    /// If the rows are not banded ([`PlasticRows::band_for`]), or `range`
    /// is not within them.
    pub fn section(&mut self, range: Range<usize>) -> PlasticSection<'_> {
        // SAFETY: `self` is borrowed mutably for the section's lifetime.
        unsafe { self.shared().section(range) }
    }

    /// The rows, for passes on several threads at once, each over its own
    /// rows ([`SharedPlasticRows::section`]).
    ///
    /// # Panics
    /// If the rows are not banded ([`PlasticRows::band_for`]).
    pub fn shared(&mut self) -> SharedPlasticRows<'_> {
        let band = self
            .band
            .expect("plastic rows are banded for the pass's rule first (PlasticRows::band_for)");
        SharedPlasticRows {
            len: self.len(),
            raw: RawPlastic::of(
                band,
                &mut self.e_p,
                &mut self.rest,
                &mut self.lower,
                &mut self.upper,
            ),
            rows: PhantomData,
        }
    }
}

/// The rest length `(1 + e_p) r0`, as every pass rounds it.
#[inline(always)]
pub(super) fn rest_length(r0: f64, e_p: f64) -> f64 {
    r0 * (1.0 + e_p)
}

/// [`PlasticRows`] lent to passes that each take their own rows.
pub struct SharedPlasticRows<'a> {
    len: usize,
    raw: RawPlastic,
    rows: PhantomData<&'a mut PlasticRows>,
}

// SAFETY: sections are taken over disjoint rows (the contract of
// `section`), so no two threads touch one value.
unsafe impl Sync for SharedPlasticRows<'_> {}

impl<'a> SharedPlasticRows<'a> {
    /// The rows `range`.
    ///
    /// # Safety
    /// No other section of these rows, live at the same time, overlaps
    /// `range`.
    pub unsafe fn section(&self, range: Range<usize>) -> PlasticSection<'a> {
        assert!(
            range.start <= range.end && range.end <= self.len,
            "rows {range:?} of {}",
            self.len
        );
        let part = |p: *mut f64| std::slice::from_raw_parts_mut(p.add(range.start), range.len());
        let raw = self.raw;
        PlasticSection {
            band: raw.band,
            e_p: part(raw.e_p),
            rest: part(raw.rest),
            lower: part(raw.lower),
            upper: part(raw.upper),
        }
    }
}

/// Some consecutive rows of [`PlasticRows`], indexed from 0.
pub struct PlasticSection<'a> {
    pub(super) band: Band,
    pub(super) e_p: &'a mut [f64],
    pub(super) rest: &'a mut [f64],
    pub(super) lower: &'a mut [f64],
    pub(super) upper: &'a mut [f64],
}

impl PlasticSection<'_> {
    /// Rows.
    pub fn len(&self) -> usize {
        self.e_p.len()
    }

    /// Whether there are no rows.
    pub fn is_empty(&self) -> bool {
        self.e_p.is_empty()
    }

    /// Row `k`'s plastic strain.
    #[inline(always)]
    pub(super) fn strain(&self, k: usize) -> f64 {
        self.e_p[k]
    }

    /// Sets row `k`'s plastic strain (its reference length `r0`) and what
    /// follows from it.
    #[inline]
    pub(super) fn set(&mut self, k: usize, r0: f64, e_p: f64) {
        assert!(k < self.len(), "row {k} of {}", self.len());
        // SAFETY: in bounds, and the section is borrowed mutably.
        unsafe { self.raw().set(k, r0, e_p) }
    }

    /// The section through pointers, for a pass that reads the bands in
    /// vectors and moves some of them.
    pub(super) fn raw(&mut self) -> RawPlastic {
        RawPlastic::of(self.band, self.e_p, self.rest, self.lower, self.upper)
    }
}

/// A [`PlasticSection`]'s arrays as pointers: reads and writes through
/// them alone while they are in use.
#[derive(Clone, Copy)]
pub(super) struct RawPlastic {
    pub(super) band: Band,
    pub(super) e_p: *mut f64,
    pub(super) rest: *mut f64,
    pub(super) lower: *mut f64,
    pub(super) upper: *mut f64,
}

impl RawPlastic {
    /// The arrays `e_p`, `rest`, `lower` and `upper` (one row each), drawn
    /// with `band`.
    fn of(
        band: Band,
        e_p: &mut [f64],
        rest: &mut [f64],
        lower: &mut [f64],
        upper: &mut [f64],
    ) -> Self {
        Self {
            band,
            e_p: e_p.as_mut_ptr(),
            rest: rest.as_mut_ptr(),
            lower: lower.as_mut_ptr(),
            upper: upper.as_mut_ptr(),
        }
    }

    /// [`PlasticSection::set`].
    ///
    /// # Safety
    /// `k` within the section, no reference into it live.
    #[inline]
    pub(super) unsafe fn set(&self, k: usize, r0: f64, e_p: f64) {
        let (lower, upper) = self.band.edges(e_p);
        *self.e_p.add(k) = e_p;
        *self.rest.add(k) = rest_length(r0, e_p);
        *self.lower.add(k) = lower;
        *self.upper.add(k) = upper;
    }
}
