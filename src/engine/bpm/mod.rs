//! The bonded particle model as a particle model of the engine: point
//! particles joined by bonds (spring + multibody volume term + damping),
//! with harmonic-plus-cubic contacts between unbonded particles.
//!
//! The model owns its bonds, their reference lengths and the per-particle
//! volume proxies. Terms that a scene cannot use are removed at load: no
//! volume pass when `a_B` is 0, no velocity terms when `Gamma` is 0, no pair
//! list when there is no pair style or it has no stiffness.

mod topology;

pub use topology::BondTopology;

use super::model::{EnergyTerm, ForceInput, ForceOutput, ModelTally, ParticleModel};
use super::neighbor::Exclusions;
use super::parallel::{as_rows, as_vec3, balanced_range, Scratch, Vec3};
use super::simbox::SimBox;
use super::timers::Stage;
use super::EngineError;
use crate::kernels::{
    accumulate_multibody_sums, accumulate_reference_volumes, balance_multibody, gather_forces,
    gather_volumes, pair_forces, row_forces, row_volumes, window_forces, BondCoeffs, BondEntry,
    BondRows, BoxImage, Fault, ForcePass, MultibodyInputs, MultibodySum, Ownership, PairCoeffs,
    PairInputs, RowInputs, RowWindow, Separation, Tally, Unwrapped,
};

/// Index of the bond term in [`ModelTally::terms`].
pub const BOND_TERM: usize = 0;
/// Index of the pair term in [`ModelTally::terms`].
pub const PAIR_TERM: usize = 1;
/// The model's energy terms: the bond spring proxy `k (r - r0)^2 / 2` (the
/// multibody term has no energy) and the contact energy.
pub const ENERGY_TERMS: [EnergyTerm; 2] = [
    EnergyTerm {
        column: "e_bond",
        observable: "bond energy",
        lammps_compute: "pe bond",
    },
    EnergyTerm {
        column: "e_pair",
        observable: "pair energy",
        lammps_compute: "pe pair",
    },
];

/// Which terms of the model are live for this scene.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct BpmTerms {
    /// The multibody volume term (`a_B != 0`).
    pub multibody: bool,
    /// Bond damping (`Gamma_B != 0`).
    pub bond_damping: bool,
    /// Pair contacts (a pair style with non-zero stiffness).
    pub pairs: bool,
    /// Pair damping (`Gamma_P != 0`).
    pub pair_damping: bool,
    /// The zero-net-multibody correction (the variant chosen and the
    /// multibody term live).
    pub zero_net: bool,
}

impl BpmTerms {
    fn of(bond: &BondCoeffs, pair: Option<&PairCoeffs>, zero_net: bool, no_bonds: bool) -> Self {
        let pairs = pair.is_some_and(|p| p.k != 0.0 || p.a != 0.0);
        let multibody = bond.a != 0.0 && !no_bonds;
        Self {
            multibody,
            zero_net: zero_net && multibody,
            bond_damping: bond.gamma != 0.0,
            pairs,
            pair_damping: pairs && pair.is_some_and(|p| p.gamma != 0.0),
        }
    }
}

/// The bonds, bond and pair coefficients, and the per-particle volumes.
#[derive(Debug)]
pub struct BpmModel {
    bond: BondCoeffs,
    pair: Option<PairCoeffs>,
    bonds: BondTopology,
    terms: BpmTerms,
    volume: Vec<f64>,
    reference_volume: Vec<f64>,
    multibody_sums: Vec<MultibodySum>,
    force_scratch: Scratch<Vec3>,
    layout: BondLayout,
    /// Whether the zero-net-multibody variant was chosen (live only with
    /// the multibody term: [`BpmTerms::zero_net`]).
    zero_net_variant: bool,
}

/// What a step or a stage changes in the model: the current force field
/// and the reference lengths (a stress-free reset rewrites them). The
/// volumes and the bond layout follow from these.
#[derive(serde::Serialize, serde::Deserialize)]
struct BpmState {
    bond: BondCoeffs,
    pair: Option<PairCoeffs>,
    zero_net: bool,
    r0: Vec<f64>,
}

