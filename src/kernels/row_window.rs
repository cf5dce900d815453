//! The two-step bond pass of [`super::bond_rows`] in windows that stay in
//! cache.
//!
//! The full-size pass writes every bond's force into a row of an array as
//! long as the bond list, then reads each row back for its two particles.
//! Beyond the last cache level that round trip goes through memory: some
//! 100 bytes of traffic per bond, against about 30 for the bond's own data.
//! Here each part of the particles (one per thread) computes its interior
//! rows a block at a time into a small ring of slots and, after each block,
//! gathers the particles whose rows are all done. The ring only has to hold
//! the rows between a particle's first bond and its last, and bonded
//! partners lie close in the numbering (grains are numbered cell by cell),
//! so it stays in the core's own cache. The plan measures that span and
//! declines when the ring would not fit: bulk solids, numbered in layers
//! of cells, span a layer (8,192 slots at L = 12 d, growing as L^2).
//!
//! A part also computes the rows of earlier particles bonded to its first
//! ones (its halo), which the part before computes too: the same arithmetic
//! on the same inputs, so the same bits. Each particle still sums its rows
//! in row order, so the forces are the full-size pass's bit for bit, for
//! every split into parts. Rows across a periodic face (the layout's
//! "boundary" rows, after the interior ones) are few: they are computed
//! beforehand, and each part copies them behind its ring, so that its
//! gather reads a single array.

use super::bond_rows::{
    gather_rows_on, row_forces_carried, BondRows, Incidence, LaneTally, RowInputs, AS_J,
};
use super::fault::ForcePass;
use super::isa::Isa;
use super::{row_forces_on, Unwrapped};
use std::ops::Range;

/// Which rows a part computes and when it gathers.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
struct WindowPart {
    /// The interior rows it computes: its halo (rows of earlier particles
    /// bonded to its own), then its own rows.
    rows: Range<usize>,
    /// The rows whose energy and virial it sums: the parts' own rows are
    /// consecutive and together all interior rows. Row `own.start` has
    /// slot 0 of the ring.
    own: Range<usize>,
    /// In turn: compute the rows up to `.0`, then gather the particles up
    /// to `.1`.
    steps: Vec<(usize, usize)>,
}

/// The schedule of a windowed bond pass: for each part of the particles,
/// the blocks of interior rows it computes and the particles it gathers
/// after each; and every particle's entries as slots of its part's
/// buffer: its ring for interior rows, then the boundary rows.
#[derive(Clone, Debug, Default)]
pub struct RowWindow {
    /// Slots per ring (a power of two, and at least one block).
    ring: usize,
    /// Rows `0..interior` are interior.
    interior: usize,
    /// Rows and particles of the layout planned for.
    rows: usize,
    particles: usize,
    /// The layout's incidence, each row replaced by its slot.
    slots: Vec<u32>,
    /// The particles whose forces each part sums.
    particles_of: Vec<Range<usize>>,
    parts: Vec<WindowPart>,
}

impl RowWindow {
    /// Plans the pass over `rows` (interior rows `0..interior`) for the
    /// given parts of the particles (consecutive, together all of them),
    /// computing `block` rows (a multiple of four) at a time. `None` when a
    /// ring would need more than `max_ring` slots: bonded partners too far
    /// apart in the numbering for a window to pay.
    pub fn plan(
        rows: &BondRows,
        interior: usize,
        parts: &[Range<usize>],
        block: usize,
        max_ring: usize,
    ) -> Option<Self> {
        let particles = rows.particles();
        assert!(
            interior <= rows.len(),
            "{interior} interior of {} rows",
            rows.len()
        );
        assert!(block > 0 && block % 4 == 0, "blocks of {block} rows");
        let consecutive = parts.windows(2).all(|w| w[0].end == w[1].start);
        assert!(
            consecutive
                && parts.first().map_or(0, |p| p.start) == 0
                && parts.last().map_or(0, |p| p.end) == particles,
            "parts {parts:?} do not cover {particles} particles in order"
        );
        let incidence = rows.incidence();
        // The interior rows of `p`: the first, and one past the last
        // (entries are in row order, interior rows first).
        let span = |p: usize| {
            let mut interior_rows = incidence
                .of(p)
                .iter()
                .map(|&e| (e & !AS_J) as usize)
                .take_while(|&r| r < interior);
            let first = interior_rows.next()?;
            Some((first, interior_rows.last().unwrap_or(first) + 1))
        };
        let mut need = block;
        let mut planned = Vec::with_capacity(parts.len());
        let mut own_start = 0;
        for (c, part) in parts.iter().enumerate() {
            let (first_row, last_row) = part
                .clone()
                .filter_map(span)
                .reduce(|(a, b), (lo, hi)| (a.min(lo), b.max(hi)))
                .unwrap_or((own_start, own_start));
            let own_end = if c + 1 == parts.len() {
                interior
            } else {
                last_row.max(own_start)
            };
            let own = own_start..own_end;
            let mut steps = Vec::new();
            let (mut done, mut gathered) = (own.start, part.start);
            loop {
                done = (done + block).min(own.end);
                while gathered < part.end {
                    match span(gathered) {
                        Some((_, end)) if end > done => break,
                        Some((start, _)) => need = need.max(done - start),
                        None => {}
                    }
                    gathered += 1;
                }
                steps.push((done, gathered));
                if done == own.end {
                    break;
                }
            }
            debug_assert_eq!(gathered, part.end, "every particle's rows computed");
            planned.push(WindowPart {
                rows: first_row.min(own.start)..own.end,
                own: own.clone(),
                steps,
            });
            own_start = own.end;
        }
        let ring = need.next_power_of_two();
        let boundary = rows.len() - interior;
        if ring > max_ring || ring + boundary > AS_J as usize {
            return None;
        }
        let mut slots = vec![0; incidence.entries.len()];
        for (part, particles) in planned.iter().zip(parts) {
            let entries = incidence.offsets[particles.start]..incidence.offsets[particles.end];
            for (slot, &e) in slots[entries.clone()]
                .iter_mut()
                .zip(&incidence.entries[entries])
            {
                let row = (e & !AS_J) as usize;
                let at = if row < interior {
                    row.wrapping_sub(part.own.start) & (ring - 1)
                } else {
                    ring + (row - interior)
                };
                *slot = at as u32 | (e & AS_J);
            }
        }
        Some(Self {
            ring,
            interior,
            rows: rows.len(),
            particles,
            slots,
            particles_of: parts.to_vec(),
            parts: planned,
        })
    }

