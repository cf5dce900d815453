//! The simulation box: orthogonal or triclinic, periodic per dimension.
//!
//! Box vectors follow LAMMPS: `a = (lx, 0, 0)`, `b = (xy, ly, 0)`,
//! `c = (xz, yz, lz)`, with the lower corner at `lo`.

pub use crate::kernels::MinimumImage;
use crate::kernels::Separation;

/// A parallelepiped box with LAMMPS's restricted-triclinic convention.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct SimBox {
    /// Lower corner (d units).
    pub lo: [f64; 3],
    /// Edge lengths `lx, ly, lz` (d units).
    pub lengths: [f64; 3],
    /// Tilt factors `xy, xz, yz` (d units).
    pub tilt: [f64; 3],
    /// Periodicity per dimension.
    pub periodic: [bool; 3],
}

impl SimBox {
    /// Box volume.
    pub fn volume(&self) -> f64 {
        self.lengths[0] * self.lengths[1] * self.lengths[2]
    }

    /// Fractional coordinates of `x` (0..1 inside the primary cell).
    #[inline]
    pub fn to_fractional(&self, x: &[f64; 3]) -> [f64; 3] {
        let [lx, ly, lz] = self.lengths;
        let [xy, xz, yz] = self.tilt;
        let sz = (x[2] - self.lo[2]) / lz;
        let sy = (x[1] - self.lo[1] - yz * sz) / ly;
        let sx = (x[0] - self.lo[0] - xy * sy - xz * sz) / lx;
        [sx, sy, sz]
    }

    /// Cartesian position of fractional coordinates `s`.
    #[inline]
    pub fn to_cartesian(&self, s: &[f64; 3]) -> [f64; 3] {
        let [lx, ly, lz] = self.lengths;
        let [xy, xz, yz] = self.tilt;
        [
            self.lo[0] + lx * s[0] + xy * s[1] + xz * s[2],
            self.lo[1] + ly * s[1] + yz * s[2],
            self.lo[2] + lz * s[2],
        ]
    }

    /// The lattice vector `h . n` of integer image `n`.
    #[inline]
    pub fn image_vector(&self, n: &[i32; 3]) -> [f64; 3] {
        let [lx, ly, lz] = self.lengths;
        let [xy, xz, yz] = self.tilt;
        let [a, b, c] = [n[0] as f64, n[1] as f64, n[2] as f64];
        [lx * a + xy * b + xz * c, ly * b + yz * c, lz * c]
    }

    /// Moves `x` into the primary cell along periodic dimensions and records
    /// the shift in `image` so unwrapped positions stay available; returns
    /// the shift.
    pub fn wrap(&self, x: &mut [f64; 3], image: &mut [i32; 3]) -> [i32; 3] {
        let s = self.to_fractional(x);
        let mut shift = [0i32; 3];
        for d in 0..3 {
            if self.periodic[d] {
                shift[d] = s[d].floor() as i32;
            }
        }
        if shift != [0, 0, 0] {
            let w = self.image_vector(&shift);
            for d in 0..3 {
                x[d] -= w[d];
                // Saturating: a blown-up position (shift near i32::MAX) must
                // reach the engine's finiteness check, not overflow here.
                image[d] = image[d].saturating_add(shift[d]);
            }
        }
        shift
    }

    /// Distance between opposite faces, per dimension.
    pub fn face_distances(&self) -> [f64; 3] {
        let [_, ly, lz] = self.lengths;
        let [xy, xz, yz] = self.tilt;
        let bxc = [ly * lz, -xy * lz, xy * yz - ly * xz];
        let norm_bxc = (bxc[0] * bxc[0] + bxc[1] * bxc[1] + bxc[2] * bxc[2]).sqrt();
        [
            self.volume() / norm_bxc,
            ly * lz / (lz * lz + yz * yz).sqrt(),
            lz,
        ]
    }

    /// Sum of the lengths of the periodic box vectors: a bound on how far an
    /// image of a neighbour can move when the box changes by `other - self`.
    pub fn periodic_drift(&self, other: &SimBox) -> f64 {
        let mut drift = 0.0;
        for (d, unit) in [[1, 0, 0], [0, 1, 0], [0, 0, 1]].iter().enumerate() {
            if self.periodic[d] {
                let a = self.image_vector(unit);
                let b = other.image_vector(unit);
                drift +=
                    ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt();
            }
        }
        drift
    }

    /// The affine map that takes positions in this box to the same
    /// fractional positions in `to`.
    pub fn remap_to(&self, to: &SimBox) -> AffineRemap {
        let [lx, ly, lz] = self.lengths;
        let [xy, xz, yz] = self.tilt;
        AffineRemap {
            from_lo: self.lo,
            inverse: [
                1.0 / lx,
                1.0 / ly,
                1.0 / lz,
                -xy / (lx * ly),
                (xy * yz - ly * xz) / (lx * ly * lz),
                -yz / (ly * lz),
            ],
            to: to.clone(),
        }
    }

    /// The centre of the box.
    pub fn centre(&self) -> [f64; 3] {
        self.to_cartesian(&[0.5, 0.5, 0.5])
    }

