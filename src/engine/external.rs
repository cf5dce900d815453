//! Forces from outside the particle models: flat and spherical harmonic
//! walls, flat granular walls, a centre-of-mass tether, viscous damping and
//! gravity. [`ExternalTerms`] holds one stage's terms; either particle
//! model runs under them. All but the granular walls act here, after the
//! model's forces; granular walls touch spheres through the model's own
//! contact law, so the model applies them (`ParticleModel::begin_stage`).

use super::particles::Particles;
use super::simbox::SimBox;
use crate::kernels::GranularMaterial;
use serde::{Deserialize, Serialize};

/// One stage's forces from outside the particle model.
#[derive(Debug, Default)]
pub struct ExternalTerms {
    /// Flat harmonic walls.
    pub walls: Vec<FlatWall>,
    /// A spherical harmonic wall.
    pub sphere_wall: Option<SphereWall>,
    /// Flat granular walls: the model applies them with its contact law.
    pub granular_walls: Vec<GranularWall>,
    /// A centre-of-mass tether, resolved against the particles.
    pub tether: Option<ActiveTether>,
    /// Viscous damping coefficient (m / tau), 0 for none.
    pub viscous: f64,
    /// A uniform acceleration on every particle (d / tau^2).
    pub gravity: Option<Gravity>,
}

/// What the external terms did in one force evaluation.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ExternalReport {
    /// Normal force on each flat wall (k d units, >= 0).
    pub wall_forces: Vec<f64>,
    /// Position of each flat wall.
    pub wall_positions: Vec<f64>,
    /// `(wall, particle)`: the first particle found on or behind the plane
    /// of a flat wall.
    pub through_wall: Option<(usize, usize)>,
    /// Summed force magnitude on the spherical wall.
    pub sphere_wall_force: f64,
    /// Energy of walls, tether and gravity.
    pub energy: f64,
}

impl ExternalTerms {
    /// Adds the forces of every term but the granular walls to
    /// `particles.f`, at `elapsed` time into the stage, in a fixed order:
    /// flat walls, the spherical wall, the tether, viscous damping,
    /// gravity.
    pub fn apply(
        &self,
        elapsed: f64,
        simbox: &SimBox,
        particles: &mut Particles,
    ) -> ExternalReport {
        let p = particles;
        let mut report = ExternalReport::default();
        for (w, wall) in self.walls.iter().enumerate() {
            let contact = wall.apply(elapsed, &p.x, &mut p.f);
            report.wall_forces.push(contact.force);
            report.wall_positions.push(wall.position_at(elapsed));
            report.energy += contact.energy;
            if let (Some(particle), None) = (contact.through, report.through_wall) {
                report.through_wall = Some((w, particle));
            }
        }
        if let Some(sphere) = &self.sphere_wall {
            let (force, energy) = sphere.apply(elapsed, &p.x, &mut p.f);
            report.sphere_wall_force = force;
            report.energy += energy;
        }
        if let Some(tether) = &self.tether {
            report.energy += tether.apply(simbox, &p.x, &p.image, &mut p.f);
        }
        if self.viscous != 0.0 {
            apply_viscous(self.viscous, &p.v, &mut p.f);
        }
        if let Some(gravity) = &self.gravity {
            report.energy += gravity.apply(&p.x, &p.mass, &mut p.f);
        }
        report
    }
}

/// A uniform acceleration `g` on every particle: force `m g`, potential
/// energy `-m g . x` (LAMMPS `fix gravity`, whose energy also takes the
/// stored positions, wrapped into a periodic box at neighbour rebuilds:
/// along a periodic dimension the energy jumps when a particle is
/// wrapped, and only its changes between rebuilds mean anything).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Gravity {
    /// The acceleration (d / tau^2).
    pub acceleration: [f64; 3],
}

impl Gravity {
    /// The acceleration `g`, formed as LAMMPS's `fix gravity` forms it from
    /// a magnitude `|g|` and a direction `g`: `|g| (g_d / |g|)`, which
    /// equals `g_d` up to round-off, so both engines add the same forces
    /// bit for bit.
    pub fn new(g: [f64; 3]) -> Self {
        let magnitude = (g[0] * g[0] + g[1] * g[1] + g[2] * g[2]).sqrt();
        let acceleration = if magnitude > 0.0 {
            g.map(|c| magnitude * (c / magnitude))
        } else {
            [0.0; 3]
        };
        Self { acceleration }
    }

    /// Adds `m g` to every particle's force; returns the energy.
    pub fn apply(&self, x: &[[f64; 3]], mass: &[f64], f: &mut [[f64; 3]]) -> f64 {
        let g = self.acceleration;
        let mut energy = 0.0;
        for ((xi, &m), fi) in x.iter().zip(mass).zip(f.iter_mut()) {
            for d in 0..3 {
                fi[d] += m * g[d];
            }
            energy -= m * (g[0] * xi[0] + g[1] * xi[1] + g[2] * xi[2]);
        }
        energy
    }
}