    /// Slots per ring: each part's ring holds this many rows.
    pub fn ring(&self) -> usize {
        self.ring
    }

    /// Rows of each part's buffer: its ring, then the boundary rows.
    pub fn buffer_len(&self) -> usize {
        self.ring + self.rows - self.interior
    }

    /// The particles each part gathers, in part order.
    pub fn particle_parts(&self) -> &[Range<usize>] {
        &self.particles_of
    }

    /// Interior rows computed by more than one part (the halos), as a
    /// fraction of the interior rows: the window's extra work.
    pub fn halo_fraction(&self) -> f64 {
        let computed: usize = self.parts.iter().map(|p| p.rows.len()).sum();
        computed.saturating_sub(self.interior) as f64 / self.interior.max(1) as f64
    }
}

/// Part `part` of the windowed bond pass: adds to `f` (the part's
/// particles, [`RowWindow::particle_parts`]) every bond force on them. `buffer`
/// ([`RowWindow::buffer_len`] rows) is the part's own: its ring, which
/// takes the part's interior rows as they are computed, then a copy of
/// `boundary` (the layout's rows from `interior` on, written by
/// [`super::row_forces`] beforehand), so the gather reads one array. The
/// forces equal [`super::row_forces`] then [`super::gather_forces`] bit for
/// bit. Returns the energy and virial of the part's own rows (when
/// `inputs.tally`; a single part sums what [`super::row_forces`] sums over
/// all interior rows, bit for bit) and the first row out of the model's
/// range.
pub fn window_forces(
    rows: &BondRows,
    window: &RowWindow,
    part: usize,
    inputs: &RowInputs,
    boundary: &[[f64; 4]],
    buffer: &mut [[f64; 4]],
    f: &mut [[f64; 3]],
) -> ForcePass {
    window_forces_on(
        Isa::detect(),
        rows,
        window,
        part,
        inputs,
        boundary,
        buffer,
        f,
    )
}

/// [`window_forces`] compiled for `isa`; every build gives the same forces
/// and sums.
#[allow(clippy::too_many_arguments)]
pub fn window_forces_on(
    isa: Isa,
    rows: &BondRows,
    window: &RowWindow,
    part: usize,
    inputs: &RowInputs,
    boundary: &[[f64; 4]],
    buffer: &mut [[f64; 4]],
    f: &mut [[f64; 3]],
) -> ForcePass {
    assert!(
        window.rows == rows.len() && window.particles == rows.particles(),
        "a window planned for {} rows on {} particles, run on {} on {}",
        window.rows,
        window.particles,
        rows.len(),
        rows.particles()
    );
    let plan = &window.parts[part];
    assert_eq!(
        boundary.len(),
        rows.len() - window.interior,
        "boundary rows"
    );
    assert_eq!(buffer.len(), window.buffer_len(), "window buffer");
    assert_eq!(
        f.len(),
        window.particles_of[part].len(),
        "forces of the part's particles"
    );
    buffer[window.ring..].copy_from_slice(boundary);
    let incidence = Incidence {
        offsets: rows.offsets(),
        entries: &window.slots,
    };
    let halo_inputs = RowInputs {
        tally: false,
        ..*inputs
    };
    let mut lanes = LaneTally::default();
    let first = window.particles_of[part].start;
    let (mut row, mut gathered) = (plan.rows.start, first);
    let mut pass = ForcePass::default();
    for &(rows_end, particles_end) in &plan.steps {
        // Pieces that end where the ring wraps, where the own rows begin
        // (the tally starts) and at the step's end: own pieces start a
        // multiple of four rows after `own.start` (blocks and the ring
        // are multiples of four).
        while row < rows_end {
            let slot = row.wrapping_sub(plan.own.start) & (window.ring - 1);
            let halo = row < plan.own.start;
            let end = if halo { plan.own.start } else { rows_end };
            let n = (window.ring - slot).min(end - row);
            let out = &mut buffer[slot..slot + n];
            let range = row..row + n;
            let piece = if halo {
                row_forces_on(isa, &Unwrapped, rows, range, &halo_inputs, out)
            } else {
                let last = row + n == plan.own.end;
                row_forces_carried(isa, &Unwrapped, rows, range, inputs, out, &mut lanes, last)
            };
            pass = pass.merged(&piece);
            row += n;
        }
        // SAFETY: the plan gave every entry of these particles a slot of
        // the buffer (its length checked above), and the ring holds each
        // interior row they name (the plan's span).
        unsafe {
            gather_rows_on(
                isa,
                incidence,
                gathered..particles_end,
                buffer,
                &mut f[gathered - first..particles_end - first],
            )
        };
        gathered = particles_end;
    }
    pass
}
