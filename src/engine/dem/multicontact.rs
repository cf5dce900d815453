//! The multi-contact closure as a pass before the contact forces: from
//! every sphere's contacts and their normal forces at the last evaluation,
//! the radius correction of each side of each pair and of each sphere at
//! each wall (`kernels::SurfaceCorrections`).
//!
//! Each sphere's contacts are its listed pairs within reach and the walls
//! within reach. A contact point is where the two surfaces meet, halfway
//! through the overlap (or, apart, the sphere's own surface point facing
//! the partner); at a wall, the point on the wall's plane. Pairs and walls
//! that do not touch yet are receivers only: their correction may bring
//! them into contact, which is why the pair list reaches further than the
//! spheres' diameters by the closure's `reach`.

// Sphere and list-entry indices address several arrays at once.
#![allow(clippy::needless_range_loop)]

use super::super::model::ForceInput;
use super::super::neighbor::NeighbourList;
use super::super::parallel::balanced_range;
use super::super::team::{SharedSlice, Team};
use super::wall::ActiveGranularWall;
use crate::kernels::{
    pair_contact_points, BoxImage, Closure, ContactHistory, ContactPoint, GranularMaterial,
    HalfSpace, MprSwitch, MprTest, SurfaceCorrections, WallPlane,
};
use serde::{Deserialize, Serialize};

/// The multi-contact closure of a DEM scene: `force_field.multicontact`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MultiContact {
    /// Geometric prefactor `gamma` of the half-space displacements, >= 0
    /// (0 is plain Hertz).
    pub prefactor: f64,
    /// The advanced closure's maximum penetration ratio `MPR` (a term
    /// beyond `MPR R` switches the correction off); absent for the
    /// standard closure.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub max_penetration_ratio: Option<f64>,
    /// What a term beyond `MPR R` switches off (advanced closure only).
    #[serde(default)]
    pub switch: MprSwitch,
    /// How a term is compared with `MPR R` (advanced closure only).
    #[serde(default)]
    pub test: MprTest,
    /// How far beyond touching, as a fraction of the two radii, a pair or
    /// wall still receives a correction (and so may come into contact);
    /// positive, default 0.25. A run whose corrections exceed it stops
    /// with an error naming the contact.
    #[serde(default = "default_reach")]
    pub reach: f64,
}

fn default_reach() -> f64 {
    0.25
}

impl MultiContact {
    /// The standard closure with prefactor `gamma`.
    pub fn standard(gamma: f64) -> Self {
        Self {
            prefactor: gamma,
            max_penetration_ratio: None,
            switch: MprSwitch::default(),
            test: MprTest::default(),
            reach: default_reach(),
        }
    }

    /// The advanced closure with prefactor `gamma` and maximum penetration
    /// ratio `mpr`, switching whole contacts on the signed test.
    pub fn advanced(gamma: f64, mpr: f64) -> Self {
        Self {
            max_penetration_ratio: Some(mpr),
            ..Self::standard(gamma)
        }
    }

    /// How the kernel combines the terms.
    pub fn closure(&self) -> Closure {
        match self.max_penetration_ratio {
            None => Closure::Standard,
            Some(max_penetration_ratio) => Closure::Advanced {
                max_penetration_ratio,
                switch: self.switch,
                test: self.test,
            },
        }
    }
}

/// Where a contact's correction goes.
#[derive(Clone, Copy, Debug)]
enum Side {
    /// A pair-list entry: `side` 0 is the row's sphere, 1 its neighbour.
    Pair { entry: u32, side: u8 },
    /// A wall (the sphere is the one whose contacts these are).
    Wall(u32),
}

/// What one pass found: the extreme corrections, how many the advanced
/// closure switched off, and the first contact where the closure stops
/// meaning anything.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ClosureReport {
    /// Largest correction over its sphere's radius (0 if none is positive).
    pub largest: f64,
    /// Most negative correction over its sphere's radius (0 if none is).
    pub smallest: f64,
    /// Contacts (whole-contact switch) or terms (per-term switch) the
    /// advanced closure switched off.
    pub switched_off: usize,
    /// The first contact whose corrections reach beyond `reach` of
    /// touching. A pair further apart, which receives no correction,
    /// might then touch if it did: a warning sign, not a proof.
    pub beyond_reach: Option<BeyondReach>,
    /// `(sphere, correction / radius)`: the first correction that moves a
    /// surface onto or past its sphere's centre.
    pub collapsed: Option<(usize, f64)>,
}

