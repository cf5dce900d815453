//! Velocity-Verlet integration, translational (LAMMPS `fix nve`) and for
//! solid spheres with rotation (LAMMPS `fix nve/sphere`).
//!
//! The arithmetic follows LAMMPS's order term by term (`dtfm = dtf / m`,
//! `v += dtfm f`), so both engines round alike.

use super::particles::{Particles, SPHERE_INERTIA};
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
        let dtf = 0.5 * dt;
        let (f, mass) = (&p.f, &p.mass);
        team.run_split(&mut p.v, |_, range, v| {
            let (f, mass) = (&f[range.clone()], &mass[range]);
            let mut kick = KickFactor::new(dtf);
            for ((v, f), &m) in v.iter_mut().zip(f).zip(mass) {
                let dtfm = kick.over(m);
                for d in 0..3 {
                    v[d] += dtfm * f[d];
                }
            }
        });
        if *self == Integrator::Rotational {
            kick_rotation(p, dtf);
        }
    }
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
