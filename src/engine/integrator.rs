//! Velocity-Verlet integration, translational (LAMMPS `fix nve`) and for
//! solid spheres with rotation (LAMMPS `fix nve/sphere`).
//!
//! The arithmetic follows LAMMPS's order term by term (`dtfm = dtf / m`,
//! `v += dtfm f`), so both engines round alike.

use super::particles::{mv2, Particles, SPHERE_INERTIA};
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
    /// deformed box and the barostat's `sum m v^2`. Each particle is then
    /// read and written once after its forces instead of two or three
    /// times; on several threads each such pass pays again for the
    /// particles the other threads' force passes have read. Returns
    /// `sum m v^2` of the kicked velocities if asked for: the same sum,
    /// bit for bit, as a [`Team::map_reduce`] of [`mv2`] over them (each
    /// chunk's in particle order, the chunks' in chunk order).
    pub fn final_half_and(
        &self,
        p: &mut Particles,
        dt: f64,
        team: &Team,
        after: AfterKick<'_>,
    ) -> Option<f64> {
        let dtf = 0.5 * dt;
        let (f, mass) = (&p.f, &p.mass);
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
                let (x, v) = (&mut p.x, &mut p.v);
                let mut on_team = |pass: &Chunk| {
                    team.reduce_split2(
                        x,
                        v,
                        0.0,
                        |range, x, v| pass(x, v, &f[range.clone()], &mass[range]),
                        |a, b| a + b,
                    )
                };
                // One loop per case, so that no particle tests the case.
                let sum = match (remap, kinetic_sum) {
                    (Some(r), true) => {
                        on_team(&|x, v, f, m| kick_then::<true>(x, v, f, m, dtf, |x| r.apply(x)))
                    }
                    (Some(r), false) => {
                        on_team(&|x, v, f, m| kick_then::<false>(x, v, f, m, dtf, |x| r.apply(x)))
                    }
                    (None, _) => on_team(&|x, v, f, m| kick_then::<true>(x, v, f, m, dtf, |_| {})),
                };
                kinetic_sum.then_some(sum)
            }
        };
        if *self == Integrator::Rotational {
            kick_rotation(p, dtf);
        }
        sum_mv2
    }
}

/// `v += dtfm f`, LAMMPS's order.
#[inline(always)]
fn kick(v: &mut [f64; 3], f: &[f64; 3], dtfm: f64) {
    for d in 0..3 {
        v[d] += dtfm * f[d];
    }
}

/// A chunk's part of [`Integrator::final_half_and`] on its positions,
/// velocities, forces and masses; its sum of [`mv2`].
type Chunk<'a> = dyn Fn(&mut [[f64; 3]], &mut [[f64; 3]], &[[f64; 3]], &[f64]) -> f64 + Sync + 'a;

/// One chunk of [`Integrator::final_half_and`]: the kick, then `place` on
/// the position, and the sum of [`mv2`] (`SUM`, else 0).
fn kick_then<const SUM: bool>(
    x: &mut [[f64; 3]],
    v: &mut [[f64; 3]],
    f: &[[f64; 3]],
    mass: &[f64],
    dtf: f64,
    place: impl Fn(&mut [f64; 3]),
) -> f64 {
    let mut factor = KickFactor::new(dtf);
    let mut sum = 0.0;
    for (((x, v), f), &m) in x.iter_mut().zip(v.iter_mut()).zip(f).zip(mass) {
        kick(v, f, factor.over(m));
        place(x);
        if SUM {
            sum += mv2(v, m);
        }
    }
    sum
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

    /// The kick's pass with the box's remap and the kinetic sum in it, in
    /// each combination, gives what the passes give apart, bit for bit:
    /// both integrators, on one and three threads (the chunks of the sum
    /// as `map_reduce`'s), with more particles than threads and fewer.
    #[test]
    fn the_fused_second_half_step_equals_its_passes_apart() {
        use crate::engine::simbox::SimBox;
        use rand::{Rng, SeedableRng};
        let bits = |rows: &[[f64; 3]]| -> Vec<[u64; 3]> {
            rows.iter().map(|r| r.map(f64::to_bits)).collect()
        };
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
        for n in [2, 1001] {
            let mut rng = rand::rngs::StdRng::seed_from_u64(7);
            let mut rows = |s: f64| -> Vec<[f64; 3]> {
                (0..n)
                    .map(|_| std::array::from_fn(|_| s * rng.gen_range(-1.0..1.0)))
                    .collect()
            };
            let mut p = Particles::at_rest(rows(5.0));
            p.v = rows(0.1);
            p.f = rows(2.0);
            // Two masses, so the kick's factor changes along the array.
            p.mass = (0..n).map(|i| if i % 7 < 3 { 1.0 } else { 1.3 }).collect();
            let mut spinning = p.clone();
            spinning.enable_rotation();
            let rotation = spinning.rotation.as_mut().unwrap();
            rotation.omega = rows(0.2);
            rotation.torque = rows(0.5);
            for p in [p, spinning] {
                let integrator = Integrator::for_particles(&p);
                for threads in [1, 3] {
                    let team = Team::new(threads);
                    let mut kicked = p.clone();
                    integrator.final_half(&mut kicked, 0.1, &team);
                    let sum = team.map_reduce(
                        n,
                        0.0,
                        |range| {
                            kicked.v[range.clone()]
                                .iter()
                                .zip(&kicked.mass[range])
                                .map(|(v, &m)| mv2(v, m))
                                .sum::<f64>()
                        },
                        |a, b| a + b,
                    );
                    let mut remapped = kicked.x.clone();
                    remapped.iter_mut().for_each(|x| remap.apply(x));
                    assert!(bits(&kicked.v) != bits(&p.v) && bits(&remapped) != bits(&p.x));
                    for (with_remap, kinetic_sum) in [(true, true), (true, false), (false, true)] {
                        let after = AfterKick {
                            remap: with_remap.then_some(&remap),
                            kinetic_sum,
                        };
                        let mut fused = p.clone();
                        let fused_sum = integrator.final_half_and(&mut fused, 0.1, &team, after);
                        let case =
                            format!("{n} particles, {integrator:?}, {threads} threads, {after:?}");
                        assert_eq!(
                            fused_sum.map(f64::to_bits),
                            kinetic_sum.then_some(sum.to_bits()),
                            "{case}"
                        );
                        let x = if with_remap { &remapped } else { &p.x };
                        assert_eq!(bits(&fused.x), bits(x), "{case}");
                        assert_eq!(bits(&fused.v), bits(&kicked.v), "{case}");
                        let omega = |p: &Particles| p.rotation.as_ref().map(|r| bits(&r.omega));
                        assert_eq!(omega(&fused), omega(&kicked), "{case}");
                    }
                }
            }
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
