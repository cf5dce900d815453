//! Per-particle state, structure of arrays.

use super::deform::LeesEdwards;
use super::simbox::SimBox;

/// Moment-of-inertia factor of a solid sphere, `I = 0.4 m r^2` (as LAMMPS's
/// `fix nve/sphere`).
pub const SPHERE_INERTIA: f64 = 0.4;

/// A particle's radius (d) when a scene gives none: half the unit diameter.
pub const DEFAULT_RADIUS: f64 = 0.5;

/// Positions, velocities, forces and per-particle properties.
#[derive(Clone, Debug, Default, serde::Serialize, serde::Deserialize)]
pub struct Particles {
    /// Positions (d), wrapped into the box along periodic dimensions at
    /// every pair-list build.
    pub x: Vec<[f64; 3]>,
    /// Velocities (d / tau).
    pub v: Vec<[f64; 3]>,
    /// Forces of the last evaluation (k d).
    pub f: Vec<[f64; 3]>,
    /// Periodic image counters: the unwrapped position is
    /// `x + simbox.image_vector(image)`.
    pub image: Vec<[i32; 3]>,
    /// Grain (molecule) id.
    pub grain: Vec<u32>,
    /// Particle type, from 1 (as LAMMPS's atom types).
    pub kind: Vec<u32>,
    /// Mass (m).
    pub mass: Vec<f64>,
    /// Radius (d); the bonded particle model's contacts use its pair
    /// coefficient `d` instead, DEM spheres use this.
    pub radius: Vec<f64>,
    /// Angular velocity and torque, for models whose particles rotate.
    pub rotation: Option<Rotation>,
}

/// Rotational state of spheres.
#[derive(Clone, Debug, Default, serde::Serialize, serde::Deserialize)]
pub struct Rotation {
    /// Angular velocity (1 / tau).
    pub omega: Vec<[f64; 3]>,
    /// Torque of the last evaluation (k d).
    pub torque: Vec<[f64; 3]>,
}

impl Particles {
    /// `n` particles at `x`, at rest, mass 1, radius [`DEFAULT_RADIUS`],
    /// type 1, grain 0.
    pub fn at_rest(x: Vec<[f64; 3]>) -> Self {
        let n = x.len();
        Self {
            x,
            v: vec![[0.0; 3]; n],
            f: vec![[0.0; 3]; n],
            image: vec![[0; 3]; n],
            grain: vec![0; n],
            kind: vec![1; n],
            mass: vec![1.0; n],
            radius: vec![DEFAULT_RADIUS; n],
            rotation: None,
        }
    }

    /// Number of particles.
    pub fn len(&self) -> usize {
        self.x.len()
    }

    /// Whether there are none.
    pub fn is_empty(&self) -> bool {
        self.x.is_empty()
    }

    /// Gives the particles angular velocities (zero) and torques, if they
    /// have none yet.
    pub fn enable_rotation(&mut self) {
        if self.rotation.is_none() {
            let n = self.len();
            self.rotation = Some(Rotation {
                omega: vec![[0.0; 3]; n],
                torque: vec![[0.0; 3]; n],
            });
        }
    }

    /// Translational kinetic energy `sum m |v|^2 / 2` (LAMMPS `compute ke`).
    pub fn kinetic_energy(&self) -> f64 {
        0.5 * self
            .v
            .iter()
            .zip(&self.mass)
            .map(|(v, m)| (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]) * m)
            .sum::<f64>()
    }

    /// Rotational kinetic energy of solid spheres, `sum I |omega|^2 / 2`
    /// (LAMMPS `compute erotate/sphere`); 0 without rotation.
    pub fn rotational_energy(&self) -> f64 {
        let Some(rot) = &self.rotation else {
            return 0.0;
        };
        0.5 * SPHERE_INERTIA
            * rot
                .omega
                .iter()
                .zip(self.mass.iter().zip(&self.radius))
                .map(|(w, (m, r))| (w[0] * w[0] + w[1] * w[1] + w[2] * w[2]) * m * r * r)
                .sum::<f64>()
    }

    /// Adds the kinetic part of the pressure-tensor numerator,
    /// `sum m v_a v_b` in the order `[xx, yy, zz, xy, xz, yz]`, to `p`.
    pub fn add_kinetic_tensor(&self, p: &mut [f64; 6]) {
        // v - 0 is v exactly: the same sums as without the offset.
        self.add_relative_kinetic_tensor(p, |_| [0.0; 3]);
    }

    /// Wraps every position into the box, updating the image counters.
    /// Under Lees-Edwards boundaries a particle moved to another image
    /// takes that image's velocity: `v - w(k)` for a shift by `h k`.
    pub fn wrap(&mut self, simbox: &SimBox, lees_edwards: Option<&LeesEdwards>) {
        for ((x, n), v) in self
            .x
            .iter_mut()
            .zip(self.image.iter_mut())
            .zip(&mut self.v)
        {
            let k = simbox.wrap(x, n);
            if let (Some(le), true) = (lees_edwards, k != [0; 3]) {
                let w = le.image_velocity(&k.map(f64::from));
                for d in 0..3 {
                    v[d] -= w[d];
                }
            }
        }
    }

    /// [`Particles::add_kinetic_tensor`] with velocities taken relative to
    /// the Lees-Edwards streaming profile of `simbox` (peculiar velocities).
    pub fn add_peculiar_kinetic_tensor(
        &self,
        simbox: &SimBox,
        lees_edwards: &LeesEdwards,
        p: &mut [f64; 6],
    ) {
        self.add_relative_kinetic_tensor(p, |x| lees_edwards.streaming_velocity(simbox, x));
    }

    /// Adds `sum m c_a c_b` with `c = v - u(x)` to `p`.
    fn add_relative_kinetic_tensor(&self, p: &mut [f64; 6], u: impl Fn(&[f64; 3]) -> [f64; 3]) {
        for ((v, x), &m) in self.v.iter().zip(&self.x).zip(&self.mass) {
            let u = u(x);
            let c = [v[0] - u[0], v[1] - u[1], v[2] - u[2]];
            p[0] += m * c[0] * c[0];
            p[1] += m * c[1] * c[1];
            p[2] += m * c[2] * c[2];
            p[3] += m * c[0] * c[1];
            p[4] += m * c[0] * c[2];
            p[5] += m * c[1] * c[2];
        }
    }

    /// Zeroes forces and torques.
    pub fn clear_forces(&mut self) {
        self.f.fill([0.0; 3]);
        if let Some(rot) = &mut self.rotation {
            rot.torque.fill([0.0; 3]);
        }
    }
}