impl ClosureReport {
    /// The report of two runs of spheres, `self`'s before `later`'s (the
    /// first collapse in sphere order; no contact beyond reach yet).
    fn merged(self, later: Self) -> Self {
        Self {
            largest: self.largest.max(later.largest),
            smallest: self.smallest.min(later.smallest),
            switched_off: self.switched_off + later.switched_off,
            beyond_reach: None,
            collapsed: self.collapsed.or(later.collapsed),
        }
    }
}

/// A contact whose corrections exceed the closure's reach.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BeyondReach {
    /// The sphere.
    pub sphere: usize,
    /// The partner sphere, or the wall.
    pub partner: usize,
    /// Whether the partner is a wall.
    pub wall: bool,
    /// The corrections over the radii they may add to.
    pub ratio: f64,
}

/// The closure's state: its settings and reusable buffers, and the
/// corrections of the last pass.
#[derive(Clone, Debug)]
pub struct ClosurePass {
    settings: MultiContact,
    closure: Closure,
    half_space: HalfSpace,
    /// Per pair-list entry, the pair's separation `x_i - x_j` and its
    /// length, the length NaN when the pair is out of reach.
    separation: Vec<([f64; 3], f64)>,
    /// The granular walls' planes at this pass.
    planes: Vec<WallPlane>,
    /// Per granular wall, per sphere, its centre's distance from the
    /// wall, or NaN when out of reach.
    wall_distance: Vec<Vec<f64>>,
    /// Sphere `i`'s contacts are `offsets[i]..offsets[i + 1]` of `sides`
    /// and `points`.
    offsets: Vec<usize>,
    /// Where each contact's correction goes, grouped by sphere.
    sides: Vec<Side>,
    points: Vec<ContactPoint>,
    /// Per chunk of the list's rows, per sphere: the chunk's pairs within
    /// reach of the sphere, then the sphere's next free slot for them.
    cursors: Vec<Vec<usize>>,
    /// Each chunk's first row.
    lowest: Vec<usize>,
    /// Each sphere's next free slot for its walls.
    wall_cursor: Vec<usize>,
    /// Prefix sums of the spheres' estimated correction costs, to share
    /// them out among the threads.
    work: Vec<usize>,
    deltas: Vec<f64>,
    /// One correction kernel (with its buffers) per thread.
    kernels: Vec<SurfaceCorrections>,
    /// Per pair-list entry, the corrections of its two sides.
    pair: Vec<[f64; 2]>,
    /// Per wall, per sphere, the sphere's correction at the wall: wall
    /// `w`'s from `w spheres` on.
    wall: Vec<f64>,
    /// Spheres at the last pass.
    spheres: usize,
    /// What the last pass found.
    report: ClosureReport,
}

impl ClosurePass {
    /// The closure `settings` for spheres of `material`.
    pub fn new(settings: MultiContact, material: &GranularMaterial) -> Self {
        Self {
            settings,
            closure: settings.closure(),
            half_space: HalfSpace::new(
                settings.prefactor,
                material.youngs_modulus,
                material.poisson_ratio,
            ),
            separation: Vec::new(),
            planes: Vec::new(),
            wall_distance: Vec::new(),
            offsets: Vec::new(),
            sides: Vec::new(),
            points: Vec::new(),
            cursors: Vec::new(),
            lowest: Vec::new(),
            wall_cursor: Vec::new(),
            work: Vec::new(),
            deltas: Vec::new(),
            kernels: Vec::new(),
            pair: Vec::new(),
            wall: Vec::new(),
            spheres: 0,
            report: ClosureReport::default(),
        }
    }

    /// The settings.
    pub fn settings(&self) -> &MultiContact {
        &self.settings
    }

    /// Per pair-list entry, the corrections of its two sides (row sphere,
    /// neighbour), from the last pass.
    pub fn pair_corrections(&self) -> &[[f64; 2]] {
        &self.pair
    }

    /// Per sphere, its correction at wall `w`, from the last pass.
    pub fn wall_corrections(&self, w: usize) -> &[f64] {
        &self.wall[w * self.spheres..(w + 1) * self.spheres]
    }

    /// What the last pass found.
    pub fn report(&self) -> &ClosureReport {
        &self.report
    }