/// A flat wall of a granular material: Hertz-Mindlin contacts with the
/// spheres, with damping, sliding (and optionally rolling and twisting)
/// friction. A scene's `stages[i].granular_walls`. The particle model
/// applies it with its contact law (DEM spheres only).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GranularWall {
    /// Axis normal to the wall: 0, 1 or 2.
    pub axis: usize,
    /// Which side the spheres are on.
    pub side: WallSide,
    /// Position along the axis at the start of the stage (d units).
    pub position: f64,
    /// Speed along the axis (d / tau); negative moves towards -axis.
    #[serde(default)]
    pub velocity: f64,
    /// The wall's material and the contact's friction: its Young's
    /// modulus and Poisson's ratio mix with the spheres' by Hertz's and
    /// Mindlin's rules (a modulus far above the spheres' makes it rigid);
    /// restitution, damping and friction are those of the sphere-wall
    /// contact.
    pub material: GranularMaterial,
    /// Whether its contacts keep their friction springs from the
    /// previous stage, when the wall at the same place in that stage's
    /// list is on the same axis and side (LIGGGHTS and LAMMPS keep a wall
    /// fix's histories across `run` commands). Otherwise the springs
    /// restart with the stage, and only the loads are kept, for the
    /// multi-contact closure.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub keep_history: bool,
}

impl GranularWall {
    /// Wall position after `elapsed` time.
    pub fn position_at(&self, elapsed: f64) -> f64 {
        self.position + self.velocity * elapsed
    }

    /// +1 when the spheres are on the +axis side (a `lo` wall), else -1.
    pub fn sign(&self) -> f64 {
        match self.side {
            WallSide::Lo => 1.0,
            WallSide::Hi => -1.0,
        }
    }
}

/// Which side of a flat wall the particles are on.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum WallSide {
    /// Particles above the wall (wall pushes towards +axis).
    Lo,
    /// Particles below the wall (wall pushes towards -axis).
    Hi,
}

/// A flat harmonic wall normal to one axis, moving at constant speed.
///
/// A particle at distance `s < cutoff` from the wall feels
/// `k (cutoff - s)` away from it (LAMMPS `fix wall/harmonic` with
/// `epsilon = k / 2`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FlatWall {
    /// Axis normal to the wall: 0, 1 or 2.
    pub axis: usize,
    /// Which side the particles are on.
    pub side: WallSide,
    /// Position along the axis at the start of the stage (d units).
    pub position: f64,
    /// Speed along the axis (d / tau); negative moves towards -axis.
    #[serde(default)]
    pub velocity: f64,
    /// Stiffness `k` (k units).
    pub stiffness: f64,
    /// Range of the wall force (d units).
    pub cutoff: f64,
}

impl FlatWall {
    /// Wall position after `elapsed` time.
    pub fn position_at(&self, elapsed: f64) -> f64 {
        self.position + self.velocity * elapsed
    }

    /// Adds wall forces; returns the normal force on the wall, the energy,
    /// and the first particle found on or behind the wall's plane.
    ///
    /// A particle there has got through the wall: like LAMMPS's
    /// `fix wall/harmonic`, the engine stops rather than push it on from
    /// the wrong side. (The wall holds a particle off its plane with at
    /// most `k cutoff`; a grain squeezed hard enough overcomes that.)
    pub fn apply(&self, elapsed: f64, x: &[[f64; 3]], f: &mut [[f64; 3]]) -> WallContact {
        let wall = self.position_at(elapsed);
        let sign = match self.side {
            WallSide::Lo => 1.0,
            WallSide::Hi => -1.0,
        };
        let mut contact = WallContact::default();
        for (i, (xi, fi)) in x.iter().zip(f.iter_mut()).enumerate() {
            let s = sign * (xi[self.axis] - wall);
            if s < self.cutoff {
                if s <= 0.0 && contact.through.is_none() {
                    contact.through = Some(i);
                }
                let overlap = self.cutoff - s;
                let force = self.stiffness * overlap;
                fi[self.axis] += sign * force;
                contact.force += force;
                contact.energy += 0.5 * self.stiffness * overlap * overlap;
            }
        }
        contact
    }
}

/// What a flat wall did in one force evaluation.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct WallContact {
    /// Normal force on the wall (k d, >= 0).
    pub force: f64,
    /// Energy.
    pub energy: f64,
    /// The first particle on or behind the wall's plane, if any.
    pub through: Option<usize>,
}

/// A harmonic spherical wall that confines particles inside a sphere whose
/// radius moves at a constant speed and oscillates with an exponentially
/// decaying amplitude: `R(t) = R0 + v t + A exp(-t / t_decay) sin(2 pi t / T)`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SphereWall {
    /// Centre (d units).
    pub centre: [f64; 3],
    /// Mean radius `R0` at the start of the stage (d units).
    pub radius: f64,
    /// Radial speed `v` (d / tau); negative shrinks the sphere.
    #[serde(default, skip_serializing_if = "is_zero")]
    pub velocity: f64,
    /// Oscillation amplitude `A` (d units); 0 for a fixed sphere.
    #[serde(default)]
    pub amplitude: f64,
    /// Oscillation period `T` (tau).
    #[serde(default = "default_period")]
    pub period: f64,
    /// Decay time of the amplitude (tau).
    #[serde(default = "default_period")]
    pub decay_time: f64,
    /// Stiffness `k` (k units).
    pub stiffness: f64,
    /// Range of the wall force (d units).
    pub cutoff: f64,
}

