//! The scene commands: `bpm build` (a bulk solid or a grain), `bpm
//! import` (a LAMMPS data file as a scene) and `bpm export` (a scene as a
//! data file).

use super::builders::bulk::{build_bulk, BulkBuild, BulkProtocol};
use super::builders::grain::{build_grain, GrainKind, GrainParams};
use super::datafile::{read_data_file, write_data_file};
use super::{read_scene_unvalidated, write_scene, ForceField, ModelKind};
use crate::kernels::BondFailure;
use anyhow::{bail, Context, Result};
use clap::{Subcommand, ValueEnum};
use std::io::IsTerminal;
use std::path::PathBuf;

/// How bonds break and yield, as the commands that squeeze or compress
/// bonded grains take it.
#[derive(Clone, Debug, Default, clap::Args)]
pub struct BondFailureArgs {
    /// Critical strain eps_c: a bond breaks when |r - r0| / r0 exceeds it.
    #[arg(long)]
    pub critical_strain: Option<f64>,
    /// Plastic strain eps_p (below eps_c): beyond it a bond's rest length
    /// follows its length, so that its strain from rest stays within eps_p.
    #[arg(long)]
    pub plastic_strain: Option<f64>,
    /// Bonds do not break (with --plastic-strain: bonds that only yield).
    #[arg(long)]
    pub no_break: bool,
    /// No smoothing of the bond force towards eps_c.
    #[arg(long)]
    pub no_smooth: bool,
}

impl BondFailureArgs {
    /// The rule the options give: none when none is given (elastic bonds).
    /// `default_critical` is eps_c when bonds break and none is given.
    pub fn failure(&self, default_critical: Option<f64>) -> Result<Option<BondFailure>> {
        for (option, value) in [
            ("--critical-strain", self.critical_strain),
            ("--plastic-strain", self.plastic_strain),
        ] {
            if let Some(v) = value.filter(|v| !(v.is_finite() && *v > 0.0)) {
                bail!("{option} must be positive and finite, got {v}");
            }
        }
        let breaks = !self.no_break;
        if !breaks && self.plastic_strain.is_none() {
            bail!("--no-break without --plastic-strain: the bonds would neither break nor yield");
        }
        if !breaks && (self.critical_strain.is_some() || self.no_smooth) {
            bail!(
                "--critical-strain and --no-smooth are for bonds that break: leave out --no-break"
            );
        }
        let critical_strain = if breaks {
            match self.critical_strain.or(default_critical) {
                Some(eps_c) => eps_c,
                None if self.plastic_strain.is_some() || self.no_smooth => {
                    bail!("bonds that break need --critical-strain (or give --no-break)")
                }
                None => return Ok(None),
            }
        } else {
            // Unused: bonds that neither break nor smooth never read it.
            1.0
        };
        let failure = BondFailure {
            critical_strain,
            breaks,
            smooth: breaks && !self.no_smooth,
            plastic_strain: self.plastic_strain,
            normalize: false,
        };
        failure.check()?;
        Ok(Some(failure))
    }
}

/// A grain kind as the command line names it (every command that builds
/// grains takes it).
#[derive(Clone, Copy, ValueEnum)]
pub enum GrainKindArg {
    /// Cut from the bonded solid.
    Rough,
    /// Cut before bonding, vibrated in an oscillating cage, then bonded.
    Smoother,
}

impl From<GrainKindArg> for GrainKind {
    fn from(k: GrainKindArg) -> Self {
        match k {
            GrainKindArg::Rough => GrainKind::Rough,
            GrainKindArg::Smoother => GrainKind::Smoother,
        }
    }
}

/// What `bpm build` builds.
#[derive(Subcommand)]
pub enum BuildCommand {
    /// The periodic bulk solid of docs/protocols.md "Bulk solid".
    Bulk(BulkArgs),
    /// One grain (docs/protocols.md "Grains"): a sphere of radius R cut
    /// from the bulk packing, rough or smoother; in a closed box, no stages.
    Grain(GrainArgs),
}

