//! Box deformation with affine remapping, and the Berendsen barostat.

use super::simbox::SimBox;
use serde::{Deserialize, Serialize};

/// A prescribed deformation of the box (LAMMPS `fix deform ... remap x`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case", deny_unknown_fields)]
pub enum Deformation {
    /// Every periodic length scales as `L0 exp(rate t)` about the box centre
    /// (tilts scale with it): negative rates compress.
    Isotropic {
        /// True strain rate (1 / tau).
        true_strain_rate: f64,
    },
    /// Simple shear by tilt: `tilt(t) = tilt0 + rate t L_perp`, the box's
    /// lower corner fixed.
    SimpleShear {
        /// Which tilt factor: "xy", "xz" or "yz".
        tilt: TiltFactor,
        /// Engineering shear strain rate (1 / tau).
        rate: f64,
        /// How particles follow the box; default "x" (affine).
        #[serde(default, skip_serializing_if = "ShearRemap::is_affine")]
        remap: ShearRemap,
    },
}

/// How particles follow a sheared box (LAMMPS `fix deform ... remap`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum ShearRemap {
    /// Positions are mapped affinely with the box at every step: the
    /// whole packing is sheared homogeneously (`remap x`).
    #[default]
    X,
    /// Lees-Edwards boundaries (`remap v`): particles are not displaced;
    /// the periodic images above and below move at the box's shear rate,
    /// so only the boundaries drive the flow. A particle that crosses a
    /// sheared face changes velocity by the images' relative velocity,
    /// the stress counts velocities relative to the linear streaming
    /// profile (peculiar velocities), and the tilt flips by one box
    /// length when it passes half of one, so strain is unbounded.
    V,
}

impl ShearRemap {
    fn is_affine(&self) -> bool {
        *self == ShearRemap::X
    }
}

/// The moving periodic images of a box sheared with Lees-Edwards
/// boundaries: the rates of its tilt factors.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct LeesEdwards {
    /// Rates of change of the tilts `xy, xz, yz` (d / tau).
    pub tilt_rate: [f64; 3],
}

impl LeesEdwards {
    /// Velocity of the image `k` lattice vectors away (`x + h k`) relative
    /// to the particle itself: `(xy' k_y + xz' k_z, yz' k_z, 0)`.
    #[inline(always)]
    pub fn image_velocity(&self, k: &[f64; 3]) -> [f64; 3] {
        let [xy, xz, yz] = self.tilt_rate;
        [xy * k[1] + xz * k[2], yz * k[2], 0.0]
    }

    /// The streaming velocity at `x`: the linear profile that is zero on
    /// the box's lower faces and equals the image velocity on the upper
    /// ones (LAMMPS `compute temp/deform`).
    #[inline]
    pub fn streaming_velocity(&self, simbox: &SimBox, x: &[f64; 3]) -> [f64; 3] {
        // Fractional coordinates of the position as it is, not wrapped: a
        // particle not yet wrapped has the velocity of the image it sits
        // in, and the profile continued outside the box matches it.
        self.image_velocity(&simbox.to_fractional(x))
    }
}

/// A tilt factor of a triclinic box.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum TiltFactor {
    /// x displaced in proportion to y.
    Xy,
    /// x displaced in proportion to z.
    Xz,
    /// y displaced in proportion to z.
    Yz,
}

impl TiltFactor {
    /// Index in `SimBox::tilt`.
    pub fn index(self) -> usize {
        self as usize
    }

    /// The dimension whose length multiplies the shear strain.
    pub fn perpendicular(self) -> usize {
        match self {
            TiltFactor::Xy => 1,
            TiltFactor::Xz | TiltFactor::Yz => 2,
        }
    }

    /// The dimension whose box length the tilt is measured along (a tilt
    /// of a whole such length is the same lattice).
    pub fn direction(self) -> usize {
        match self {
            TiltFactor::Xy | TiltFactor::Xz => 0,
            TiltFactor::Yz => 1,
        }
    }

