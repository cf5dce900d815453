//! Velocity-Verlet integration, translational (LAMMPS `fix nve`) and for
//! solid spheres with rotation (LAMMPS `fix nve/sphere`).
//!
//! The arithmetic follows LAMMPS's order term by term (`dtfm = dtf / m`,
//! `v += dtfm f`), so both engines round alike.

use super::particles::{Particles, SPHERE_INERTIA};
use super::simbox::AffineRemap;
use super::team::Team;

/// Which degrees of freedom are integrated.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Integrator {
    /// Positions and velocities.
    Translational,
    /// Positions, velocities and angular velocities of solid spheres
    /// (`I = 0.4 m r^2`); orientations are not tracked.
    Rotational,
}

impl Integrator {
    /// The integrator for `particles`: rotational when they carry angular
    /// velocities.
    pub fn for_particles(particles: &Particles) -> Self {
        if particles.rotation.is_some() {
            Integrator::Rotational
        } else {
            Integrator::Translational
        }
    }

    /// First half step: half kick and drift (and half kick of the angular
    /// velocity).
    pub fn initial(&self, p: &mut Particles, dt: f64, team: &Team) {
        let dtf = 0.5 * dt;
        let (f, mass) = (&p.f, &p.mass);
        team.run_split2(&mut p.x, &mut p.v, |range, x, v| {
            let (f, mass) = (&f[range.clone()], &mass[range]);
            let mut kick = KickFactor::new(dtf);
            for (((x, v), f), &m) in x.iter_mut().zip(v.iter_mut()).zip(f).zip(mass) {
                let dtfm = kick.over(m);
                for d in 0..3 {
                    v[d] += dtfm * f[d];
                    x[d] += dt * v[d];
                }
            }
        });
        if *self == Integrator::Rotational {
            kick_rotation(p, dtf);
        }
    }

    /// Second half step: half kick (and half kick of the angular velocity).
    pub fn final_half(&self, p: &mut Particles, dt: f64, team: &Team) {
        self.final_half_and(p, dt, team, AfterKick::default());
    }

    /// [`Integrator::final_half`], with what the step does next to each
    /// particle done in the same pass (`after`): the affine remap of a
    /// deformed box and the barostat's `sum m v^2`. A step then reads and
    /// writes each particle once after its forces instead of two or three
    /// times, and on several threads the passes that each pay for the
    /// particles the other threads' force passes read. Returns `sum m v^2`
    /// of the kicked velocities if asked for: the same sum, bit for bit,
    /// as a [`Team::map_reduce`] over them (each chunk's in particle
    /// order, the chunks' in chunk order).
    pub fn final_half_and(
        &self,
        p: &mut Particles,
        dt: f64,
        team: &Team,
        after: AfterKick<'_>,
    ) -> Option<f64> {
        let dtf = 0.5 * dt;
        let (f, mass) = (&p.f, &p.mass);
        let kick = |v: &mut [f64; 3], f: &[f64; 3], dtfm: f64| {
            for d in 0..3 {
                v[d] += dtfm * f[d];
            }
        };
        let sum_mv2 = match after {
            AfterKick {
                remap: None,
                kinetic_sum: false,
            } => {
                team.run_split(&mut p.v, |_, range, v| {
                    let (f, mass) = (&f[range.clone()], &mass[range]);
                    let mut factor = KickFactor::new(dtf);
                    for ((v, f), &m) in v.iter_mut().zip(f).zip(mass) {
                        kick(v, f, factor.over(m));
                    }
                });
                None
            }
            AfterKick { remap, kinetic_sum } => {
                let sum = team.reduce_split2(
                    &mut p.x,
                    &mut p.v,
                    0.0,
                    |range, x, v| {
                        let (f, mass) = (&f[range.clone()], &mass[range]);
                        let mut factor = KickFactor::new(dtf);
                        let mut sum = 0.0;
                        for (((x, v), f), &m) in x.iter_mut().zip(v.iter_mut()).zip(f).zip(mass) {
                            kick(v, f, factor.over(m));
                            if let Some(remap) = remap {
                                remap.apply(x);
                            }
                            if kinetic_sum {
                                sum += (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]) * m;
                            }
                        }
                        sum
                    },
                    |a, b| a + b,
                );
                kinetic_sum.then_some(sum)
            }
        };
        if *self == Integrator::Rotational {
            kick_rotation(p, dtf);
        }
        sum_mv2
    }
}

/// What the second half step's pass does to each particle after its kick
/// ([`Integrator::final_half_and`]).
#[derive(Clone, Copy, Debug, Default)]
pub struct AfterKick<'a> {
    /// Map the position affinely into a deformed box.
    pub remap: Option<&'a AffineRemap>,
    /// Sum `m v^2` over the kicked velocities (a barostat's pressure).
    pub kinetic_sum: bool,
}

/// `dtf / m`, divided again only when the mass differs from the last
/// one's: a division costs more than the rest of a particle's kick, and the
/// grains of a bonded packing all have one mass. The quotient is the same
/// bit for bit as dividing every time.
struct KickFactor {
    dtf: f64,
    mass: f64,
    factor: f64,
}

impl KickFactor {
    fn new(dtf: f64) -> Self {
        Self {
            dtf,
            mass: f64::NAN,
            factor: f64::NAN,
        }
    }

    #[inline(always)]
    fn over(&mut self, m: f64) -> f64 {
        // Bits, not values: -0.0 and 0.0 would compare equal.
        if m.to_bits() != self.mass.to_bits() {
            self.mass = m;
            self.factor = self.dtf / m;
        }
        self.factor
    }
}