impl BuildCommand {
    /// `bpm build bulk` or `bpm build grain`.
    pub fn run(self, threads: usize) -> Result<()> {
        match self {
            Self::Bulk(args) => args.run(threads),
            Self::Grain(args) => args.run(threads),
        }
    }
}

/// The arguments of `bpm build bulk`.
#[derive(clap::Args)]
pub struct BulkArgs {
    /// Box side L (d).
    #[arg(long, default_value_t = 14.0)]
    size: f64,
    /// Seed of the fill and thermal velocities.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Multibody strength a_B (k d).
    #[arg(long = "a-b", default_value_t = 0.0, allow_hyphen_values = true)]
    a_b: f64,
    /// Protocol stages to append.
    #[arg(long, value_enum, default_value = "relax")]
    protocol: BulkProtocol,
    /// Steps of the relax protocol.
    #[arg(long, default_value_t = 1000)]
    steps: u64,
    /// Strain of compress and shear.
    #[arg(long, default_value_t = 0.005)]
    strain: f64,
    /// Strain rate of compress and shear (1 / tau).
    #[arg(long, default_value_t = 1e-5)]
    rate: f64,
    /// Scale the build's relax, thermal and quench times (1 = the paper's).
    #[arg(long, default_value_t = 1.0)]
    time_scale: f64,
    /// Output scene (JSON).
    #[arg(short, long)]
    output: PathBuf,
}

impl BulkArgs {
    /// `bpm build bulk`.
    pub fn run(self, threads: usize) -> Result<()> {
        let Self {
            size,
            seed,
            a_b,
            protocol,
            steps,
            strain,
            rate,
            time_scale,
            output,
        } = self;
        let progress = std::io::stderr().is_terminal();
        let bulk = BulkBuild {
            size,
            seed,
            a_b,
            protocol,
            steps,
            strain,
            rate,
            time_scale,
        };
        bulk.validate()?;
        let params = bulk.params();
        let (mut scene, summary) = build_bulk(&params, threads, progress)?;
        scene.stages = bulk.stages(params.dt);
        write_scene(&output, &scene)?;
        println!(
            "bulk solid L = {size} d, seed {seed}: {} particles, {} bonds, {:.2} bonds per particle (paper: about 15), largest overlap {:.4} d, built in {:.1} s -> {}",
            summary.particles,
            summary.bonds,
            summary.mean_bonds_per_particle,
            summary.max_overlap,
            summary.seconds,
            output.display()
        );
        Ok(())
    }
}

/// The arguments of `bpm build grain`.
#[derive(clap::Args)]
pub struct GrainArgs {
    /// Rough (bonds of the solid kept) or smoother (vibrated, then bonded).
    #[arg(long, value_enum, default_value = "smoother")]
    kind: GrainKindArg,
    /// Radius R (d); the paper's grains have R = 10 d, about 5,000 particles.
    #[arg(long, default_value_t = 10.0)]
    radius: f64,
    /// Seed of the bulk packing.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Multibody strength a_B of the scene's force field (k d).
    #[arg(long = "a-b", default_value_t = 0.0, allow_hyphen_values = true)]
    a_b: f64,
    /// Scale of every time of the build (1 = the full protocol).
    #[arg(long, default_value_t = 1.0)]
    time_scale: f64,
    /// Output scene (JSON).
    #[arg(short, long)]
    output: PathBuf,
    /// Also write it as a LAMMPS data file.
    #[arg(long)]
    data: Option<PathBuf>,
}

