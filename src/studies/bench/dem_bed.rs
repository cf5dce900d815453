//! The DEM workload's cost against size in `bpm bench`: a periodic bed of
//! spheres in contact that can be tiled to any size, timed with plain
//! Hertz and with the standard closure on one and two threads.
//!
//! The LIGGGHTS bed (514 spheres between walls under a lid) cannot be
//! copied side by side. This bed is the DEM comparison's own (`bpm compact
//! --model dem`): one sphere per grain at the template's centres, with its
//! Hertz contact and sliding friction. Built contact-free, it is squeezed
//! affinely to [`BED_FRACTION`], which presses most spheres against their
//! near neighbours (the line reports the contacts per sphere), and is then
//! held at fixed box: every step searches, measures and sums contacts as
//! a compressed bed does.

use super::{check_copies, faster_on_1_and_2, scene_case, steps_on_copies, BenchCase, BenchError};
use crate::engine::dem::MultiContact;
use crate::scene::builders::grain::GrainKind;
use crate::scene::builders::packing::{build_sphere_packing, PackingParams};
use crate::scene::builders::replicate::replicate;
use crate::scene::{Scene, StageSpec};
use crate::studies::compaction::DemContact;
use crate::studies::hertz::Moduli;
use serde::Serialize;

/// Sphere volume fraction the bed is squeezed to.
pub const BED_FRACTION: f64 = 0.64;

/// The closure's prefactor (LIGGGHTS's hydrogel tutorial's, as in the
/// LIGGGHTS case).
pub const BED_CLOSURE_GAMMA: f64 = 1.125;

/// Largest bed built (spheres); copies give larger ones.
pub const MAX_BED_SPHERES: usize = 20_000;

/// Time step of the bed (tau): the compaction protocol's.
const BED_DT: f64 = 0.1;

/// Which bed the DEM workload times.
#[derive(Clone, Debug, Serialize)]
pub struct DemBedWorkload {
    /// Spheres of the bed (one per grain of a `bpm compact` template).
    pub spheres: usize,
    /// Steps timed on the bed itself (copies run about the same
    /// sphere-steps, at least 20 steps).
    pub steps: u64,
    /// Copies of the bed per side.
    pub replicas: Vec<usize>,
    /// Seed of the template.
    pub seed: u64,
}

impl DemBedWorkload {
    /// Refuses, naming the option, what the builder would refuse only
    /// after the other cases have run.
    pub fn validate(&self) -> Result<(), BenchError> {
        // The template builder and the contact count (every pair) grow
        // faster than the bed: larger beds are copies (--dem-replicas).
        if !(2..=MAX_BED_SPHERES).contains(&self.spheres) {
            return Err(BenchError::Options(format!(
                "--dem-spheres must be 0 (skip) or 2 to {MAX_BED_SPHERES} (larger beds: --dem-replicas), got {}",
                self.spheres
            )));
        }
        if self.steps == 0 {
            return Err(BenchError::Options("--dem-steps must be at least 1".into()));
        }
        check_copies("--dem-replicas", &self.replicas)
    }
}

/// What the DEM workload measured.
#[derive(Clone, Debug, Default, Serialize)]
pub struct DemBedBench {
    /// Spheres of the bed.
    pub spheres: usize,
    /// Spheres pressed together, per sphere (twice the overlapping pairs
    /// over the spheres), on the squeezed bed as its runs start.
    pub contacts_per_sphere: f64,
    /// Plain Hertz, per size and thread count.
    pub hertz: Vec<BenchCase>,
    /// The standard closure, per size and thread count.
    pub closure: Vec<BenchCase>,
}

/// The bed: `spheres` DEM spheres of the compaction's DEM comparison (the
/// template of R = 3 d grains, plain Hertz with sliding friction),
/// squeezed about the box's corner to [`BED_FRACTION`]; no stages.
pub fn dem_bed(spheres: usize, seed: u64, threads: usize) -> Result<Scene, BenchError> {
    let contact = DemContact::default();
    let moduli = Moduli::paper_fits(0.0);
    let params = PackingParams::new(spheres, GrainKind::Smoother, 3.0, 0.0, seed);
    let placeholder = contact.material_of(&moduli, 1.0, 1.0);
    let (mut bed, summary) = build_sphere_packing(&params, placeholder, threads, false)?;
    let mass = bed.particles.mass.mean();
    bed.force_field =
        contact.force_field(contact.material_of(&moduli, summary.template_radius, mass));
    let volume: f64 = bed.simbox.lengths.iter().product();
    let fraction =
        spheres as f64 * 4.0 / 3.0 * std::f64::consts::PI * summary.template_radius.powi(3)
            / volume;
    let scale = (fraction / BED_FRACTION).cbrt();
    for x in &mut bed.particles.positions {
        for (c, lo) in x.iter_mut().zip(bed.simbox.lo) {
            *c = lo + (*c - lo) * scale;
        }
    }
    bed.simbox.lengths = bed.simbox.lengths.map(|l| l * scale);
    Ok(bed)
}

