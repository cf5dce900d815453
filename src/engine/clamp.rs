//! Particles moved at a constant velocity, as LAMMPS's `fix move linear`:
//! a clamp takes its particles' positions `x0` when it is made and places
//! them at `x0 + v t` at every step of the stage it drives (`t` counted
//! from the stage's start), with velocity `v`, whatever the forces on
//! them. The force the rest of the sample exerts on a clamp is what a
//! tensile or compressive test reads. A clamp belongs to one stage: made
//! at that stage's start, from the positions it starts from.

use super::particles::Particles;
use thiserror::Error;

/// A group of particles moved rigidly at a constant velocity.
#[derive(Clone, Debug, PartialEq)]
pub struct Clamp {
    particles: Vec<usize>,
    velocity: [f64; 3],
    origins: Vec<[f64; 3]>,
}

/// A clamp the engine cannot hold.
#[derive(Clone, Debug, PartialEq, Error)]
pub enum ClampError {
    /// A particle index past the last particle.
    #[error("clamp particle {index} is out of range: the system has {particles} particles")]
    OutOfRange {
        /// The index.
        index: usize,
        /// Particles in the system.
        particles: usize,
    },
    /// A particle listed twice, in one clamp or in two.
    #[error("particle {0} is clamped twice")]
    Twice(usize),
    /// A velocity component that is not finite.
    #[error("clamp velocity {0:?} must be finite")]
    Velocity([f64; 3]),
    /// A clamp moving along a periodic dimension, where the pair list
    /// would wrap its particles back into the box.
    #[error(
        "a clamp moves along periodic dimension {0}: clamps move only along closed dimensions"
    )]
    AlongPeriodic(usize),
    /// Clamps in a stage whose box deforms or is barostatted: the remap
    /// would move clamped particles off their lines.
    #[error("clamps cannot drive a stage whose box deforms or is barostatted: the box's remap would move clamped particles off their lines")]
    WithBoxChange,
}

impl Clamp {
    /// Clamps `particles` at their positions in `x`, moving at `velocity`.
    pub fn new(
        particles: Vec<usize>,
        velocity: [f64; 3],
        x: &[[f64; 3]],
    ) -> Result<Self, ClampError> {
        if !velocity.iter().all(|c| c.is_finite()) {
            return Err(ClampError::Velocity(velocity));
        }
        let mut seen = vec![false; x.len()];
        for &index in &particles {
            let Some(seen) = seen.get_mut(index) else {
                return Err(ClampError::OutOfRange {
                    index,
                    particles: x.len(),
                });
            };
            if std::mem::replace(seen, true) {
                return Err(ClampError::Twice(index));
            }
        }
        let origins = particles.iter().map(|&p| x[p]).collect();
        Ok(Self {
            particles,
            velocity,
            origins,
        })
    }

    /// The clamped particles.
    pub fn particles(&self) -> &[usize] {
        &self.particles
    }

    /// Places the particles at `x0 + v elapsed` with velocity `v`, after
    /// the integrator has moved them (LAMMPS: `xoriginal + v delta` with
    /// `delta` the steps since the clamp began times the timestep).
    pub fn place(&self, elapsed: f64, p: &mut Particles) {
        let v = self.velocity;
        for (&i, x0) in self.particles.iter().zip(&self.origins) {
            p.x[i] = [
                x0[0] + v[0] * elapsed,
                x0[1] + v[1] * elapsed,
                x0[2] + v[2] * elapsed,
            ];
            p.v[i] = v;
        }
    }

    /// Undoes the integrator's last half kick: the velocity stays `v`.
    pub fn hold_velocity(&self, p: &mut Particles) {
        for &i in &self.particles {
            p.v[i] = self.velocity;
        }
    }

    /// The sum of the forces on the clamped particles.
    pub fn force(&self, f: &[[f64; 3]]) -> [f64; 3] {
        self.particles.iter().fold([0.0; 3], |s, &i| {
            [s[0] + f[i][0], s[1] + f[i][1], s[2] + f[i][2]]
        })
    }
}