    /// Computes every correction for the state in `input` from the normal
    /// forces stored in the pair and wall histories, on the input's team:
    /// the pairs are measured and placed in parallel over the list's rows,
    /// the spheres corrected in parallel over spheres. Each sphere's
    /// contacts take the same slots, in the same order, on any number of
    /// threads, so the corrections are the same bits.
    pub fn update(
        &mut self,
        sep: &BoxImage,
        input: &ForceInput<'_>,
        pair_history: &[ContactHistory],
        walls: &[ActiveGranularWall],
        wall_history: &[Vec<ContactHistory>],
    ) {
        let (radius, list, team) = (input.radius, input.neighbours, input.team);
        let n = input.x.len();
        let mut planes = std::mem::take(&mut self.planes);
        planes.clear();
        planes.extend(walls.iter().map(|w| w.plane(input.elapsed)));
        self.measure(sep, input);
        self.count(input, &planes);
        self.place(list, radius, pair_history, team);
        self.place_walls(radius, &planes, wall_history);
        self.planes = planes;
        self.spheres = n;
        self.wall.clear();
        self.wall.resize(walls.len() * n, 0.0);
        let chunks = team.threads();
        self.kernels
            .resize_with(chunks, SurfaceCorrections::default);
        let kernels = SharedSlice::new(&mut self.kernels);
        let deltas = SharedSlice::new(&mut self.deltas);
        // One entry per side: a pair's two sides may be two threads'.
        let pair = SharedSlice::new(self.pair.as_flattened_mut());
        let wall = SharedSlice::new(&mut self.wall);
        let corrected = CorrectedSpheres {
            half_space: &self.half_space,
            closure: &self.closure,
            radius,
            offsets: &self.offsets,
            points: &self.points,
            sides: &self.sides,
        };
        let mut report = team.reduce_chunks(
            ClosureReport::default(),
            |c| {
                let spheres = balanced_range(&self.work, chunks, c);
                let contacts = self.offsets[spheres.start]..self.offsets[spheres.end];
                // SAFETY: chunk c alone uses kernels[c]; the chunks' spheres,
                // and so their contacts, are disjoint, and each side of a
                // pair and each sphere at a wall is one sphere's contact.
                let target = CorrectionTarget {
                    kernel: unsafe { kernels.get(c) },
                    first: contacts.start,
                    deltas: unsafe { deltas.range(contacts) },
                    pair: &pair,
                    wall: &wall,
                    spheres: n,
                };
                unsafe { corrected.correct(spheres, target) }
            },
            ClosureReport::merged,
        );
        report.beyond_reach = self.beyond_reach(list, radius, report.largest);
        self.report = report;
    }

    /// Measures every listed pair within reach into `separation` (NaN
    /// lengths for the others), clears its corrections, and counts per
    /// chunk of the list's rows each sphere's pairs within reach in that
    /// chunk (into `cursors`, from the chunk's first row on: a half list
    /// reaches no lower sphere); in parallel over the rows.
    fn measure(&mut self, sep: &BoxImage, input: &ForceInput<'_>) {
        let (x, radius, list, team) = (input.x, input.radius, input.neighbours, input.team);
        let (n, entries) = (x.len(), list.neighbours.len());
        let reach_factor = 1.0 + self.settings.reach;
        self.separation.resize(entries, ([0.0; 3], f64::NAN));
        self.pair.resize(entries, [0.0; 2]);
        let chunks = team.threads();
        self.cursors.resize_with(chunks, Vec::new);
        let separation = SharedSlice::new(&mut self.separation);
        let pair = SharedSlice::new(&mut self.pair);
        let cursors = SharedSlice::new(&mut self.cursors);
        team.run(|c| {
            let rows = list.balanced_rows(chunks, c);
            let section = list.entries(rows.clone());
            let first = section.start;
            // SAFETY: the chunks' rows, and so their list entries, are
            // disjoint, and chunk c alone uses cursors[c].
            let (out, pair, counts) = unsafe {
                (
                    separation.range(section.clone()),
                    pair.range(section),
                    cursors.get(c),
                )
            };
            pair.fill([0.0; 2]);
            counts.resize(n, 0);
            counts[rows.start..].fill(0);
            for i in rows {
                for k in list.offsets[i]..list.offsets[i + 1] {
                    let j = list.neighbours[k] as usize;
                    // `place` hands out slots safely only on a half list:
                    // a pair is counted and placed by its lower sphere's
                    // chunk alone.
                    assert!(j > i, "pair list entry {k} ({i}, {j}) is not j > i");
                    let (del, _) = sep.delta_image(&x[i], &x[j]);
                    let r = (del[0] * del[0] + del[1] * del[1] + del[2] * del[2]).sqrt();
                    out[k - first] = if r < reach_factor * (radius[i] + radius[j]) {
                        counts[i] += 1;
                        counts[j] += 1;
                        (del, r)
                    } else {
                        ([0.0; 3], f64::NAN)
                    };
                }
            }
        });
    }

