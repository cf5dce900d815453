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
    },
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
            Deformation::SimpleShear { tilt, rate } => {
                let mut tilts = start.tilt;
                tilts[tilt.index()] += rate * elapsed * start.lengths[tilt.perpendicular()];
                // A tilt moves no corner of the box's lower face: the lower
                // corner stays, as in LAMMPS's `fix deform`.
                b.tilt = tilts;
            }
        }
        b
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