/// Checks that no particle is in two of `clamps` (of a system of
/// `particles`), that none moves along a dimension of `periodic`, and
/// that the box does not change (`box_changes`).
pub fn check_clamps(
    clamps: &[Clamp],
    particles: usize,
    periodic: [bool; 3],
    box_changes: bool,
) -> Result<(), ClampError> {
    if box_changes && !clamps.is_empty() {
        return Err(ClampError::WithBoxChange);
    }
    let mut seen = vec![false; particles];
    for clamp in clamps {
        if let Some(d) = (0..3).find(|&d| periodic[d] && clamp.velocity[d] != 0.0) {
            return Err(ClampError::AlongPeriodic(d));
        }
        for &index in &clamp.particles {
            let Some(seen) = seen.get_mut(index) else {
                return Err(ClampError::OutOfRange { index, particles });
            };
            if std::mem::replace(seen, true) {
                return Err(ClampError::Twice(index));
            }
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::engine::{EngineError, StageDrivers};
    use crate::scene::{build_system, Scene};

    /// Three particles in a row, bonded 0-1-2, in a closed box (or one
    /// periodic along x).
    fn chain(periodic_x: bool) -> Scene {
        serde_json::from_value(serde_json::json!({
            "seed": 1,
            "box": {"lo": [-5, -5, -5], "lengths": [10, 10, 10], "periodic": [periodic_x, false, false]},
            "particles": {"positions": [[0.0, 0.0, 0.0], [1.0, 0.1, 0.0], [2.0, 0.0, 0.0]]},
            "bonds": {"pairs": [[0, 1], [1, 2]]},
            "force_field": {"bond": {"k": 1.0, "a": 0.0, "gamma": 0.5}},
            "stages": [{"name": "pull", "steps": 10, "dt": 0.01}]
        }))
        .expect("a valid chain scene")
    }

    #[test]
    fn clamped_particles_follow_their_line_and_the_free_one_is_integrated() {
        let mut sys = build_system(&chain(false), 1);
        let x0 = sys.particles.x.clone();
        let v = [0.02, 0.0, -0.01];
        let drivers = StageDrivers {
            dt: 0.01,
            clamps: vec![
                Clamp::new(vec![0], [0.0; 3], &x0).unwrap(),
                Clamp::new(vec![2], v, &x0).unwrap(),
            ],
            ..Default::default()
        };
        sys.setup(&drivers).unwrap();
        let stage_box = sys.simbox.clone();
        for step in 1..=200 {
            sys.step(&drivers, step, &stage_box).unwrap();
            let t = step as f64 * 0.01;
            let p = &sys.particles;
            assert_eq!(
                p.x[2],
                [
                    x0[2][0] + v[0] * t,
                    x0[2][1] + v[1] * t,
                    x0[2][2] + v[2] * t
                ]
            );
            assert_eq!((p.x[0], p.v[0], p.v[2]), (x0[0], [0.0; 3], v));
        }
        let p = &sys.particles;
        // The middle particle, pulled by two stretched bonds, has moved.
        assert!((p.x[1][1] - x0[1][1]).abs() > 1e-3, "{:?}", p.x[1]);
        // Bonds pull the clamps as much as they pull the free particle.
        let on_clamps = [&drivers.clamps[0], &drivers.clamps[1]].map(|c| c.force(&p.f));
        for (d, free) in p.f[1].iter().enumerate() {
            let sum = on_clamps[0][d] + on_clamps[1][d] + free;
            assert!(sum.abs() < 1e-15, "dimension {d}: {sum}");
        }
        assert!(
            on_clamps[1][0] < 0.0,
            "the stretched chain pulls the moving clamp back"
        );
    }

    #[test]
    fn a_clamp_moving_along_a_periodic_dimension_is_refused_at_set_up() {
        let mut sys = build_system(&chain(true), 1);
        let x0 = sys.particles.x.clone();
        let drivers = StageDrivers {
            dt: 0.01,
            clamps: vec![Clamp::new(vec![2], [0.1, 0.0, 0.0], &x0).unwrap()],
            ..Default::default()
        };
        let err = sys.setup(&drivers).unwrap_err();
        assert!(matches!(
            err,
            EngineError::Clamp(ClampError::AlongPeriodic(0))
        ));
        assert!(err.to_string().contains("periodic dimension 0"), "{err}");
    }

    #[test]
    fn bad_clamps_are_refused_naming_the_value() {
        let x = vec![[0.0; 3]; 3];
        assert_eq!(
            Clamp::new(vec![0, 3], [0.0; 3], &x),
            Err(ClampError::OutOfRange {
                index: 3,
                particles: 3
            })
        );
        assert_eq!(
            Clamp::new(vec![1, 1], [0.0; 3], &x),
            Err(ClampError::Twice(1))
        );
        let nan = [0.0, f64::NAN, 0.0];
        assert!(matches!(
            Clamp::new(vec![0], nan, &x),
            Err(ClampError::Velocity(_))
        ));
        let (a, b) = (
            Clamp::new(vec![0, 1], [0.0; 3], &x).unwrap(),
            Clamp::new(vec![2, 1], [0.0; 3], &x).unwrap(),
        );
        let open = [false; 3];
        assert_eq!(
            check_clamps(&[a.clone(), b], 3, open, false),
            Err(ClampError::Twice(1))
        );
        assert_eq!(
            check_clamps(std::slice::from_ref(&a), 1, open, false),
            Err(ClampError::OutOfRange {
                index: 1,
                particles: 1
            })
        );
        assert_eq!(
            check_clamps(std::slice::from_ref(&a), 3, open, false),
            Ok(())
        );
        let moving = Clamp::new(vec![0], [0.0, 0.0, 1.0], &x).unwrap();
        assert_eq!(
            check_clamps(&[moving], 3, [false, false, true], false),
            Err(ClampError::AlongPeriodic(2))
        );
        assert_eq!(
            check_clamps(std::slice::from_ref(&a), 3, [true; 3], false),
            Ok(())
        );
        assert_eq!(
            check_clamps(&[a], 3, open, true),
            Err(ClampError::WithBoxChange)
        );
        assert_eq!(check_clamps(&[], 3, open, true), Ok(()));
    }
}
