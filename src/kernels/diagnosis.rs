//! Why a run went unstable: the likely cause of a [`Fault`], judged from
//! the timestep against the estimated stable limit of velocity Verlet, the
//! multibody coefficient and how close unbonded particles came. Kept apart
//! from `fault.rs`, which the force kernels use in their loops and which
//! must not depend on any force law.

use super::fault::{Fault, FaultKind, DEEP_OVERLAP};
use super::BondCoeffs;

impl Fault {
    /// The likely cause, judged from the timestep, the coefficients of the
    /// interaction ([`stable_timestep`]) and, when the caller knows it
    /// (NaN otherwise), the distance from either particle to its nearest
    /// unbonded neighbour over the contact distance.
    pub fn likely_cause(
        &self,
        dt: f64,
        bond: Option<&BondCoeffs>,
        mass: f64,
        nearest_unbonded: f64,
    ) -> String {
        if self.kind == FaultKind::NonFinite {
            return "a value was already NaN or infinite when the forces were computed: an earlier \
                    blow-up between checks, or non-finite input"
                .into();
        }
        let Some(c) = bond.filter(|_| self.bonded) else {
            return "unbonded particles out of the contact model's range".into();
        };
        let limit = stable_timestep(c, self.reference, mass);
        if dt > LIMIT_MARGIN * limit {
            return format!(
                "the timestep dt = {dt} tau is near or above the stable limit, about {limit:.3} \
                 tau for these coefficients and masses in a solid of the paper's coordination: \
                 reduce dt"
            );
        }
        if self.kind == FaultKind::BondCollapsed && c.a <= -MULTIBODY_LIMIT * c.k {
            return format!(
                "a_B = {} is at or beyond the incompressible limit (about -{MULTIBODY_LIMIT} k_B \
                 d): the multibody term outweighs the spring and bonds collapse; raise a_B",
                c.a
            );
        }
        if nearest_unbonded < DEEP_OVERLAP {
            return format!(
                "unbonded particles overlap here (nearest at {nearest_unbonded:.3} of the contact \
                 distance): the contact repulsion is far stiffer there than the bonds; particles \
                 were placed overlapping, or driven together too fast (strain rate, wall speed)"
            );
        }
        "the solid was deformed faster or further than it can follow (strain rate, wall \
         speed), or a stiffer than usual cluster limits the timestep below the estimate"
            .into()
    }
}

/// `a_B / (k_B d)` at and below which the multibody term is taken as the
/// likely cause of a collapsed bond: the bulk solid rearranges under a 1%
/// compression at `a_B = -1.0` and its bonds collapse at `-1.1`, at every
/// timestep tried (`bpm stability`).
pub const MULTIBODY_LIMIT: f64 = 1.0;

/// The stiffest vibration mode of the paper's bonded solids (about 15
/// bonds per particle) has `lambda ~ STIFFEST_MODE (k_B + a_B / r0) / m`
/// for `a_B >= 0` and damping rate `c ~ STIFFEST_MODE Gamma / m`: measured
/// by power iteration (`bpm stability`, results/stability: `lambda = 10.3
/// (k_B + 0.87 a_B)` on the L = 10 d solid), where [`verlet_limit`] of that
/// mode matches the bisected limit within 1-3% from `a_B = 3` to `-0.5`.
pub const STIFFEST_MODE: f64 = 10.0;

/// A run at more than this fraction of [`stable_timestep`] names the
/// timestep as the likely cause (random packings vary by a few percent).
pub const LIMIT_MARGIN: f64 = 0.9;

/// The largest stable timestep of velocity Verlet (as LAMMPS's `fix nve`
/// and the native engine run it: forces from the half-step velocity) for a
/// mode `x'' = -lambda x - c x'`.
///
/// One step maps `(x, v_{n-1/2})` by a matrix with determinant `1 - c dt`
/// and trace `2 - lambda dt^2 - c dt`; its eigenvalues stay in the unit
/// disc while `lambda dt^2 + 2 c dt <= 4` (and `c dt <= 2`, implied).
pub fn verlet_limit(lambda: f64, c: f64) -> f64 {
    let half = c / lambda;
    -half + (half * half + 4.0 / lambda).sqrt()
}

/// Estimated largest stable timestep (tau) of a bonded solid with bond
/// coefficients `c`, bond length `r0` and particle mass `mass`: the
/// [`verlet_limit`] of its stiffest mode ([`STIFFEST_MODE`]). A negative
/// `a_B` softens that mode, but below `a_B = -0.5` the measured limit falls
/// again (the compressed soft solid rearranges), so it counts as 0 here:
/// the estimate stays on the safe side. Infinite without stiffness.
pub fn stable_timestep(c: &BondCoeffs, r0: f64, mass: f64) -> f64 {
    let lambda = STIFFEST_MODE * (c.k + c.a.max(0.0) / r0) / mass;
    if lambda.is_nan() || lambda <= 0.0 {
        return f64::INFINITY;
    }
    verlet_limit(lambda, STIFFEST_MODE * c.gamma / mass)
}