    /// The dimensions that must be periodic for this tilt.
    pub fn needs_periodic(self) -> [usize; 2] {
        match self {
            TiltFactor::Xy => [0, 1],
            TiltFactor::Xz => [0, 2],
            TiltFactor::Yz => [1, 2],
        }
    }
}

impl Deformation {
    /// The box `elapsed` time after a stage began in box `start`.
    pub fn box_at(&self, start: &SimBox, elapsed: f64) -> SimBox {
        let mut b = start.clone();
        match *self {
            Deformation::Isotropic { true_strain_rate } => {
                let scale = (true_strain_rate * elapsed).exp();
                let mut lengths = start.lengths;
                for (d, l) in lengths.iter_mut().enumerate() {
                    if start.periodic[d] {
                        *l *= scale;
                    }
                }
                b.resize_about_centre(lengths, start.tilt.map(|t| t * scale));
            }
            Deformation::SimpleShear { tilt, rate, remap } => {
                let k = tilt.index();
                let mut tilts = start.tilt;
                tilts[k] += rate * elapsed * start.lengths[tilt.perpendicular()];
                if remap == ShearRemap::V {
                    // Flip by whole box vectors: the same lattice, so the
                    // same periodic system, with the tilt back within half
                    // a length. A yz flip replaces c by c - m b, which also
                    // moves xz by m xy (then xz is brought back in turn).
                    let base = start.lengths[tilt.direction()];
                    let m = (tilts[k] / base).round();
                    tilts[k] -= m * base;
                    if tilt == TiltFactor::Yz {
                        tilts[1] -= m * tilts[0];
                        tilts[1] -= (tilts[1] / start.lengths[0]).round() * start.lengths[0];
                    }
                }
                // A tilt moves no corner of the box's lower face: the lower
                // corner stays, as in LAMMPS's `fix deform`.
                b.tilt = tilts;
            }
        }
        b
    }

    /// The Lees-Edwards images of this deformation from box `start`, or
    /// `None` when particles follow the box affinely.
    pub fn lees_edwards(&self, start: &SimBox) -> Option<LeesEdwards> {
        match *self {
            Deformation::SimpleShear {
                tilt,
                rate,
                remap: ShearRemap::V,
            } => {
                let mut tilt_rate = [0.0; 3];
                tilt_rate[tilt.index()] = rate * start.lengths[tilt.perpendicular()];
                Some(LeesEdwards { tilt_rate })
            }
            _ => None,
        }
    }

    /// Whether positions follow the box affinely.
    pub fn remaps_positions(&self) -> bool {
        !matches!(
            self,
            Deformation::SimpleShear {
                remap: ShearRemap::V,
                ..
            }
        )
    }
}

/// Isotropic Berendsen barostat, LAMMPS's `fix press/berendsen iso`: at
/// the end of each step every periodic length (and tilt) scales about the
/// box centre by `(1 - gain (P_target - P))^(1/3)`, where `P` is LAMMPS's
/// scalar pressure ([`crate::engine::System::scalar_pressure`]). `gain` is
/// LAMMPS's `dt / (Pdamp * modulus)` per step; the harness writes
/// `Pdamp = dt` and `modulus = 1 / gain`, and [`Barostat::step`] evaluates
/// the same expression in the same order, so both engines scale the box
/// by the same number.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Barostat {
    /// Target pressure (k/d).
    pub target_pressure: f64,
    /// Gain per step (d / k).
    pub gain: f64,
}

impl Barostat {
    /// LAMMPS's `modulus` for `Pdamp = dt`: the gain's inverse.
    pub fn modulus(&self) -> f64 {
        1.0 / self.gain
    }