fn is_zero(v: &f64) -> bool {
    *v == 0.0
}

fn default_period() -> f64 {
    1.0
}

impl SphereWall {
    /// Radius after `elapsed` time.
    pub fn radius_at(&self, elapsed: f64) -> f64 {
        let phase = 2.0 * std::f64::consts::PI * elapsed / self.period;
        self.radius
            + self.velocity * elapsed
            + self.amplitude * (-elapsed / self.decay_time).exp() * phase.sin()
    }

    /// Adds the inward wall force; returns (summed force magnitude, energy).
    pub fn apply(&self, elapsed: f64, x: &[[f64; 3]], f: &mut [[f64; 3]]) -> (f64, f64) {
        let radius = self.radius_at(elapsed);
        let (mut total, mut energy) = (0.0, 0.0);
        for (xi, fi) in x.iter().zip(f.iter_mut()) {
            let d = [
                xi[0] - self.centre[0],
                xi[1] - self.centre[1],
                xi[2] - self.centre[2],
            ];
            let s = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
            let gap = radius - s;
            if gap < self.cutoff && s > 0.0 {
                let overlap = self.cutoff - gap;
                let force = self.stiffness * overlap;
                for k in 0..3 {
                    fi[k] -= force * d[k] / s;
                }
                total += force;
                energy += 0.5 * self.stiffness * overlap * overlap;
            }
        }
        (total, energy)
    }
}

/// A soft spring from a group's centre of mass to an anchor, per selected
/// dimension (LAMMPS `fix spring tether` with `NULL` for unselected ones).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Tether {
    /// Grain id of the group; `None` tethers every particle.
    #[serde(default)]
    pub grain: Option<u32>,
    /// Anchor point; `None` anchors at the centre of mass at stage start.
    #[serde(default)]
    pub anchor: Option<[f64; 3]>,
    /// Dimensions the spring acts in.
    pub dims: [bool; 3],
    /// Spring constant (k units), on the whole group.
    pub stiffness: f64,
}

/// A tether resolved against the particles of one stage.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct ActiveTether {
    members: Vec<usize>,
    anchor: [f64; 3],
    dims: [bool; 3],
    stiffness: f64,
}

impl ActiveTether {
    /// Resolves the group and the anchor (by default the group's current
    /// centre of mass, unwrapped with `image`).
    pub fn new(
        spec: &Tether,
        grain: &[u32],
        simbox: &SimBox,
        x: &[[f64; 3]],
        image: &[[i32; 3]],
    ) -> Self {
        let members: Vec<usize> = (0..grain.len())
            .filter(|&i| spec.grain.is_none_or(|g| grain[i] == g))
            .collect();
        let anchor = spec
            .anchor
            .unwrap_or_else(|| centre_of(&members, simbox, x, image));
        Self {
            members,
            anchor,
            dims: spec.dims,
            stiffness: spec.stiffness,
        }
    }

    /// Adds the tether force (uniform masses: shared equally); returns energy.
    /// Positions are unwrapped with `image` so a group may straddle the box.
    pub fn apply(
        &self,
        simbox: &SimBox,
        x: &[[f64; 3]],
        image: &[[i32; 3]],
        f: &mut [[f64; 3]],
    ) -> f64 {
        if self.members.is_empty() {
            return 0.0;
        }
        let com = centre_of(&self.members, simbox, x, image);
        let share = 1.0 / self.members.len() as f64;
        let mut energy = 0.0;
        for d in 0..3 {
            if !self.dims[d] {
                continue;
            }
            let stretch = com[d] - self.anchor[d];
            energy += 0.5 * self.stiffness * stretch * stretch;
            let per_atom = -self.stiffness * stretch * share;
            for &i in &self.members {
                f[i][d] += per_atom;
            }
        }
        energy
    }
}

/// Centre of the `members` (uniform masses) in unwrapped coordinates, so a
/// group that straddles the box is not torn apart.
fn centre_of(members: &[usize], simbox: &SimBox, x: &[[f64; 3]], image: &[[i32; 3]]) -> [f64; 3] {
    let mut c = [0.0; 3];
    for &i in members {
        let w = simbox.image_vector(&image[i]);
        for d in 0..3 {
            c[d] += x[i][d] + w[d];
        }
    }
    let inv = 1.0 / members.len().max(1) as f64;
    c.map(|v| v * inv)
}

/// Adds `-gamma v` to every particle (LAMMPS `fix viscous`).
pub fn apply_viscous(gamma: f64, v: &[[f64; 3]], f: &mut [[f64; 3]]) {
    for (vi, fi) in v.iter().zip(f.iter_mut()) {
        for d in 0..3 {
            fi[d] -= gamma * vi[d];
        }
    }
}