impl GrainArgs {
    /// `bpm build grain`.
    pub fn run(self, threads: usize) -> Result<()> {
        let Self {
            kind,
            radius,
            seed,
            a_b,
            time_scale,
            output,
            data,
        } = self;
        let progress = std::io::stderr().is_terminal();
        let mut params = GrainParams::new(kind.into(), radius, seed, a_b);
        params.time_scale = time_scale;
        let (scene, summary) = build_grain(&params, threads, progress)?;
        write_scene(&output, &scene)?;
        if let Some(data) = data {
            std::fs::write(&data, write_data_file(&scene))
                .with_context(|| format!("writing {}", data.display()))?;
        }
        let r = summary.roughness;
        println!(
            "{} grain R = {radius} d, seed {seed}: {} particles, {} bonds, {:.2} bonds per particle; surface height {:.3} +- {:.3} d (roughness, {} direction cells), farthest particle {:.3} d; built in {:.1} s -> {}",
            scene.description.split(' ').next().unwrap_or(""),
            summary.particles,
            summary.bonds,
            summary.mean_bonds_per_particle,
            r.mean_height,
            r.sd_height,
            r.cells,
            r.max_distance,
            summary.seconds,
            output.display()
        );
        Ok(())
    }
}

/// The arguments of `bpm import`.
#[derive(clap::Args)]
#[command(after_help = IMPORT_NOTES)]
pub struct ImportArgs {
    /// The data file (LAMMPS or LIGGGHTS `write_data`: `atom_style bond` or
    /// `atom_style sphere`).
    data: PathBuf,
    /// Periodicity per dimension, as LAMMPS's boundary (data files do
    /// not record it): e.g. `p p p` or `f f f`.
    #[arg(long, num_args = 3, default_values = ["p", "p", "p"])]
    boundary: Vec<String>,
    /// Multibody strength a_B of the scene's (paper) force field (k d).
    #[arg(long = "a-b", default_value_t = 0.0, allow_hyphen_values = true)]
    a_b: f64,
    /// Seed recorded in the scene.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// The sphere material of a DEM data file, as the scene's
    /// force_field.granular: inline JSON or a JSON file, e.g.
    /// '{"youngs_modulus": 100, "poisson_ratio": 0.25, "restitution": 0.5,
    /// "tangential_damping": 1, "sliding_friction": 0.3}'.
    #[arg(long, value_name = "JSON")]
    granular: Option<String>,
    /// Neighbour-list skin, in the file's length unit (force_field.skin).
    /// Default 0.3, or 0.15 x the mean sphere diameter when that lies
    /// outside [0.5, 2] (see below).
    #[arg(long, value_name = "S", allow_negative_numbers = true)]
    skin: Option<f64>,
    /// Gravity, as three numbers GX GY GZ in the file's units of length
    /// over time squared (force_field.gravity), e.g. `--gravity 0 0 -9.81`
    /// for an SI file. Default none.
    #[arg(
        long,
        num_args = 3,
        value_names = ["GX", "GY", "GZ"],
        allow_negative_numbers = true
    )]
    gravity: Option<Vec<f64>>,
    /// Output scene (JSON).
    #[arg(short, long)]
    output: PathBuf,
}

/// What `bpm import --help` adds after the options.
const IMPORT_NOTES: &str = "\
Atom ids are kept: the particles are ordered by id and the scene records the
ids (particles.ids; left out when they are 1..N), so data files and dumps
written from it carry them again.

Units: a data file's lengths and times are taken as the scene's. The default
skin 0.3 is meant for the bonded model's unit length d ~ 1: when the
imported spheres' mean diameter lies outside [0.5, 2], the skin becomes
0.15 x the mean diameter (3 significant digits) and the command says so.
--skin overrides either.

Refused, with a message: Pair Coeffs, PairIJ Coeffs or Bond Coeffs that differ
between types (a scene holds one material), Angles, Dihedrals, Impropers and
body sections, duplicate atom ids, unknown sections.";

/// The skin of imported spheres of mean diameter `mean_diameter` when the
/// default skin (0.3, sized for the bonded model's d ~ 1) does not suit
/// them: 0.15 x the mean diameter, to 3 significant digits, when that
/// diameter lies outside [0.5, 2]; `None` inside.
pub fn skin_for_diameter(mean_diameter: f64) -> Option<f64> {
    if !(mean_diameter > 0.0 && mean_diameter.is_finite()) || (0.5..=2.0).contains(&mean_diameter) {
        return None;
    }
    Some(three_digits(0.15 * mean_diameter)).filter(|s| s.is_finite() && *s > 0.0)
}