    /// Sets new lengths and tilts keeping the centre fixed.
    pub fn resize_about_centre(&mut self, lengths: [f64; 3], tilt: [f64; 3]) {
        let centre = self.centre();
        self.lengths = lengths;
        self.tilt = tilt;
        let half = self.to_cartesian(&[0.5, 0.5, 0.5]);
        for d in 0..3 {
            self.lo[d] += centre[d] - half[d];
        }
    }
}

/// Positions mapped affinely from one box into another, through the
/// inverse of the first box's matrix computed once: a deformed or
/// barostatted box remaps every particle at every step, and with three
/// chained divisions per particle the remap was the costliest of the
/// integrator's passes (results/bench/issue33-contact-image, "whole
/// runs"). LAMMPS maps into fractional coordinates the same way
/// (`Domain::x2lamda`).
#[derive(Clone, Debug)]
pub struct AffineRemap {
    from_lo: [f64; 3],
    /// `1/lx, 1/ly, 1/lz` and the off-diagonal terms `(0,1), (0,2), (1,2)`
    /// of the inverse of the upper-triangular box matrix.
    inverse: [f64; 6],
    to: SimBox,
}

impl AffineRemap {
    /// Moves `x` to the point of the target box with the fractional
    /// coordinates it had in the first.
    #[inline]
    pub fn apply(&self, x: &mut [f64; 3]) {
        let [ix, iy, iz, ixy, ixz, iyz] = self.inverse;
        let d = [
            x[0] - self.from_lo[0],
            x[1] - self.from_lo[1],
            x[2] - self.from_lo[2],
        ];
        let s = [
            ix * d[0] + ixy * d[1] + ixz * d[2],
            iy * d[1] + iyz * d[2],
            iz * d[2],
        ];
        *x = self.to.to_cartesian(&s);
    }
}

impl SimBox {
    /// The minimum-image separation of this box, valid while interaction
    /// ranges stay below half of each face distance and tilts within half a
    /// box length (both checked at scene load).
    pub fn minimum_image(&self) -> MinimumImage {
        MinimumImage::new(self.lengths, self.tilt, self.periodic)
    }
}

impl Separation for SimBox {
    #[inline]
    fn delta(&self, xi: &[f64; 3], xj: &[f64; 3]) -> [f64; 3] {
        self.minimum_image().delta(xi, xj)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tilted() -> SimBox {
        SimBox {
            lo: [-1.0, 0.5, 2.0],
            lengths: [5.0, 6.0, 7.0],
            tilt: [0.4, -0.3, 0.2],
            periodic: [true; 3],
        }
    }

    #[test]
    fn fractional_round_trip() {
        let b = tilted();
        let x = [1.3, -2.2, 8.1];
        let back = b.to_cartesian(&b.to_fractional(&x));
        for d in 0..3 {
            assert!((back[d] - x[d]).abs() < 1e-12);
        }
    }

    #[test]
    fn remap_keeps_fractional_positions() {
        let from = tilted();
        let mut to = tilted();
        to.lo = [0.3, -0.7, 1.1];
        to.lengths = [5.5, 5.8, 7.3];
        to.tilt = [-0.2, 0.6, 0.1];
        let remap = from.remap_to(&to);
        for x in [[1.3, -2.2, 8.1], [-4.0, 7.5, 2.0], [0.0, 0.0, 0.0]] {
            let mut y = x;
            remap.apply(&mut y);
            let (s, t) = (from.to_fractional(&x), to.to_fractional(&y));
            for d in 0..3 {
                assert!((s[d] - t[d]).abs() < 1e-14, "{x:?}: {s:?} against {t:?}");
            }
        }
    }

    #[test]
    fn minimum_image_is_invariant_under_lattice_shifts() {
        let b = tilted();
        let xi = [0.2, 1.0, 3.0];
        let xj = [0.9, 1.7, 2.5];
        let base = b.delta(&xi, &xj);
        for n in [[1, 0, 0], [0, -1, 0], [0, 0, 1], [1, 1, -1]] {
            let w = b.image_vector(&n);
            let shifted = [xj[0] + w[0], xj[1] + w[1], xj[2] + w[2]];
            let d = b.delta(&xi, &shifted);
            for k in 0..3 {
                assert!((d[k] - base[k]).abs() < 1e-12, "image {n:?}");
            }
        }
    }

    #[test]
    fn open_dimensions_are_not_imaged() {
        let mut b = tilted();
        b.tilt = [0.0; 3];
        b.periodic = [false, true, false];
        let d = b.delta(&[0.0, 0.0, 0.0], &[4.9, 5.9, 6.9]);
        assert_eq!(d, [-4.9, 0.1 - 0.0 + (-5.9 + 6.0) - 0.1, -6.9]);
    }

    #[test]
    fn wrap_keeps_unwrapped_position() {
        let b = tilted();
        let mut x = [12.0, -9.0, 30.0];
        let orig = x;
        let mut image = [0; 3];
        b.wrap(&mut x, &mut image);
        let s = b.to_fractional(&x);
        assert!(s.iter().all(|&c| (0.0..1.0).contains(&c)));
        let w = b.image_vector(&image);
        for d in 0..3 {
            assert!((x[d] + w[d] - orig[d]).abs() < 1e-12);
        }
    }
}