/// Spheres pressed together per sphere in `bed` (minimum image, one
/// radius).
fn contacts_per_sphere(bed: &Scene) -> f64 {
    let x = &bed.particles.positions;
    let radius = bed.particles.radius.as_ref().map_or(0.0, |r| r[0]);
    let l = bed.simbox.lengths;
    let mut pairs = 0usize;
    for i in 0..x.len() {
        for j in i + 1..x.len() {
            let d2: f64 = (0..3)
                .map(|k| {
                    let d = x[i][k] - x[j][k];
                    let d = d - l[k] * (d / l[k]).round();
                    d * d
                })
                .sum();
            pairs += usize::from(d2 < 4.0 * radius * radius);
        }
    }
    2.0 * pairs as f64 / x.len() as f64
}

/// Builds the bed and times it; `log` receives each line.
pub fn bench_dem_bed(
    workload: &DemBedWorkload,
    threads: usize,
    log: &mut dyn FnMut(&str),
) -> Result<DemBedBench, BenchError> {
    let bed = dem_bed(workload.spheres, workload.seed, threads)?;
    let mut bench = DemBedBench {
        spheres: workload.spheres,
        contacts_per_sphere: contacts_per_sphere(&bed),
        ..DemBedBench::default()
    };
    log(&format!(
        "DEM bed: {} spheres squeezed to phi = {BED_FRACTION}, {:.2} contacts per sphere",
        workload.spheres, bench.contacts_per_sphere
    ));
    for &k in &workload.replicas {
        let copies = replicate(&bed, [k; 3])?;
        let steps = steps_on_copies(workload.steps, k);
        let name = match k {
            1 => format!("DEM bed {}", workload.spheres),
            _ => format!("DEM bed {} x{}", workload.spheres, k * k * k),
        };
        bench.hertz.extend(faster_on_1_and_2(log, |threads| {
            bed_case(&copies, &format!("{name} Hertz"), None, threads, steps)
        }));
        let closure = Some(MultiContact::standard(BED_CLOSURE_GAMMA));
        bench.closure.extend(faster_on_1_and_2(log, |threads| {
            bed_case(&copies, &format!("{name} closure"), closure, threads, steps)
        }));
    }
    Ok(bench)
}

/// `bed` held for `steps` steps with `closure` (or plain Hertz), timed.
fn bed_case(
    bed: &Scene,
    name: &str,
    closure: Option<MultiContact>,
    threads: usize,
    steps: u64,
) -> BenchCase {
    let mut scene = bed.clone();
    scene.force_field.multicontact = closure;
    let mut hold = StageSpec::hold("hold", steps, BED_DT);
    hold.record.every = steps;
    scene.stages = vec![hold];
    let name = format!("{name} threads={threads}");
    let ws = bed_working_set_bytes(scene.particles.positions.len());
    scene_case(&scene, name, 0.0, threads, ws)
}

/// Bytes a DEM step touches, roughly: positions, velocities, forces,
/// angular velocities and torques (5 x 24), radius and mass (16), and
/// six listed pairs per sphere (each pair once, within the cutoff and
/// skin), each with its index and tangential history (8 + 24). The
/// closure's buffers come on top.
fn bed_working_set_bytes(spheres: usize) -> usize {
    spheres * (5 * 24 + 16 + 6 * (8 + 24))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_bed_is_squeezed_into_contact_and_options_are_checked() {
        let bed = dem_bed(24, 3, 1).unwrap();
        let r = bed.particles.radius.as_ref().unwrap()[0];
        let volume: f64 = bed.simbox.lengths.iter().product();
        let phi = 24.0 * 4.0 / 3.0 * std::f64::consts::PI * r.powi(3) / volume;
        assert!((phi - BED_FRACTION).abs() < 1e-12, "{phi}");
        let z = contacts_per_sphere(&bed);
        assert!(z > 1.0, "{z} contacts per sphere");
        // Every sphere stays in the box, scaled about its corner.
        let (lo, l) = (bed.simbox.lo, bed.simbox.lengths);
        assert!(bed
            .particles
            .positions
            .iter()
            .all(|x| (0..3).all(|k| x[k] >= lo[k] && x[k] <= lo[k] + l[k])));
        let workload = |spheres, steps, replicas: Vec<usize>| DemBedWorkload {
            spheres,
            steps,
            replicas,
            seed: 1,
        };
        assert!(workload(1, 10, vec![1]).validate().is_err());
        let e = workload(MAX_BED_SPHERES + 1, 10, vec![1]).validate();
        assert!(e.unwrap_err().to_string().contains("--dem-replicas"));
        assert!(workload(8, 0, vec![1]).validate().is_err());
        assert!(workload(8, 10, vec![0]).validate().is_err());
        assert!(workload(8, 10, vec![1, 2]).validate().is_ok());
    }
}