    /// Gives each sphere its slots (`offsets`: its pairs within reach, then
    /// its walls within reach), turns each chunk's counts into the chunk's
    /// first slot per sphere (`cursors`) and each sphere's first wall slot
    /// (`wall_cursor`), measures each sphere's distance from every wall,
    /// and weighs each sphere's correction (`work`).
    fn count(&mut self, input: &ForceInput<'_>, planes: &[WallPlane]) {
        let (x, radius, list) = (input.x, input.radius, input.neighbours);
        let n = x.len();
        let reach_factor = 1.0 + self.settings.reach;
        self.wall_distance.resize(planes.len(), Vec::new());
        for (plane, distances) in planes.iter().zip(&mut self.wall_distance) {
            distances.clear();
            distances.extend((0..n).map(|i| {
                let distance = plane.distance(&x[i]);
                if distance <= 0.0 || distance >= reach_factor * radius[i] {
                    f64::NAN
                } else {
                    distance
                }
            }));
        }
        let chunks = self.cursors.len();
        self.lowest.clear();
        self.lowest
            .extend((0..chunks).map(|c| list.balanced_rows(chunks, c).start));
        self.offsets.clear();
        self.offsets.resize(n + 1, 0);
        self.wall_cursor.clear();
        self.wall_cursor.resize(n, 0);
        self.work.clear();
        self.work.resize(n + 1, 0);
        for i in 0..n {
            let mut slot = self.offsets[i];
            for (counts, &lowest) in self.cursors.iter_mut().zip(&self.lowest) {
                // Below its first row a chunk reaches no sphere (its pairs
                // have j > i): its count there is stale, and never read.
                if i >= lowest {
                    let count = counts[i];
                    counts[i] = slot;
                    slot += count;
                }
            }
            self.wall_cursor[i] = slot;
            let walls = self.wall_distance.iter().filter(|d| !d[i].is_nan()).count();
            self.offsets[i + 1] = slot + walls;
            // A sphere's correction costs about its receiver blocks times
            // its contacts.
            let m = self.offsets[i + 1] - self.offsets[i];
            self.work[i + 1] = self.work[i] + m.div_ceil(4) * m;
        }
    }

    /// Places every pair within reach in its spheres' slots, in parallel
    /// over the list's rows: the pairs in list order, each as its row
    /// sphere's then its neighbour's contact (chunk c's slots of a sphere
    /// follow those of the chunks before it).
    fn place(
        &mut self,
        list: &NeighbourList,
        radius: &[f64],
        history: &[ContactHistory],
        team: &Team,
    ) {
        let total = self.offsets[radius.len()];
        self.points.resize(total, ContactPoint::default());
        self.sides.resize(total, Side::Wall(0));
        self.deltas.resize(total, 0.0);
        let chunks = team.threads();
        let separation = &self.separation;
        let points = SharedSlice::new(&mut self.points);
        let sides = SharedSlice::new(&mut self.sides);
        let cursors = SharedSlice::new(&mut self.cursors);
        team.run(|c| {
            // SAFETY: chunk c alone uses cursors[c]; the slots it hands out
            // are its own (`count`), so no two chunks write one slot.
            let cursor = unsafe { cursors.get(c) };
            for i in list.balanced_rows(chunks, c) {
                for k in list.offsets[i]..list.offsets[i + 1] {
                    let (del, r) = separation[k];
                    if r.is_nan() {
                        continue;
                    }
                    let j = list.neighbours[k] as usize;
                    let pair_points =
                        pair_contact_points(&del, r, radius[i], radius[j], history[k].normal_force);
                    for (side, (sphere, point)) in [i, j].into_iter().zip(pair_points).enumerate() {
                        let slot = cursor[sphere];
                        cursor[sphere] += 1;
                        unsafe {
                            *points.get(slot) = point;
                            *sides.get(slot) = Side::Pair {
                                entry: k as u32,
                                side: side as u8,
                            };
                        }
                    }
                }
            }
        });
    }