/// The bonds as rows for the two-step bond pass
/// ([`crate::kernels::row_forces`], then [`crate::kernels::gather_forces`]),
/// split by whether the plain difference of the stored positions is already
/// the minimum image ("interior", most bonds, first) or not ("boundary").
///
/// Positions wrap only when the pair list is rebuilt, and between wraps a
/// bond's plain difference changes continuously (also under affine
/// deformation), so the split holds until the next wrap; interior bonds then
/// skip the minimum-image arithmetic, as LAMMPS's ghost atoms do.
#[derive(Debug, Default)]
struct BondLayout {
    /// The wrap count of the system when the split was made.
    generation: Option<u64>,
    /// Interior rows, then boundary rows, each in CSR order.
    rows: BondRows,
    /// Number of interior rows.
    interior: usize,
    /// Each row's force on its atom `i`, written by the first step.
    force: Vec<[f64; 4]>,
    /// Each row's `[r, r^3]` (the multibody term only).
    lengths: Vec<[f64; 2]>,
    /// Each thread's share of the row pass.
    passes: Vec<ForcePass>,
    /// The windowed pass's plan for the current rows and team size, when
    /// the rows outgrow the cache ([`WINDOW_FROM_ROWS`]) and bonded
    /// partners lie close enough in the numbering; planned on first use.
    window: Option<RowWindow>,
    /// Whether `window` was planned for the current rows, and for how many
    /// threads.
    window_planned_for: Option<usize>,
    /// Each thread's buffer of rows (its ring, then the boundary rows) and
    /// what its part found.
    buffers: Vec<(Vec<[f64; 4]>, ForcePass)>,
    /// When to run the bond pass in windows.
    mode: BondWindow,
}

/// When the bond pass runs in windows ([`RowWindow`]): both ways give the
/// same forces bit for bit, and on one thread the same energy and virial.
/// On more threads those two sums differ in their last bits (the threads
/// split the rows differently), so a run that reads them (a barostat)
/// follows the full-size pass only to round-off.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum BondWindow {
    /// From [`WINDOW_FROM_ROWS`] rows on, where bonded partners lie close
    /// enough in the numbering.
    #[default]
    Auto,
    /// Whenever bonded partners lie close enough (tests, benchmarks).
    Always,
    /// Never: the full-size array of rows (tests, benchmarks).
    Never,
}

/// Rows from which the bond pass runs in windows ([`RowWindow`]): 8 MiB
/// of rows (32 bytes each). Below, the full-size array mostly stays in the
/// last-level cache and the windows gain nothing measurable (the 35,456-
/// particle packing, 193,664 rows: bond pass 0.91x on one thread, 1.02x and
/// 1.04x on two; `results/bench/issue33-bond-window/`).
const WINDOW_FROM_ROWS: usize = 1 << 18;
/// Rows a windowed part computes between two gathers.
const WINDOW_BLOCK: usize = 512;
/// The largest ring a window may use: 16,384 rows of 32 bytes, half a
/// core's 1 MiB L2 on the machines this is tuned on.
const WINDOW_MAX_RING: usize = 1 << 14;

impl BondLayout {
    fn rebuild<S: Separation>(
        &mut self,
        sep: &S,
        x: &[[f64; 3]],
        bonds: &BondTopology,
        reference_volumes: Option<&[f64]>,
        generation: u64,
    ) {
        let plain = |b: &BondEntry| {
            let (xi, xj) = (&x[b.i as usize], &x[b.j as usize]);
            sep.delta(xi, xj) == Unwrapped.delta(xi, xj)
        };
        let (interior, boundary): (Vec<usize>, Vec<usize>) =
            (0..bonds.len()).partition(|&b| plain(&bonds.entries[b]));
        self.interior = interior.len();
        let row = |b: usize| {
            let e = &bonds.entries[b];
            (e.i as usize, e.j as usize, bonds.r0[b], b)
        };
        let order: Vec<usize> = interior.into_iter().chain(boundary).collect();
        self.rows = BondRows::new(x.len(), order.into_iter().map(row), reference_volumes)
            .expect("the topology's bonds join distinct particles of the system");
        self.force.resize(self.rows.len(), [0.0; 4]);
        self.generation = Some(generation);
        self.window = None;
        self.window_planned_for = None;
    }

