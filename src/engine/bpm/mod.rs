//! The bonded particle model as a particle model of the engine: point
//! particles joined by bonds (spring + multibody volume term + damping),
//! with harmonic-plus-cubic contacts between unbonded particles.
//!
//! The model owns its bonds, their reference lengths and the per-particle
//! volume proxies. Terms that a scene cannot use are removed at load: no
//! volume pass when `a_B` is 0, no velocity terms when `Gamma` is 0, no pair
//! list when there is no pair style or it has no stiffness, and the
//! elastic bond pass unless bonds break or yield.
//!
//! Bonds that break ([`BondFailure`]) leave the bond arrays at the end of
//! the step in which they break; their particles then interact through the
//! contact law from the next force evaluation, through a short list of new contacts
//! until the pair list is next rebuilt without their exclusion. With
//! [`BpmForceField::overlay_pair`] nothing is excluded: bonded particles
//! touch through the contact law as well, as unbonded ones do. The
//! volume proxies `V` and `V0` sum over intact bonds, and `V0` over their
//! rest lengths (docs/model.md, "Breaking and yielding").

mod topology;

pub use topology::BondTopology;

use super::model::{EnergyTerm, ForceInput, ForceOutput, ModelTally, ParticleModel};
use super::neighbor::Exclusions;
use super::parallel::{as_rows, as_vec3, balanced_range, Scratch, Vec3};
use super::simbox::SimBox;
use super::timers::Stage;
use super::EngineError;
use crate::kernels::{
    accumulate_multibody_sums, accumulate_reference_volumes, balance_multibody, failing_row_forces,
    gather_forces, gather_rest_volumes, gather_volumes, pair_forces, row_broke, row_forces,
    row_volumes, window_forces, BondCoeffs, BondEntry, BondFailure, BondRows, BoxImage,
    FailurePass, Fault, ForcePass, MultibodyInputs, MultibodySum, Ownership, PairCoeffs,
    PairInputs, PlasticRows, RowInputs, RowWindow, Separation, Tally, Unwrapped,
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
    /// Bonds break, yield or have a spring in strain
    /// ([`BondFailure::is_live`]): the failing bond pass replaces the
    /// elastic one.
    pub failure: bool,
    /// Bonds yield: their rest lengths, and with the multibody term the
    /// reference volumes, change from step to step.
    pub yields: bool,
}

impl BpmTerms {
    fn of(field: &BpmForceField, no_bonds: bool) -> Self {
        let (bond, pair) = (&field.bond, field.pair.as_ref());
        let pairs = pair.is_some_and(|p| p.k != 0.0 || p.a != 0.0);
        let multibody = bond.a != 0.0 && !no_bonds;
        let failure = field.live_failure();
        Self {
            multibody,
            zero_net: field.zero_net && multibody,
            bond_damping: bond.gamma != 0.0,
            pairs,
            pair_damping: pairs && pair.is_some_and(|p| p.gamma != 0.0),
            failure: failure.is_some() && !no_bonds,
            yields: failure.is_some_and(|f| f.plastic_strain.is_some()) && !no_bonds,
        }
    }
}

/// The bonded model's force field: bond coefficients and how bonds fail,
/// pair coefficients, and the bond force's variant.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct BpmForceField {
    /// Bond coefficients.
    pub bond: BondCoeffs,
    /// How bonds break and yield; `None`, they stay elastic.
    pub failure: Option<BondFailure>,
    /// Pair coefficients, if contacts are modelled.
    pub pair: Option<PairCoeffs>,
    /// Bonded particles also touch through the contact law: the pair list
    /// keeps them (upstream's `overlay/pair yes`).
    #[serde(default)]
    pub overlay_pair: bool,
    /// The zero-net-multibody variant (the scene refuses it with failing
    /// bonds).
    pub zero_net: bool,
}

impl BpmForceField {
    /// How bonds fail, if that changes anything ([`BondFailure::is_live`]).
    pub fn live_failure(&self) -> Option<&BondFailure> {
        self.failure.as_ref().filter(|f| f.is_live())
    }
}