/// `x > 0` rounded to 3 significant digits, through exact powers of ten.
fn three_digits(x: f64) -> f64 {
    let shift = 2 - x.log10().floor() as i32;
    if shift >= 0 {
        let p = 10f64.powi(shift);
        (x * p).round() / p
    } else {
        let p = 10f64.powi(-shift);
        (x / p).round() * p
    }
}

impl ImportArgs {
    /// `bpm import`.
    pub fn run(self) -> Result<()> {
        let Self {
            data,
            boundary,
            a_b,
            seed,
            granular,
            skin,
            gravity,
            output,
        } = self;
        let periodic = parse_boundary(&boundary)?;
        if !a_b.is_finite() {
            bail!("--a-b must be finite, got {a_b}");
        }
        if let Some(s) = skin {
            if !(s > 0.0 && s.is_finite()) {
                bail!("--skin must be a finite number > 0, got {s}");
            }
        }
        let gravity = match gravity.as_deref() {
            None => None,
            Some(&[x, y, z]) if [x, y, z].iter().all(|g| g.is_finite()) => Some([x, y, z]),
            Some(g) => bail!("--gravity takes three finite numbers GX GY GZ, got {g:?}"),
        };
        let mut force_field = ForceField::paper(a_b);
        if let Some(g) = granular {
            let text = if g.trim_start().starts_with('{') {
                g
            } else {
                std::fs::read_to_string(&g).with_context(|| format!("reading --granular {g}"))?
            };
            force_field.granular =
                Some(serde_json::from_str(&text).with_context(|| {
                    "--granular is not a sphere material (force_field.granular)"
                })?);
        }
        force_field.gravity = gravity;
        if let Some(s) = skin {
            force_field.skin = s;
        }
        let mut scene = read_data_file(&data, periodic, force_field, seed)?;
        if let (None, Some(mean_diameter)) = (skin, scene.particles.mean_diameter()) {
            if let Some(s) = skin_for_diameter(mean_diameter) {
                scene.force_field.skin = s;
                println!(
                    "skin set to {s} (0.15 of the mean diameter {}); override with --skin",
                    three_digits(mean_diameter)
                );
            }
        }
        write_scene(&output, &scene)?;
        if scene.model == ModelKind::Dem {
            println!(
                "{}: {} DEM spheres -> {}",
                data.display(),
                scene.particles.positions.len(),
                output.display()
            );
        } else {
            let grains = scene
                .particles
                .grain
                .as_ref()
                .map_or(1, |g| g.iter().max().map_or(0, |m| m + 1));
            println!(
                "{}: {} particles in {grains} grain(s), {} bonds -> {}",
                data.display(),
                scene.particles.positions.len(),
                scene.bonds.pairs.len(),
                output.display()
            );
        }
        Ok(())
    }
}

/// The arguments of `bpm export`.
#[derive(clap::Args)]
pub struct ExportArgs {
    /// The scene (JSON).
    scene: PathBuf,
    /// Output data file.
    #[arg(short, long)]
    output: PathBuf,
}

impl ExportArgs {
    /// `bpm export`.
    pub fn run(self) -> Result<()> {
        let Self { scene, output } = self;
        let scene = read_scene_unvalidated(&scene)
            .with_context(|| format!("reading scene {}", scene.display()))?;
        std::fs::write(&output, write_data_file(&scene))
            .with_context(|| format!("writing {}", output.display()))?;
        println!("wrote {}", output.display());
        Ok(())
    }
}

/// `p`/`f` per dimension, as LAMMPS's `boundary` command.
fn parse_boundary(words: &[String]) -> Result<[bool; 3]> {
    let mut periodic = [true; 3];
    for (d, w) in words.iter().enumerate().take(3) {
        periodic[d] = match w.as_str() {
            "p" => true,
            "f" | "s" | "m" => false,
            other => bail!("--boundary takes p or f per dimension, got `{other}`"),
        };
    }
    Ok(periodic)
}
