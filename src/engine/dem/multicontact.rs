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
use super::super::simbox::MinimumImage;
use super::wall::ActiveGranularWall;
use crate::kernels::{
    pair_contact_points, Closure, ContactHistory, ContactPoint, GranularMaterial, HalfSpace,
    MprSwitch, MprTest, SurfaceCorrections, WallPlane,
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
    /// Each sphere's next free slot while the contacts are placed.
    cursor: Vec<usize>,
    deltas: Vec<f64>,
    lanes: SurfaceCorrections,
    /// Per pair-list entry, the corrections of its two sides.
    pair: Vec<[f64; 2]>,
    /// Per wall, per sphere, the sphere's correction at the wall.
    wall: Vec<Vec<f64>>,
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
            cursor: Vec::new(),
            deltas: Vec::new(),
            lanes: SurfaceCorrections::default(),
            pair: Vec::new(),
            wall: Vec::new(),
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
        &self.wall[w]
    }

    /// What the last pass found.
    pub fn report(&self) -> &ClosureReport {
        &self.report
    }

    /// Computes every correction for the state in `input` from the normal
    /// forces stored in the pair and wall histories.
    pub fn update(
        &mut self,
        sep: &MinimumImage,
        input: &ForceInput<'_>,
        pair_history: &[ContactHistory],
        walls: &[ActiveGranularWall],
        wall_history: &[Vec<ContactHistory>],
    ) {
        let (x, radius) = (input.x, input.radius);
        let n = x.len();
        let reach_factor = 1.0 + self.settings.reach;
        let mut planes = std::mem::take(&mut self.planes);
        planes.clear();
        planes.extend(walls.iter().map(|w| w.plane(input.elapsed)));
        self.count(sep, input.neighbours, x, radius, &planes, reach_factor);
        self.place(
            input.neighbours,
            radius,
            pair_history,
            &planes,
            wall_history,
        );
        self.planes = planes;
        self.pair.clear();
        self.pair
            .resize(input.neighbours.neighbours.len(), [0.0; 2]);
        self.wall.resize(walls.len(), Vec::new());
        for w in &mut self.wall {
            w.clear();
            w.resize(n, 0.0);
        }
        let mut report = ClosureReport::default();
        for i in 0..n {
            let range = self.offsets[i]..self.offsets[i + 1];
            // A sphere with one contact, or none that pressed, has nothing
            // to correct.
            if range.len() < 2 || self.points[range.clone()].iter().all(|p| p.force == 0.0) {
                continue;
            }
            report.switched_off += self.lanes.compute(
                &self.half_space,
                &self.closure,
                radius[i],
                &self.points[range.clone()],
                &mut self.deltas[range.clone()],
            );
            for (side, &delta) in self.sides[range.clone()].iter().zip(&self.deltas[range]) {
                match *side {
                    Side::Pair { entry, side } => self.pair[entry as usize][side as usize] = delta,
                    Side::Wall(w) => self.wall[w as usize][i] = delta,
                }
                // The extremes over every contact: those of spheres with
                // nothing to correct are 0 and change neither.
                let ratio = delta / radius[i];
                report.largest = report.largest.max(ratio);
                report.smallest = report.smallest.min(ratio);
                if ratio <= -1.0 && report.collapsed.is_none() {
                    report.collapsed = Some((i, ratio));
                }
            }
        }
        report.beyond_reach = self.beyond_reach(input.neighbours, radius, report.largest);
        self.report = report;
    }

    /// Measures every listed pair and each sphere's distance from every
    /// wall, and counts each sphere's contacts within reach into
    /// `offsets`.
    fn count(
        &mut self,
        sep: &MinimumImage,
        list: &NeighbourList,
        x: &[[f64; 3]],
        radius: &[f64],
        planes: &[WallPlane],
        reach_factor: f64,
    ) {
        let n = x.len();
        self.offsets.clear();
        self.offsets.resize(n + 1, 0);
        self.separation.clear();
        self.separation
            .resize(list.neighbours.len(), ([0.0; 3], f64::NAN));
        for i in 0..n {
            for k in list.offsets[i]..list.offsets[i + 1] {
                let j = list.neighbours[k] as usize;
                let (del, _) = sep.delta_image(&x[i], &x[j]);
                let r = (del[0] * del[0] + del[1] * del[1] + del[2] * del[2]).sqrt();
                if r < reach_factor * (radius[i] + radius[j]) {
                    self.separation[k] = (del, r);
                    self.offsets[i + 1] += 1;
                    self.offsets[j + 1] += 1;
                }
            }
        }
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
            for (i, d) in distances.iter().enumerate() {
                self.offsets[i + 1] += usize::from(!d.is_nan());
            }
        }
        for i in 0..n {
            self.offsets[i + 1] += self.offsets[i];
        }
    }

    /// Places every contact within reach in its sphere's slots: the pairs
    /// in list order, each as its row sphere's then its neighbour's
    /// contact, then the walls in order. Each sphere's contacts keep that
    /// order.
    fn place(
        &mut self,
        list: &NeighbourList,
        radius: &[f64],
        history: &[ContactHistory],
        planes: &[WallPlane],
        wall_history: &[Vec<ContactHistory>],
    ) {
        let total = self.offsets[radius.len()];
        self.points.resize(total, ContactPoint::default());
        self.sides.resize(total, Side::Wall(0));
        self.deltas.resize(total, 0.0);
        self.cursor.clear();
        self.cursor.extend_from_slice(&self.offsets[..radius.len()]);
        for i in 0..radius.len() {
            for k in list.offsets[i]..list.offsets[i + 1] {
                let (del, r) = self.separation[k];
                if r.is_nan() {
                    continue;
                }
                let j = list.neighbours[k] as usize;
                let points =
                    pair_contact_points(&del, r, radius[i], radius[j], history[k].normal_force);
                for (side, (sphere, point)) in [i, j].into_iter().zip(points).enumerate() {
                    let slot = self.cursor[sphere];
                    self.cursor[sphere] += 1;
                    self.points[slot] = point;
                    self.sides[slot] = Side::Pair {
                        entry: k as u32,
                        side: side as u8,
                    };
                }
            }
        }
        let walls = planes.iter().zip(&self.wall_distance).zip(wall_history);
        for (w, ((plane, distances), history)) in walls.enumerate() {
            for (i, &distance) in distances.iter().enumerate() {
                if distance.is_nan() {
                    continue;
                }
                let slot = self.cursor[i];
                self.cursor[i] += 1;
                // On the wall's plane: a rigid wall does not give way.
                let point = plane.contact_point(distance);
                self.points[slot] = ContactPoint::new(point, history[i].normal_force, radius[i]);
                self.sides[slot] = Side::Wall(w as u32);
            }
        }
        debug_assert!(
            (0..radius.len()).all(|i| self.cursor[i] == self.offsets[i + 1]),
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
        self.wall.iter().enumerate().find_map(|(w, deltas)| {
            let i = (0..deltas.len()).find(|&i| deltas[i] > reach * radius[i])?;
            Some(BeyondReach {
                sphere: i,
                partner: w,
                wall: true,
                ratio: deltas[i] / radius[i],
            })
        })
    }
}