/// The bonds, bond and pair coefficients, and the per-particle volumes.
#[derive(Debug)]
pub struct BpmModel {
    field: BpmForceField,
    bonds: BondTopology,
    terms: BpmTerms,
    volume: Vec<f64>,
    reference_volume: Vec<f64>,
    multibody_sums: Vec<MultibodySum>,
    force_scratch: Scratch<Vec3>,
    layout: BondLayout,
    /// Each thread's share of the failing bond pass.
    failure_passes: Vec<FailurePass>,
    /// Pairs whose bond broke since the pair list was built.
    new_contacts: NewContacts,
    /// The particles of every bond that broke, in the order they broke.
    broken: Vec<[usize; 2]>,
    /// Whether `V0` must be summed anew over the rows' rest lengths before
    /// the next pass (bonds that yield, with the multibody term): after a
    /// layout rebuild and after a pass in which bonds yielded.
    rest_volumes_stale: bool,
}

/// Pairs whose bond broke: they interact as contacts from the step after,
/// through this list until the pair list is rebuilt (positions wrapped)
/// without their exclusion.
#[derive(Clone, Debug, Default, serde::Serialize, serde::Deserialize)]
struct NewContacts {
    /// The wrap count (pair-list generation) the list belongs to.
    wraps: u64,
    /// `(i, [j])` with `i < j`, in the form of a pair list's rows.
    pairs: Vec<(usize, [i32; 1])>,
}

/// What a step or a stage changes in the model: the current force field,
/// the reference lengths (a stress-free reset rewrites them), and with
/// failing bonds the bonds left, their plastic strains, the bonds broken
/// and the contacts they left. The volumes and the bond layout follow from
/// these.
#[derive(serde::Serialize, serde::Deserialize)]
struct BpmState {
    field: BpmForceField,
    r0: Vec<f64>,
    /// With failing bonds: the bonds left, their plastic strains, the broken
    /// bonds and the contacts not yet in the pair list.
    failing: Option<FailingState>,
}

#[derive(serde::Serialize, serde::Deserialize)]
struct FailingState {
    bonds: Vec<[usize; 2]>,
    plastic: Vec<f64>,
    broken: Vec<[usize; 2]>,
    new_contacts: NewContacts,
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
    /// Each row's plastic strain (bonds that yield only).
    plastic: PlasticRows,
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

    /// Writes each row's plastic strain to its bond's place in `plastic`.
    fn copy_plastic_strains(&self, plastic: &mut [f64]) {
        for (b, &e_p) in self.rows.bonds().zip(self.plastic.strains()) {
            plastic[b] = e_p;
        }
    }

