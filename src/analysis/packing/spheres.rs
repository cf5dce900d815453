//! A state of a packing of DEM spheres: the same measurements as for
//! bonded grains where they exist for rigid spheres (`phi_sphere`,
//! `phi_MC`, contacts and the coordination number without rattlers); a
//! sphere keeps its shape, so it has no volumetric strain or asphericity.

use super::{coordination, geometric_contacts, monte_carlo_volume_fraction};
use super::{AnalysisOptions, PackingError, PackingState};
use crate::engine::SimBox;

/// The state of spheres of one radius `radius` centred at `centres`
/// (wrapped or not) in `simbox`:
///
/// - `phi_sphere`: the spheres' volumes over the box volume, which counts
///   overlaps twice and exceeds 1 when compressed far;
/// - `phi_mc`: the volume fraction of the union of the spheres, by Monte
///   Carlo (`opts.mc_points`, `opts.mc_seed`);
/// - contacts: overlapping pairs (centres closer than `2 radius`, in any
///   periodic image), the coordination number without rattlers in both
///   `z_force` and `z_geometry` (for spheres the two definitions agree).
pub fn analyse_spheres(
    simbox: &SimBox,
    centres: &[[f64; 3]],
    radius: f64,
    opts: &AnalysisOptions,
) -> Result<PackingState, PackingError> {
    if !simbox.periodic.iter().all(|&p| p) {
        return Err(PackingError::NotPeriodic);
    }
    let box_volume = simbox.volume();
    let phi =
        monte_carlo_volume_fraction(simbox, &[], centres, radius, opts.mc_points, opts.mc_seed);
    let volume = centres.len() as f64 * 4.0 / 3.0 * std::f64::consts::PI * radius.powi(3);
    let contacts = geometric_contacts(simbox, centres, 2.0 * radius);
    let z = coordination(centres.len(), &contacts, opts.max_rattler_contacts);
    Ok(PackingState {
        box_volume,
        phi_mc: phi.phi,
        phi_mc_error: phi.error,
        phi_sphere: volume / box_volume,
        z_force: z.z,
        rattlers_force: z.rattlers,
        z_geometry: z.z,
        rattlers_geometry: z.rattlers,
        force_contacts: contacts.len(),
        ..PackingState::default()
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cube(length: f64) -> SimBox {
        SimBox {
            lo: [0.0; 3],
            lengths: [length; 3],
            tilt: [0.0; 3],
            periodic: [true; 3],
        }
    }

    fn opts(points: u64) -> AnalysisOptions {
        AnalysisOptions {
            mc_points: points,
            ..AnalysisOptions::default()
        }
    }

    /// Two overlapping spheres: `phi_MC` is the union's volume (two
    /// spheres less their lens, `pi (4R + s)(2R - s)^2 / 12` at centre
    /// distance `s`), `phi_sphere` counts the lens twice.
    #[test]
    fn overlapping_spheres_fill_their_union() {
        let (r, s, length): (f64, f64, f64) = (1.0, 1.2, 4.0);
        let simbox = cube(length);
        let centres = [[1.5, 2.0, 2.0], [1.5 + s, 2.0, 2.0]];
        let state = analyse_spheres(&simbox, &centres, r, &opts(400_000)).unwrap();
        let ball = 4.0 / 3.0 * std::f64::consts::PI * r.powi(3);
        let lens = std::f64::consts::PI * (4.0 * r + s) * (2.0 * r - s).powi(2) / 12.0;
        let union = (2.0 * ball - lens) / length.powi(3);
        assert!(
            (state.phi_mc - union).abs() < 4.0 * state.phi_mc_error,
            "{} vs {union}",
            state.phi_mc
        );
        assert!((state.phi_sphere - 2.0 * ball / length.powi(3)).abs() < 1e-15);
        assert_eq!(state.force_contacts, 1);
        // Two spheres with one contact each are rattlers.
        assert_eq!((state.rattlers_force, state.z_force), (2, 0.0));
    }

    /// A simple cubic lattice of spheres pressed 5% into their neighbours,
    /// across the periodic faces too: six contacts each, no rattlers.
    #[test]
    fn a_pressed_cubic_lattice_has_six_contacts_per_sphere() {
        let (r, spacing, per_side) = (0.5, 0.95, 4);
        let simbox = cube(spacing * per_side as f64);
        let mut centres = Vec::new();
        for a in 0..per_side {
            for b in 0..per_side {
                for c in 0..per_side {
                    centres.push([a, b, c].map(|k| (k as f64 + 0.5) * spacing));
                }
            }
        }
        let state = analyse_spheres(&simbox, &centres, r, &opts(10_000)).unwrap();
        assert_eq!(state.force_contacts, 3 * centres.len());
        assert_eq!((state.z_force, state.rattlers_force), (6.0, 0));
        assert_eq!(state.z_geometry, state.z_force);
        assert!(state.eps_v.is_empty() && state.asphericity.is_empty());
    }
}