    /// Plans the window for a team of `threads` if the rows or the team
    /// changed since the last plan; none when the rows are few or their
    /// partners too far apart.
    fn plan_window(&mut self, threads: usize) {
        if self.window_planned_for != Some(threads) {
            let wanted = match self.mode {
                BondWindow::Auto => self.rows.len() >= WINDOW_FROM_ROWS,
                BondWindow::Always => true,
                BondWindow::Never => false,
            };
            self.window = wanted
                .then(|| {
                    let offsets = self.rows.offsets();
                    let parts: Vec<_> = (0..threads)
                        .map(|c| balanced_range(offsets, threads, c))
                        .collect();
                    RowWindow::plan(
                        &self.rows,
                        self.interior,
                        &parts,
                        WINDOW_BLOCK,
                        WINDOW_MAX_RING,
                    )
                })
                .flatten();
            self.window_planned_for = Some(threads);
            let buffer_len = self.window.as_ref().map_or(0, RowWindow::buffer_len);
            self.buffers.resize_with(threads, Default::default);
            for (buffer, _) in &mut self.buffers {
                buffer.resize(buffer_len, [0.0; 4]);
            }
        }
    }
}

impl BpmModel {
    /// A model of `bonds` on `n` particles, with the zero-net-multibody
    /// variant of the bond force or without; `V0` is computed here once.
    pub fn new(
        bond: BondCoeffs,
        pair: Option<PairCoeffs>,
        zero_net: bool,
        n: usize,
        bonds: BondTopology,
    ) -> Self {
        let mut model = Self {
            bond,
            pair,
            bonds,
            terms: BpmTerms::of(&bond, pair.as_ref(), zero_net, false),
            volume: Vec::new(),
            reference_volume: Vec::new(),
            multibody_sums: Vec::new(),
            force_scratch: Scratch::default(),
            layout: BondLayout::default(),
            zero_net_variant: zero_net,
        };
        model.set_coefficients(bond, pair, zero_net, n);
        model
    }

    /// Replaces the coefficients and the variant (a stage's force-field
    /// change) and re-derives the live terms and `V0`.
    pub fn set_coefficients(
        &mut self,
        bond: BondCoeffs,
        pair: Option<PairCoeffs>,
        zero_net: bool,
        n: usize,
    ) {
        self.bond = bond;
        self.pair = pair;
        self.zero_net_variant = zero_net;
        self.terms = BpmTerms::of(&bond, pair.as_ref(), zero_net, self.bonds.is_empty());
        self.update_reference_volumes(n);
    }

    /// Chooses when the bond pass runs in windows; the default,
    /// [`BondWindow::Auto`], is the fastest measured.
    pub fn set_bond_window(&mut self, mode: BondWindow) {
        self.layout.mode = mode;
        self.layout.window = None;
        self.layout.window_planned_for = None;
    }

    /// The windowed pass's ring size in rows and its halo fraction
    /// ([`RowWindow::halo_fraction`]) for the last step, if it ran in
    /// windows.
    pub fn bond_window(&self) -> Option<(usize, f64)> {
        self.layout
            .window
            .as_ref()
            .map(|w| (w.ring(), w.halo_fraction()))
    }

    /// Bond coefficients.
    pub fn bond_coeffs(&self) -> BondCoeffs {
        self.bond
    }

    /// Pair coefficients, if contacts are modelled.
    pub fn pair_coeffs(&self) -> Option<PairCoeffs> {
        self.pair
    }

    /// The bonds and their reference lengths.
    pub fn bonds(&self) -> &BondTopology {
        &self.bonds
    }

    /// The live terms.
    pub fn terms(&self) -> BpmTerms {
        self.terms
    }

    /// Makes every bond's current length its reference length (the
    /// stress-free reset of the compaction protocol) and recomputes `V0`.
    pub fn reset_reference(&mut self, simbox: &SimBox, x: &[[f64; 3]]) {
        self.bonds.reset_reference(simbox, x);
        self.update_reference_volumes(x.len());
    }

    fn update_reference_volumes(&mut self, n: usize) {
        self.layout.generation = None;
        if self.terms.multibody {
            self.volume = vec![0.0; n];
            self.reference_volume = vec![0.0; n];
            self.multibody_sums = vec![[0.0; 4]; n];
            accumulate_reference_volumes(
                &self.bonds.entries,
                &self.bonds.r0,
                Ownership::all(n),
                &mut self.reference_volume,
            );
        }
    }