    /// Plans the window for a team of `threads` if the rows or the team
    /// changed since the last plan; none when the rows are few or their
    /// partners too far apart, or the pass cannot run in windows
    /// (`!allowed`: the failing bond pass has no windowed build). A change
    /// of `allowed` comes with new rows.
    fn plan_window(&mut self, threads: usize, allowed: bool) {
        if self.window_planned_for != Some(threads) {
            let wanted = allowed
                && match self.mode {
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
    /// A model of `bonds` on `n` particles with force field `field`; `V0`
    /// is computed here once.
    pub fn new(field: BpmForceField, n: usize, bonds: BondTopology) -> Self {
        let mut model = Self {
            field,
            bonds,
            terms: BpmTerms::of(&field, false),
            volume: Vec::new(),
            reference_volume: Vec::new(),
            multibody_sums: Vec::new(),
            force_scratch: Scratch::default(),
            layout: BondLayout::default(),
            failure_passes: Vec::new(),
            new_contacts: NewContacts::default(),
            broken: Vec::new(),
            rest_volumes_stale: true,
        };
        model.set_force_field(field, n);
        model
    }

    /// Replaces the force field (a stage's force-field change) and
    /// re-derives the live terms and `V0`. A change of `overlay_pair`
    /// changes which pairs the pair list must hold: rebuild it (as
    /// [`crate::engine::System::setup`] does at each stage start). Bonds keep their plastic
    /// strains; a field whose bonds do not yield makes each bond's rest
    /// length its reference length.
    pub fn set_force_field(&mut self, field: BpmForceField, n: usize) {
        self.retire_layout();
        if field
            .live_failure()
            .and_then(|f| f.plastic_strain)
            .is_none()
        {
            self.bonds.fold_plastic_strains();
        }
        self.field = field;
        self.terms = BpmTerms::of(&field, self.bonds.is_empty());
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
        self.field.bond
    }

    /// Pair coefficients, if contacts are modelled.
    pub fn pair_coeffs(&self) -> Option<PairCoeffs> {
        self.field.pair
    }

    /// The force field.
    pub fn force_field(&self) -> BpmForceField {
        self.field
    }

    /// The bonds and their reference lengths. Plastic strains are those of
    /// the last bond-layout rebuild; [`BpmModel::plastic_strains`] has the
    /// current ones.
    pub fn bonds(&self) -> &BondTopology {
        &self.bonds
    }

    /// Each bond's current plastic strain, in the order of
    /// [`BpmModel::bonds`].
    pub fn plastic_strains(&self) -> Vec<f64> {
        let mut plastic = self.bonds.plastic.clone();
        if self.layout_holds_plastic_strains() {
            self.layout.copy_plastic_strains(&mut plastic);
        }
        plastic
    }

    /// The particles of every bond that broke, in the order they broke.
    pub fn broken_bonds(&self) -> &[[usize; 2]] {
        &self.broken
    }

    /// The live terms.
    pub fn terms(&self) -> BpmTerms {
        self.terms
    }

    /// Makes every bond's current length its reference length and its
    /// plastic strain 0 (the stress-free reset of the compaction protocol)
    /// and recomputes `V0`.
    pub fn reset_reference(&mut self, simbox: &SimBox, x: &[[f64; 3]]) {
        self.retire_layout();
        self.bonds.reset_reference(simbox, x);
        self.update_reference_volumes(x.len());
    }

    /// Whether the bond layout holds the bonds' current plastic strains,
    /// newer than the topology's.
    fn layout_holds_plastic_strains(&self) -> bool {
        self.terms.yields && self.layout.generation.is_some()
    }

    /// Drops the bond layout, first giving the topology the plastic strains
    /// it holds; the next evaluation builds it anew.
    fn retire_layout(&mut self) {
        if self.layout_holds_plastic_strains() {
            self.layout.copy_plastic_strains(&mut self.bonds.plastic);
        }
        self.layout.generation = None;
    }

    /// Recomputes `V0` over the bonds' rest lengths (only with the
    /// multibody term); the layout must have been retired.
    fn update_reference_volumes(&mut self, n: usize) {
        debug_assert!(self.layout.generation.is_none(), "layout retired first");
        if self.terms.multibody {
            self.volume = vec![0.0; n];
            self.reference_volume = vec![0.0; n];
            self.multibody_sums = vec![[0.0; 4]; n];
            let rest: Vec<f64>;
            let lengths = if self.bonds.plastic.iter().any(|&e| e != 0.0) {
                rest = self.bonds.rest_lengths().collect();
                &rest
            } else {
                &self.bonds.r0
            };
            accumulate_reference_volumes(
                &self.bonds.entries,
                lengths,
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
            self.retire_layout();
            let reference = self.terms.multibody.then_some(&self.reference_volume[..]);
            self.layout.rebuild(&sep, x, &self.bonds, reference, wraps);
            self.rest_volumes_stale = true;
            let yielding = self.field.live_failure().filter(|_| self.terms.yields);
            if let Some(rule) = yielding {
                let layout = &mut self.layout;
                let strains = layout.rows.bonds().map(|b| self.bonds.plastic[b]).collect();
                layout.plastic = PlasticRows::new(&layout.rows, strains);
                layout.plastic.band_for(rule);
            }
        }
        self.layout.plan_window(chunks, !self.terms.failure);
        if self.terms.multibody && self.terms.yields && self.rest_volumes_stale {
            // V0 of the rest lengths the last pass left.
            let _t = timers.start(Stage::Volumes);
            let layout = &self.layout;
            team.run_split(&mut self.reference_volume, |_, range, part| {
                gather_rest_volumes(&layout.rows, range, &layout.plastic, part)
            });
            self.layout
                .rows
                .set_reference_volumes(&self.reference_volume)
                .expect("one reference volume per particle");
            self.rest_volumes_stale = false;
        }
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
        let inputs = RowInputs {
            x,
            v: self.terms.bond_damping.then_some(v),
            coeffs: self.field.bond,
            multibody: self
                .terms
                .multibody
                .then_some((&self.volume[..], &layout.lengths[..])),
            tally,
        };
        let mut broken = 0;
        let bond_pass = {
            let _t = timers.start(Stage::Bonds);
            if let Some(rule) = self.field.live_failure().filter(|_| self.terms.failure) {
                self.failure_passes.resize(chunks, FailurePass::default());
                let plastic = rule.plastic_strain.map(|_| layout.plastic.shared());
                team.run_sections(
                    &mut layout.force,
                    layout.interior,
                    &mut self.failure_passes,
                    |_, [(ri, interior), (rb, boundary)]| {
                        let section = |r: &std::ops::Range<usize>| {
                            // SAFETY: each chunk gets rows of its own.
                            plastic.as_ref().map(|p| unsafe { p.section(r.clone()) })
                        };
                        let (pi, pb) = (section(&ri), section(&rb));
                        failing_row_forces(&Unwrapped, rows, ri, &inputs, rule, pi, interior)
                            .merged(&failing_row_forces(
                                &sep, rows, rb, &inputs, rule, pb, boundary,
                            ))
                    },
                );
                let forces = &layout.force;
                team.run_split(f, |_, range, part| gather_forces(rows, range, forces, part));
                let pass = self
                    .failure_passes
                    .iter()
                    .fold(FailurePass::default(), |acc, p| acc.merged(p));
                broken = pass.broken;
                self.rest_volumes_stale |= pass.yielded > 0;
                pass.pass
            } else if let Some(window) = &layout.window {
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
        if self.new_contacts.wraps != wraps {
            // The pair list was rebuilt: it holds them now.
            self.new_contacts.pairs.clear();
        }
        let pair_pass = match (self.terms.pairs, self.field.pair) {
            (true, Some(p)) => {
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
                    damping_taper: false,
                };
                // A half list (`j > i`) split by `i` into parts of about
                // as many pairs: chunk c writes from its first `i` on.
                let first = |c| neighbours.balanced_rows(chunks, c).start;
                let image = BoxImage::of(&sep);
                let listed = if neighbours.is_empty() {
                    ForcePass::default()
                } else {
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
                };
                let new = &self.new_contacts.pairs;
                let unlisted = new.iter().map(|(i, j)| (*i, &j[..]));
                listed.merged(&pair_forces(&sep, &inputs, unlisted, own, f))
            }
            _ => ForcePass::default(),
        };
        if broken > 0 {
            self.break_bonds(wraps);
        }
        out.fault = out.fault.or(bond_pass.fault).or(pair_pass.fault);
        let mut result = ModelTally::default();
        result.terms[BOND_TERM] = bond_pass.tally.merged(&balance);
        result.terms[PAIR_TERM] = pair_pass.tally;
        result
    }

    /// Removes the bonds whose rows broke in the last pass: their pairs
    /// become new contacts, `V0` is summed over the bonds left, and the
    /// layout is built anew at the next evaluation.
    fn break_bonds(&mut self, wraps: u64) {
        let layout = &self.layout;
        let mut doomed: Vec<usize> = layout
            .rows
            .bonds()
            .zip(&layout.force)
            .filter(|(_, row)| row_broke(row))
            .map(|(b, _)| b)
            .collect();
        doomed.sort_unstable();
        self.retire_layout();
        let pairs = self.bonds.remove(&doomed);
        if self.new_contacts.wraps != wraps {
            self.new_contacts = NewContacts {
                wraps,
                pairs: Vec::new(),
            };
        }
        // Without contacts there is no pair list to wait for; with the
        // contacts overlaid on the bonds, the list holds these pairs already.
        if self.terms.pairs && !self.field.overlay_pair {
            self.new_contacts
                .pairs
                .extend(pairs.iter().map(|&[i, j]| (i, [j as i32])));
        }
        self.broken.extend(pairs);
        let n = self.bonds.offsets.len().saturating_sub(1);
        self.terms = BpmTerms::of(&self.field, self.bonds.is_empty());
        self.update_reference_volumes(n);
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
            coeffs: std::slice::from_ref(&self.field.bond),
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
        self.terms
            .pairs
            .then(|| self.field.pair.map_or(0.0, |p| p.d))
    }

    fn exclusions(&self) -> Option<&Exclusions> {
        (!self.field.overlay_pair).then(|| self.bonds.exclusions())
    }

    fn bonded_pairs(&self) -> Option<&Exclusions> {
        Some(self.bonds.exclusions())
    }

    fn energy_terms(&self) -> &'static [EnergyTerm] {
        &ENERGY_TERMS
    }

    fn compute(&mut self, input: &ForceInput<'_>, out: &mut ForceOutput<'_>) -> ModelTally {
        self.compute_forces(input, out)
    }

    fn likely_cause(&self, fault: &Fault, dt: f64, mass: f64, nearest_unbonded: f64) -> String {
        fault.likely_cause(dt, Some(&self.field.bond), mass, nearest_unbonded)
    }

    fn save_state(&self) -> Result<ciborium::Value, EngineError> {
        // Whatever changed the bonds since the scene was loaded, even if
        // the rule is off now (every bond broke, or a later stage's field
        // has none).
        let changed = self.terms.failure
            || !self.broken.is_empty()
            || self.bonds.plastic.iter().any(|&e| e != 0.0);
        let failing = changed.then(|| FailingState {
            bonds: self.bonds.pairs().collect(),
            plastic: self.plastic_strains(),
            broken: self.broken.clone(),
            new_contacts: self.new_contacts.clone(),
        });
        let state = BpmState {
            field: self.field,
            r0: self.bonds.r0.clone(),
            failing,
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
        let n = self.bonds.offsets.len().saturating_sub(1);
        let count_mismatch = |what: &str, saved: usize, here: usize| {
            Err(EngineError::StateMismatch {
                what: format!("it has {saved} {what}, this system {here}"),
            })
        };
        self.layout.generation = None;
        match state.failing {
            Some(failing) => {
                if failing.bonds.len() != state.r0.len() || failing.plastic.len() != state.r0.len()
                {
                    return count_mismatch("bonds", failing.bonds.len(), state.r0.len());
                }
                if let Some(&[i, j]) = failing.bonds.iter().find(|[i, j]| *i >= n || *j >= n) {
                    return Err(EngineError::StateMismatch {
                        what: format!("it bonds particles {i} and {j}, this system has {n}"),
                    });
                }
                let bonds: Vec<_> = failing
                    .bonds
                    .iter()
                    .zip(&state.r0)
                    .zip(&failing.plastic)
                    .map(|((&[i, j], &r0), &e_p)| (i, j, r0, e_p))
                    .collect();
                self.bonds = BondTopology::with_plastic_strains(n, &bonds);
                self.broken = failing.broken;
                self.new_contacts = failing.new_contacts;
            }
            None => {
                if state.r0.len() != self.bonds.len() {
                    return count_mismatch("bonds", state.r0.len(), self.bonds.len());
                }
                self.bonds.r0 = state.r0;
                self.bonds.plastic.fill(0.0);
                self.broken.clear();
                self.new_contacts = NewContacts::default();
            }
        }
        self.set_force_field(state.field, n);
        Ok(())
    }

    fn as_any(&self) -> &dyn std::any::Any {
        self
    }

    fn as_any_mut(&mut self) -> &mut dyn std::any::Any {
        self
    }
}