    /// Places every wall within reach in its sphere's last slots, the
    /// walls in order.
    fn place_walls(
        &mut self,
        radius: &[f64],
        planes: &[WallPlane],
        wall_history: &[Vec<ContactHistory>],
    ) {
        let walls = planes.iter().zip(&self.wall_distance).zip(wall_history);
        for (w, ((plane, distances), history)) in walls.enumerate() {
            for (i, &distance) in distances.iter().enumerate() {
                if distance.is_nan() {
                    continue;
                }
                let slot = self.wall_cursor[i];
                self.wall_cursor[i] += 1;
                // On the wall's plane: a rigid wall does not give way.
                let point = plane.contact_point(distance);
                self.points[slot] = ContactPoint::new(point, history[i].normal_force, radius[i]);
                self.sides[slot] = Side::Wall(w as u32);
            }
        }
        debug_assert!(
            (0..radius.len()).all(|i| self.wall_cursor[i] == self.offsets[i + 1]),
            "every sphere fills the slots it counted"
        );
    }

    /// The first contact whose corrections reach beyond the closure's
    /// reach, given the largest correction over its radius.
    fn beyond_reach(
        &self,
        list: &NeighbourList,
        radius: &[f64],
        largest: f64,
    ) -> Option<BeyondReach> {
        let reach = self.settings.reach;
        if largest <= reach {
            // Two corrections each within `reach` of their radii add up
            // to within `reach` of the radii's sum.
            return None;
        }
        for i in 0..radius.len() {
            for k in list.offsets[i]..list.offsets[i + 1] {
                let j = list.neighbours[k] as usize;
                let [a, b] = self.pair[k];
                let ratio = (a + b) / (radius[i] + radius[j]);
                if ratio > reach {
                    return Some(BeyondReach {
                        sphere: i,
                        partner: j,
                        wall: false,
                        ratio,
                    });
                }
            }
        }
        let n = radius.len();
        (0..self.wall.len() / n.max(1)).find_map(|w| {
            let deltas = self.wall_corrections(w);
            let i = (0..n).find(|&i| deltas[i] > reach * radius[i])?;
            Some(BeyondReach {
                sphere: i,
                partner: w,
                wall: true,
                ratio: deltas[i] / radius[i],
            })
        })
    }
}

/// What the correction of a run of spheres reads: the closure and every
/// sphere's contacts, placed.
struct CorrectedSpheres<'a> {
    half_space: &'a HalfSpace,
    closure: &'a Closure,
    radius: &'a [f64],
    offsets: &'a [usize],
    points: &'a [ContactPoint],
    sides: &'a [Side],
}

/// Where the correction of a run of spheres goes.
struct CorrectionTarget<'a> {
    kernel: &'a mut SurfaceCorrections,
    /// The run's first contact, and its contacts' corrections.
    first: usize,
    deltas: &'a mut [f64],
    /// Per pair-list entry, the corrections of its two sides, flat.
    pair: &'a SharedSlice<f64>,
    /// Per wall, per sphere, the sphere's correction at the wall.
    wall: &'a SharedSlice<f64>,
    spheres: usize,
}

impl CorrectedSpheres<'_> {
    /// Corrects every contact of `spheres` into `target` and reports the
    /// extremes in sphere order.
    ///
    /// # Safety
    /// No other thread writes the pair sides and wall entries of these
    /// spheres' contacts meanwhile.
    unsafe fn correct(
        &self,
        spheres: std::ops::Range<usize>,
        target: CorrectionTarget<'_>,
    ) -> ClosureReport {
        let mut report = ClosureReport::default();
        for i in spheres {
            let range = self.offsets[i]..self.offsets[i + 1];
            // A sphere with one contact, or none that pressed, has nothing
            // to correct.
            if range.len() < 2 || self.points[range.clone()].iter().all(|p| p.force == 0.0) {
                continue;
            }
            let deltas = &mut target.deltas[range.start - target.first..range.end - target.first];
            report.switched_off += target.kernel.compute(
                self.half_space,
                self.closure,
                self.radius[i],
                &self.points[range.clone()],
                deltas,
            );
            for (side, &delta) in self.sides[range].iter().zip(&*deltas) {
                match *side {
                    Side::Pair { entry, side } => {
                        *target.pair.get(2 * entry as usize + side as usize) = delta;
                    }
                    Side::Wall(w) => *target.wall.get(w as usize * target.spheres + i) = delta,
                }
                // The extremes over every contact: those of spheres with
                // nothing to correct are 0 and change neither.
                let ratio = delta / self.radius[i];
                report.largest = report.largest.max(ratio);
                report.smallest = report.smallest.min(ratio);
                if ratio <= -1.0 && report.collapsed.is_none() {
                    report.collapsed = Some((i, ratio));
                }
            }
        }
        report
    }
}