    /// Current volume proxies `V_i` (empty when the multibody term is off).
    pub fn volumes(&self) -> (&[f64], &[f64]) {
        (&self.volume, &self.reference_volume)
    }

    /// Adds all bond and pair forces to `out.f`.
    fn compute_forces(&mut self, input: &ForceInput<'_>, out: &mut ForceOutput<'_>) -> ModelTally {
        let ForceInput {
            simbox,
            x,
            v,
            neighbours,
            wraps,
            team,
            tally,
            ..
        } = *input;
        let timers = &mut *out.timers;
        let f = &mut *out.f;
        let n = x.len();
        let own = Ownership::all(n);
        let chunks = team.threads();
        let sep = simbox.minimum_image();
        if self.layout.generation != Some(wraps) {
            let reference = self.terms.multibody.then_some(&self.reference_volume[..]);
            self.layout.rebuild(&sep, x, &self.bonds, reference, wraps);
        }
        self.layout.plan_window(chunks);
        let layout = &mut self.layout;
        layout.passes.resize(chunks, ForcePass::default());
        let rows = &layout.rows;
        if self.terms.multibody {
            let _t = timers.start(Stage::Volumes);
            layout.lengths.resize(rows.len(), [0.0; 2]);
            // No result per chunk: a vector of `()` allocates nothing.
            team.run_sections(
                &mut layout.lengths,
                layout.interior,
                &mut vec![(); chunks],
                |_, [(ri, interior), (rb, boundary)]| {
                    row_volumes(&Unwrapped, rows, ri, x, interior);
                    row_volumes(&sep, rows, rb, x, boundary);
                },
            );
            let lengths = &layout.lengths;
            team.run_split(&mut self.volume, |_, range, part| {
                gather_volumes(rows, range, lengths, part)
            });
        }
        let bond_pass = {
            let _t = timers.start(Stage::Bonds);
            let inputs = RowInputs {
                x,
                v: self.terms.bond_damping.then_some(v),
                coeffs: self.bond,
                multibody: self
                    .terms
                    .multibody
                    .then_some((&self.volume[..], &layout.lengths[..])),
                tally,
            };
            if let Some(window) = &layout.window {
                // Boundary rows first, into the full-size array's tail;
                // then each thread's part, its interior rows in its ring.
                team.run_sections(
                    &mut layout.force,
                    layout.interior,
                    &mut layout.passes,
                    |_, [_, (rb, boundary)]| row_forces(&sep, rows, rb, &inputs, boundary),
                );
                let boundary = &layout.force[layout.interior..];
                team.run_parts(
                    f,
                    window.particle_parts(),
                    &mut layout.buffers,
                    |c, part, (buffer, pass)| {
                        *pass = window_forces(rows, window, c, &inputs, boundary, buffer, part)
                    },
                );
                layout
                    .buffers
                    .iter()
                    .map(|(_, pass)| pass)
                    .chain(&layout.passes)
                    .fold(ForcePass::default(), |acc, p| acc.merged(p))
            } else {
                team.run_sections(
                    &mut layout.force,
                    layout.interior,
                    &mut layout.passes,
                    |_, [(ri, interior), (rb, boundary)]| {
                        row_forces(&Unwrapped, rows, ri, &inputs, interior)
                            .merged(&row_forces(&sep, rows, rb, &inputs, boundary))
                    },
                );
                let forces = &layout.force;
                team.run_split(f, |_, range, part| gather_forces(rows, range, forces, part));
                layout
                    .passes
                    .iter()
                    .fold(ForcePass::default(), |acc, p| acc.merged(p))
            }
        };
        let balance = if self.terms.zero_net {
            let _t = timers.start(Stage::Bonds);
            self.apply_zero_net_correction(&sep, x, tally, f)
        } else {
            Tally::default()
        };
        let pair_pass = match (self.terms.pairs, self.pair) {
            (true, Some(p)) if !neighbours.is_empty() => {
                let _t = timers.start(Stage::Pairs);
                let coeffs = [p];
                let inputs = PairInputs {
                    x,
                    v: self.terms.pair_damping.then_some(v),
                    types: None,
                    ntypes: 1,
                    coeffs: &coeffs,
                    special: [1.0; 4],
                    tally,
                };
                // A half list (`j > i`) split by `i` into parts of about
                // as many pairs: chunk c writes from its first `i` on.
                let first = |c| neighbours.balanced_rows(chunks, c).start;
                let image = BoxImage::of(&sep);
                self.force_scratch
                    .scatter(team, as_vec3(f), first, |c, out| {
                        let rows = neighbours.rows(neighbours.balanced_rows(chunks, c));
                        match &image {
                            BoxImage::Orthogonal(image) => {
                                pair_forces(image, &inputs, rows, own, as_rows(out))
                            }
                            BoxImage::Tilted(image) => {
                                pair_forces(image, &inputs, rows, own, as_rows(out))
                            }
                        }
                    })
            }
            _ => ForcePass::default(),
        };
        out.fault = out.fault.or(bond_pass.fault).or(pair_pass.fault);
        let mut result = ModelTally::default();
        result.terms[BOND_TERM] = bond_pass.tally.merged(&balance);
        result.terms[PAIR_TERM] = pair_pass.tally;
        result
    }
}