fn kick_rotation(p: &mut Particles, dtf: f64) {
    let Some(rot) = &mut p.rotation else {
        return;
    };
    let dtfrotate = dtf / SPHERE_INERTIA;
    for (((w, t), &m), &r) in rot
        .omega
        .iter_mut()
        .zip(&rot.torque)
        .zip(&p.mass)
        .zip(&p.radius)
    {
        let dtirotate = dtfrotate / (r * r * m);
        for d in 0..3 {
            w[d] += dtirotate * t[d];
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn constant_force_gives_uniform_acceleration() {
        let mut p = Particles::at_rest(vec![[0.0; 3]]);
        p.mass[0] = 2.0;
        p.f[0] = [1.0, 0.0, -4.0];
        let dt = 0.1;
        let team = Team::new(2);
        for _ in 0..10 {
            Integrator::Translational.initial(&mut p, dt, &team);
            Integrator::Translational.final_half(&mut p, dt, &team);
        }
        // a = f / m; after t = 1: v = a t, x = a t^2 / 2 (exact for
        // velocity Verlet under a constant force).
        assert!((p.v[0][0] - 0.5).abs() < 1e-14 && (p.v[0][2] + 2.0).abs() < 1e-14);
        assert!((p.x[0][0] - 0.25).abs() < 1e-14 && (p.x[0][2] + 1.0).abs() < 1e-14);
    }

    /// The kick's pass with the box's remap and the kinetic sum in it
    /// gives what the three passes give apart, bit for bit, on one and
    /// three threads (the chunks of the sum as `map_reduce`'s).
    #[test]
    fn the_fused_second_half_step_equals_its_passes_apart() {
        use crate::engine::simbox::SimBox;
        use rand::{Rng, SeedableRng};
        let mut rng = rand::rngs::StdRng::seed_from_u64(7);
        let mut row =
            |s: f64| -> [f64; 3] { std::array::from_fn(|_| s * rng.gen_range(-1.0..1.0)) };
        let n = 1001;
        let mut p = Particles::at_rest((0..n).map(|_| row(5.0)).collect());
        p.v = (0..n).map(|_| row(0.1)).collect();
        p.f = (0..n).map(|_| row(2.0)).collect();
        // Two masses, so the kick's factor changes along the array.
        p.mass = (0..n).map(|i| if i % 7 < 3 { 1.0 } else { 1.3 }).collect();
        let from = SimBox {
            lo: [-5.0; 3],
            lengths: [10.0, 10.5, 11.0],
            tilt: [0.0; 3],
            periodic: [true; 3],
        };
        let to = SimBox {
            lengths: [9.99, 10.49, 10.98],
            tilt: [0.01, 0.0, -0.02],
            ..from
        };
        let remap = from.remap_to(&to);
        for threads in [1, 3] {
            let team = Team::new(threads);
            let mut apart = p.clone();
            Integrator::Translational.final_half(&mut apart, 0.1, &team);
            apart.x.iter_mut().for_each(|x| remap.apply(x));
            let sum = team.map_reduce(
                n,
                0.0,
                |range| {
                    apart.v[range.clone()]
                        .iter()
                        .zip(&apart.mass[range])
                        .map(|(v, &m)| (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]) * m)
                        .sum::<f64>()
                },
                |a, b| a + b,
            );
            let mut fused = p.clone();
            let after = AfterKick {
                remap: Some(&remap),
                kinetic_sum: true,
            };
            let fused_sum = Integrator::Translational.final_half_and(&mut fused, 0.1, &team, after);
            assert_eq!(fused_sum.map(f64::to_bits), Some(sum.to_bits()));
            assert_eq!(fused.x, apart.x);
            assert_eq!(fused.v, apart.v);
            assert!(fused.x != p.x && fused.v != p.v);
            // Each part alone.
            let mut kicked = p.clone();
            let only_sum = AfterKick {
                remap: None,
                kinetic_sum: true,
            };
            let kicked_sum =
                Integrator::Translational.final_half_and(&mut kicked, 0.1, &team, only_sum);
            assert_eq!(kicked_sum, Some(sum));
            assert_eq!((kicked.x, kicked.v), (p.x.clone(), apart.v.clone()));
        }
    }

    #[test]
    fn constant_torque_spins_a_sphere_up_at_torque_over_inertia() {
        let mut p = Particles::at_rest(vec![[0.0; 3]; 2]);
        p.enable_rotation();
        p.mass = vec![1.0, 3.0];
        p.radius = vec![0.5, 2.0];
        p.rotation.as_mut().unwrap().torque = vec![[0.0, 0.0, 0.2], [1.0, 0.0, 0.0]];
        let integrator = Integrator::for_particles(&p);
        assert_eq!(integrator, Integrator::Rotational);
        let dt = 0.05;
        let team = Team::new(1);
        for _ in 0..40 {
            integrator.initial(&mut p, dt, &team);
            integrator.final_half(&mut p, dt, &team);
        }
        let omega = &p.rotation.as_ref().unwrap().omega;
        // omega = T t / (0.4 m r^2) after t = 2.
        let expect0 = 0.2 * 2.0 / (0.4 * 1.0 * 0.25);
        let expect1 = 1.0 * 2.0 / (0.4 * 3.0 * 4.0);
        assert!((omega[0][2] - expect0).abs() < 1e-12, "{}", omega[0][2]);
        assert!((omega[1][0] - expect1).abs() < 1e-12, "{}", omega[1][0]);
        assert_eq!(p.x[0], [0.0; 3], "a torque does not move the centre");
        // Work-energy: rotational energy equals T . omega t / 2 for a
        // constant torque from rest.
        let work = 0.5 * (0.2 * omega[0][2] + 1.0 * omega[1][0]) * 2.0;
        assert!((p.rotational_energy() - work).abs() < 1e-12);
    }
}