    /// The box after one barostat step at current pressure `pressure`, or
    /// `None` when the gain is so large that the box would invert.
    pub fn step(&self, current: &SimBox, pressure: f64) -> Option<SimBox> {
        // LAMMPS: pow(1 - dt/Pdamp * (P_target - P) / modulus, 1/3) with
        // dt/Pdamp exactly 1; pow, not cbrt, for the same last bit.
        let arg = 1.0 - (self.target_pressure - pressure) / self.modulus();
        if arg.is_nan() || arg <= 0.0 {
            return None;
        }
        let mu = arg.powf(1.0 / 3.0);
        let mut b = current.clone();
        let mut lengths = current.lengths;
        for (d, l) in lengths.iter_mut().enumerate() {
            if current.periodic[d] {
                *l *= mu;
            }
        }
        b.resize_about_centre(lengths, current.tilt.map(|t| t * mu));
        Some(b)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::engine::Particles;

    fn cube() -> SimBox {
        SimBox {
            lo: [0.0; 3],
            lengths: [4.0, 5.0, 6.0],
            tilt: [0.0; 3],
            periodic: [true; 3],
        }
    }

    fn shear(remap: ShearRemap) -> Deformation {
        Deformation::SimpleShear {
            tilt: TiltFactor::Xy,
            rate: 0.1,
            remap,
        }
    }

    #[test]
    fn lees_edwards_tilt_flips_by_a_box_length_and_affine_tilt_does_not() {
        let start = cube();
        // xy = 0.1 t 5: half of lx = 4 at t = 4.
        for (t, flipped) in [(3.9, 1.95), (4.1, 2.05 - 4.0), (12.1, 6.05 - 8.0)] {
            let le = shear(ShearRemap::V).box_at(&start, t);
            assert!((le.tilt[0] - flipped).abs() < 1e-12, "t {t}: {:?}", le.tilt);
            let affine = shear(ShearRemap::X).box_at(&start, t);
            assert!((affine.tilt[0] - 0.5 * t).abs() < 1e-12);
        }
        // A yz flip in a box tilted in xy moves xz with it: the lattice
        // vectors before and after span the same lattice.
        let mut tilted = start.clone();
        tilted.tilt = [1.0, 0.0, 0.0];
        let yz = Deformation::SimpleShear {
            tilt: TiltFactor::Yz,
            rate: 0.1,
            remap: ShearRemap::V,
        };
        let flipped = yz.box_at(&tilted, 4.5); // yz = 0.1 * 4.5 * 6 = 2.7 > 2.5
        assert!(
            (flipped.tilt[2] - (2.7 - 5.0)).abs() < 1e-12,
            "{:?}",
            flipped.tilt
        );
        assert!(
            (flipped.tilt[1] - (-1.0)).abs() < 1e-12,
            "{:?}",
            flipped.tilt
        );
        let le = shear(ShearRemap::V).lees_edwards(&start).unwrap();
        assert_eq!(le.tilt_rate, [0.5, 0.0, 0.0]);
        assert!(shear(ShearRemap::X).lees_edwards(&start).is_none());
        assert!(!shear(ShearRemap::V).remaps_positions());
        assert!(shear(ShearRemap::X).remaps_positions());
    }

    #[test]
    fn a_particle_wrapped_through_a_sheared_face_takes_its_image_velocity() {
        let b = cube();
        let le = LeesEdwards {
            tilt_rate: [0.5, 0.0, 0.0],
        };
        // Above the top face, below the bottom one, and out through x only.
        let mut p = Particles::at_rest(vec![[1.0, 5.5, 1.0], [1.0, -0.5, 1.0], [4.5, 1.0, 1.0]]);
        p.v = vec![[0.1, 0.0, 0.0]; 3];
        p.wrap(&b, Some(&le));
        assert_eq!(p.v[0], [0.1 - 0.5, 0.0, 0.0]);
        assert_eq!(p.v[1], [0.1 + 0.5, 0.0, 0.0]);
        assert_eq!(p.v[2], [0.1, 0.0, 0.0]);
        // The streaming profile is continuous across the move: the velocity
        // relative to it is kept.
        let mut q = Particles::at_rest(vec![[1.0, 5.5, 1.0]]);
        q.v = vec![[0.1, 0.0, 0.0]];
        let before = le.streaming_velocity(&b, &q.x[0])[0];
        q.wrap(&b, Some(&le));
        let after = le.streaming_velocity(&b, &q.x[0])[0];
        assert!(((q.v[0][0] - after) - (0.1 - before)).abs() < 1e-15);
    }
}