impl BpmModel {
    /// The zero-net-multibody correction, added to `f` after the bond pass:
    /// per-particle multibody sums, then the correction bond by bond. One
    /// thread: the variant is an option, not the hot path.
    fn apply_zero_net_correction<S: Separation>(
        &mut self,
        sep: &S,
        x: &[[f64; 3]],
        tally: bool,
        f: &mut [[f64; 3]],
    ) -> Tally {
        let own = Ownership::all(x.len());
        let bonds = &self.bonds;
        self.multibody_sums.fill([0.0; 4]);
        let inputs = MultibodyInputs {
            x,
            bonds: &bonds.entries,
            r0: &bonds.r0,
            coeffs: std::slice::from_ref(&self.bond),
            volumes: (&self.volume, &self.reference_volume),
        };
        accumulate_multibody_sums(sep, &inputs, own, &mut self.multibody_sums);
        balance_multibody(sep, x, &bonds.entries, &self.multibody_sums, own, f, tally)
    }
}

impl ParticleModel for BpmModel {
    fn name(&self) -> &'static str {
        "bpm"
    }

    fn pair_cutoff(&self) -> Option<f64> {
        self.terms.pairs.then(|| self.pair.map_or(0.0, |p| p.d))
    }

    fn exclusions(&self) -> Option<&Exclusions> {
        Some(self.bonds.exclusions())
    }

    fn energy_terms(&self) -> &'static [EnergyTerm] {
        &ENERGY_TERMS
    }

    fn compute(&mut self, input: &ForceInput<'_>, out: &mut ForceOutput<'_>) -> ModelTally {
        self.compute_forces(input, out)
    }

    fn likely_cause(&self, fault: &Fault, dt: f64, mass: f64, nearest_unbonded: f64) -> String {
        fault.likely_cause(dt, Some(&self.bond), mass, nearest_unbonded)
    }

    fn save_state(&self) -> Result<ciborium::Value, EngineError> {
        let state = BpmState {
            bond: self.bond,
            pair: self.pair,
            zero_net: self.zero_net_variant,
            r0: self.bonds.r0.clone(),
        };
        ciborium::Value::serialized(&state).map_err(|e| EngineError::StateMismatch {
            what: format!("the bonded model's state could not be saved: {e}"),
        })
    }

    fn restore_state(&mut self, state: ciborium::Value) -> Result<(), EngineError> {
        let state: BpmState = state
            .deserialized()
            .map_err(|e| EngineError::StateMismatch {
                what: format!("it is not a bonded model's state: {e}"),
            })?;
        if state.r0.len() != self.bonds.len() {
            return Err(EngineError::StateMismatch {
                what: format!(
                    "it has {} bonds, this system {}",
                    state.r0.len(),
                    self.bonds.len()
                ),
            });
        }
        self.bonds.r0 = state.r0;
        let n = self.bonds.offsets.len().saturating_sub(1);
        self.set_coefficients(state.bond, state.pair, state.zero_net, n);
        Ok(())
    }

    fn as_any(&self) -> &dyn std::any::Any {
        self
    }

    fn as_any_mut(&mut self) -> &mut dyn std::any::Any {
        self
    }
}
