//! `bpm mc-box`, `bpm mc-compress`, `bpm mc-calibrate` and `bpm
//! mc-shear`: the multi-contact studies from the command line.

use crate::reference::multicontact;
use crate::scene::protocols::lid::LidOptions;
use crate::studies::mcdem::shear::{self, ContactLaw, Grid, SeriesSpec, ShearOptions};
use crate::studies::mcdem::{calibration as mc_calibration, compression, lid, rigid_box, Closures};
use crate::studies::{command_line, print_line, RuntimeArgs};
use anyhow::{bail, Context, Result};
use clap::ValueEnum;
use std::io::IsTerminal;
use std::path::PathBuf;

/// The closures a multi-contact study compares with plain Hertz.
#[derive(Clone, Copy, Debug, clap::Args)]
pub struct ClosureArgs {
    /// Prefactor of the standard closure.
    #[arg(long, default_value_t = multicontact::STANDARD_GAMMA)]
    gamma: f64,
    /// Prefactor of the advanced closure.
    #[arg(long, default_value_t = multicontact::ADVANCED_GAMMA)]
    gamma_advanced: f64,
    /// Maximum penetration ratio of the advanced closure.
    #[arg(long, default_value_t = multicontact::ADVANCED_MPR)]
    mpr: f64,
}

impl From<ClosureArgs> for Closures {
    fn from(a: ClosureArgs) -> Self {
        Self {
            gamma: a.gamma,
            gamma_advanced: a.gamma_advanced,
            mpr: a.mpr,
        }
    }
}

/// `bpm mc-shear --grid`.
#[derive(Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum ShearGrid {
    /// 21 curves at 6 volume fractions (about 21 minutes on 2 cores).
    Default,
    /// One curve per law at friction 0.5, Poisson's ratio 0.5, volume
    /// fractions 0.75 and 0.9, 108 spheres, short strains.
    Quick,
}

/// The arguments of `bpm mc-box`.
#[derive(clap::Args)]
pub struct McBoxArgs {
    /// Output folder.
    #[arg(short, long, default_value = "results/mcdem/rigid-box")]
    output: PathBuf,
    /// Sphere diameter (m).
    #[arg(long, default_value_t = 2e-3)]
    diameter: f64,
    /// Lid speed (m/s).
    #[arg(long, default_value_t = 0.01)]
    lid_speed: f64,
    /// Young's modulus of the box's walls (Pa).
    #[arg(long, default_value_t = 5e7)]
    wall_modulus: f64,
    /// Lid travel over the sphere radius.
    #[arg(long, default_value_t = 0.5)]
    max_displacement: f64,
    /// Time step (tau = sqrt(m / (E d))).
    #[arg(long, default_value_t = 0.05)]
    dt: f64,
    /// Recorded states per run.
    #[arg(long, default_value_t = 100)]
    records: u64,
    #[command(flatten)]
    closures: ClosureArgs,
    #[command(flatten)]
    runtime: RuntimeArgs,
}

impl McBoxArgs {
    /// `bpm mc-box`.
    pub fn run(self, threads: usize) -> Result<()> {
        let Self {
            output,
            diameter,
            lid_speed,
            wall_modulus,
            max_displacement,
            dt,
            records,
            closures,
            runtime,
        } = self;
        let opts = rigid_box::BoxOptions {
            diameter,
            lid_speed,
            wall_modulus,
            max_displacement,
            dt,
            records,
            closures: closures.into(),
        };
        let runtime = runtime.runtime("mc-box", &opts, threads)?;
        let report = rigid_box::run_box(&opts, &command_line(), &runtime)?;
        rigid_box::write_report(&report, &output)?;
        println!("{}", rigid_box::table(&report));
        println!(
            "wrote {}/rigid_box.json and rigid_box.svg",
            output.display()
        );
        Ok(())
    }
}

/// The arguments of `bpm mc-compress`.
#[derive(clap::Args)]
pub struct McCompressArgs {
    /// Output folder.
    #[arg(short, long, default_value = "results/mcdem/compression")]
    output: PathBuf,
    /// Number of spheres.
    #[arg(long, default_value_t = 514)]
    spheres: usize,
    /// Mean sphere diameter (m).
    #[arg(long, default_value_t = 2.149e-2)]
    mean_diameter: f64,
    /// Standard deviation of the diameters (m).
    #[arg(long, default_value_t = 0.12e-2)]
    diameter_sd: f64,
    /// Box edges x,y,z (m).
    #[arg(
        long = "box",
        value_delimiter = ',',
        default_value = "0.165,0.166,0.168"
    )]
    box_size: Vec<f64>,
    /// Lid speed (m/s).
    #[arg(long, default_value_t = 0.1)]
    lid_speed: f64,
    /// Volume fraction at which the lid turns back.
    #[arg(long, default_value_t = 0.85)]
    max_fraction: f64,
    /// Compression and decompression cycles.
    #[arg(long, default_value_t = 2)]
    cycles: usize,
    /// Young's modulus of the box's walls (Pa).
    #[arg(long, default_value_t = 5e7)]
    wall_modulus: f64,
    /// Time step (tau = sqrt(m / (E d)), d the mean diameter; with
    /// --packing, in the data file's time unit, and required).
    #[arg(long)]
    dt: Option<f64>,
    /// Recorded states per pass of the lid.
    #[arg(long, default_value_t = 200)]
    records: u64,
    /// Seed of the bed.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    #[command(flatten)]
    closures: ClosureArgs,
    #[command(flatten)]
    packing: PackingArgs,
    #[command(flatten)]
    runtime: RuntimeArgs,
}

/// `bpm mc-compress --packing`: the lid protocol on a bed from a data
/// file, every quantity in the file's units (SI for a LIGGGHTS bed). It
/// runs plain Hertz and the standard closure (--gamma); --lid-speed,
/// --cycles, --wall-modulus and --dt apply too, in the file's units.
#[derive(Clone, Debug, clap::Args)]
pub struct PackingArgs {
    /// A bed of spheres as a LAMMPS or LIGGGHTS data file (atom_style
    /// sphere): instead of building one.
    #[arg(long, value_name = "FILE.data")]
    packing: Option<PathBuf>,
    /// With --packing: the side walls, at x = 0 and X, y = 0 and Y (the
    /// floor is z = 0).
    #[arg(long, value_delimiter = ',', value_name = "X,Y")]
    base: Vec<f64>,
    /// With --packing: the lid's height at the start of each compression.
    #[arg(long)]
    lid_start: Option<f64>,
    /// With --packing: the height where the lid turns back.
    #[arg(long)]
    lid_end: Option<f64>,
    /// With --packing: the spheres' Young's modulus [default: 23.3e3].
    #[arg(long)]
    youngs_modulus: Option<f64>,
    /// With --packing: Poisson's ratio of spheres and walls [default: 0.5].
    #[arg(long)]
    poisson_ratio: Option<f64>,
    /// With --packing: the restitution coefficient of every contact
    /// [default: 0.95].
    #[arg(long)]
    restitution: Option<f64>,
    /// With --packing: the sliding friction coefficient of every contact
    /// [default: 0.03].
    #[arg(long)]
    friction: Option<f64>,
    /// With --packing: gravity, an acceleration as three numbers GX GY GZ
    /// (e.g. `--gravity 0 0 -9.81`); none by default.
    #[arg(
        long,
        num_args = 3,
        value_names = ["GX", "GY", "GZ"],
        allow_negative_numbers = true
    )]
    gravity: Vec<f64>,
    /// With --packing: steps between recorded rows [default: 100].
    #[arg(long)]
    record_every: Option<u64>,
    /// With --packing: the neighbour skin (default: a tenth of the mean
    /// diameter).
    #[arg(long)]
    skin: Option<f64>,
    /// With --packing: the walls keep their contacts' friction springs
    /// from one pass of the lid to the next, as LIGGGHTS's wall fixes do
    /// across `run` commands (by default they restart with each pass).
    #[arg(long)]
    keep_wall_histories: bool,
}

impl McCompressArgs {
    /// `bpm mc-compress`.
    pub fn run(self, threads: usize) -> Result<()> {
        let Self {
            output,
            spheres,
            mean_diameter,
            diameter_sd,
            box_size,
            lid_speed,
            max_fraction,
            cycles,
            wall_modulus,
            dt,
            records,
            seed,
            closures,
            packing,
            runtime,
        } = self;
        if let Some(file) = &packing.packing {
            let lid = lid_options(
                &packing,
                file,
                lid_speed,
                cycles,
                wall_modulus,
                dt,
                &closures,
            )?;
            let runtime = runtime.runtime("mc-compress", &lid, threads)?;
            let (report, scenes) = lid::run_lid(&lid, &command_line(), &runtime)?;
            lid::write_lid_report(&report, &scenes, &output)?;
            println!(
                "{} spheres, {} steps per pass, lid at {:e} per time unit, skin {}",
                report.spheres, report.steps_per_pass, report.lid_velocity, report.skin
            );
            print!("{}", lid::lid_table(&report));
            println!(
                "wrote {}/lid.json, lid.svg and scene-*.json",
                output.display()
            );
            return Ok(());
        }
        let p = &packing;
        let given = [
            ("--base", !p.base.is_empty()),
            ("--lid-start", p.lid_start.is_some()),
            ("--lid-end", p.lid_end.is_some()),
            ("--youngs-modulus", p.youngs_modulus.is_some()),
            ("--poisson-ratio", p.poisson_ratio.is_some()),
            ("--restitution", p.restitution.is_some()),
            ("--friction", p.friction.is_some()),
            ("--gravity", !p.gravity.is_empty()),
            ("--record-every", p.record_every.is_some()),
            ("--skin", p.skin.is_some()),
            ("--keep-wall-histories", p.keep_wall_histories),
        ];
        if let Some((option, _)) = given.iter().find(|(_, given)| *given) {
            bail!("{option} belongs to the lid protocol on a bed from a data file: give --packing FILE.data too");
        }
        let dt = dt.unwrap_or(0.05);
        let [bx, by, bz] = box_size[..] else {
            bail!("--box takes three lengths x,y,z (got {})", box_size.len());
        };
        let opts = compression::CompressionOptions {
            spheres,
            mean_diameter,
            diameter_sd,
            box_size: [bx, by, bz],
            lid_speed,
            max_fraction,
            cycles,
            wall_modulus,
            dt,
            records,
            seed,
            closures: closures.into(),
        };
        opts.validate()?;
        let runtime = runtime.runtime("mc-compress", &opts, threads)?;
        let (report, scene) = compression::run_compression(&opts, &command_line(), &runtime)?;
        compression::write_report(&report, &scene, &output)?;
        println!("{}", compression::table(&report));
        println!(
            "wrote {}/compression.json, compression.svg and scene.json",
            output.display()
        );
        Ok(())
    }
}

/// The lid protocol's options from `bpm mc-compress --packing`'s
/// arguments; the error names a missing or malformed option.
fn lid_options(
    p: &PackingArgs,
    file: &std::path::Path,
    lid_speed: f64,
    cycles: usize,
    wall_modulus: f64,
    dt: Option<f64>,
    closures: &ClosureArgs,
) -> Result<LidOptions> {
    let [x, y] = p.base[..] else {
        bail!(
            "--packing needs --base X,Y, the side walls' positions (got {} values)",
            p.base.len()
        );
    };
    let gravity = match p.gravity[..] {
        [] => [0.0; 3],
        [gx, gy, gz] => [gx, gy, gz],
        _ => bail!(
            "--gravity takes three components GX GY GZ (got {})",
            p.gravity.len()
        ),
    };
    let Some(lid_start) = p.lid_start else {
        bail!("--packing needs --lid-start, the lid's height at the start of each compression");
    };
    let Some(lid_end) = p.lid_end else {
        bail!("--packing needs --lid-end, the height where the lid turns back");
    };
    let Some(dt) = dt else {
        bail!("--packing needs --dt, the time step in the data file's time unit");
    };
    let opts = LidOptions {
        packing: file.to_path_buf(),
        base: [x, y],
        lid_start,
        lid_end,
        lid_speed,
        cycles,
        dt,
        youngs_modulus: p.youngs_modulus.unwrap_or(23.3e3),
        wall_modulus,
        poisson_ratio: p.poisson_ratio.unwrap_or(0.5),
        restitution: p.restitution.unwrap_or(0.95),
        friction: p.friction.unwrap_or(0.03),
        gamma: closures.gamma,
        gravity,
        record_every: p.record_every.unwrap_or(100),
        skin: p.skin,
        keep_wall_histories: p.keep_wall_histories,
    };
    opts.validate()?;
    Ok(opts)
}

/// The arguments of `bpm mc-calibrate`.
#[derive(clap::Args)]
pub struct McCalibrateArgs {
    /// Grain compaction studies (folders with a compaction.json).
    #[arg(required = true, num_args = 1..)]
    grains: Vec<PathBuf>,
    /// Output folder.
    #[arg(short, long, default_value = "results/mcdem/calibration")]
    output: PathBuf,
    /// The spheres' friction mu_s,mu_r,mu_t.
    #[arg(long, value_delimiter = ',', default_value = "0.15,0,0")]
    friction: Vec<f64>,
    /// Prefactors of the standard closure.
    #[arg(
        long,
        value_delimiter = ',',
        default_value = "0.5,0.82,1,1.1,1.25,1.5,2"
    )]
    gammas: Vec<f64>,
    /// Prefactors of the advanced closure.
    #[arg(long, value_delimiter = ',', default_value = "0.81,1.25,2")]
    advanced_gammas: Vec<f64>,
    /// Maximum penetration ratios of the advanced closure.
    #[arg(long, value_delimiter = ',', default_value = "0.05,0.11")]
    mprs: Vec<f64>,
    /// The closures' reach (fraction of the two radii). The box must
    /// stay wider than twice the spheres' diameter times (1 + reach),
    /// which is why the default is below `compact`'s 0.25: 32 spheres
    /// compressed by 48% leave room for 0.2.
    #[arg(long, default_value_t = 0.2)]
    reach: f64,
    /// Volumetric strain of the box after jamming at which the spheres
    /// stop.
    #[arg(long, default_value_t = 0.48)]
    volumetric_strain: f64,
    /// Range lo,hi of phi_MC - phi_c over which the fit's error is
    /// taken (default: where the closures act; nearer jamming the
    /// overlaps are too small for a correction to matter).
    #[arg(long, value_delimiter = ',', default_value = "0.1,0.3")]
    window: Vec<f64>,
    #[command(flatten)]
    runtime: RuntimeArgs,
}

impl McCalibrateArgs {
    /// `bpm mc-calibrate`.
    pub fn run(self, threads: usize) -> Result<()> {
        let Self {
            grains,
            output,
            friction,
            gammas,
            advanced_gammas,
            mprs,
            reach,
            volumetric_strain,
            window,
            runtime,
        } = self;
        let [mu_s, mu_r, mu_t] = friction[..] else {
            bail!(
                "--friction takes three values, mu_s,mu_r,mu_t; got {}",
                friction.len()
            );
        };
        let [lo, hi] = window[..] else {
            bail!("--window takes two distances lo,hi; got {}", window.len());
        };
        let opts = mc_calibration::CalibrationOptions {
            grains,
            friction: [mu_s, mu_r, mu_t],
            gammas,
            advanced_gammas,
            mprs,
            reach,
            volumetric_strain,
            window: [lo, hi],
        };
        opts.validate()?;
        let runtime = runtime.runtime("mc-calibrate", &opts, threads)?;
        let report = mc_calibration::run_calibration(
            &opts,
            &runtime,
            &output,
            &command_line(),
            &mut print_line,
        )?;
        print!("{}", mc_calibration::table(&report));
        println!(
            "wrote {}/calibration.json, calibration.svg and calibration.txt",
            output.display()
        );
        Ok(())
    }
}

/// The arguments of `bpm mc-shear`.
#[derive(clap::Args)]
pub struct McShearArgs {
    /// Output folder.
    #[arg(short, long, default_value = "results/mcdem/shear")]
    output: PathBuf,
    /// The grid of curves and volume fractions; options below override
    /// it.
    #[arg(long, value_enum, default_value_t = ShearGrid::Default)]
    grid: ShearGrid,
    /// Volume fractions (default: the grid's).
    #[arg(long, value_delimiter = ',')]
    fractions: Option<Vec<f64>>,
    /// Contact laws. Given any of --laws, --frictions and
    /// --poissons, the curves are every combination of the three
    /// lists, and a list not given takes every value in the grid (for
    /// the default grid: all three laws, friction 0, 0.1, 0.5, 1,
    /// Poisson's ratio 0.25, 0.4, 0.5).
    #[arg(long, value_enum, value_delimiter = ',')]
    laws: Option<Vec<ContactLaw>>,
    /// Friction coefficients.
    #[arg(long, value_delimiter = ',')]
    frictions: Option<Vec<f64>>,
    /// Poisson's ratios.
    #[arg(long, value_delimiter = ',')]
    poissons: Option<Vec<f64>>,
    /// Spheres (grid default: 256; quick: 108).
    #[arg(long)]
    spheres: Option<usize>,
    /// Dimensionless slow shear rate gamma_dot d / sqrt(k / rho)
    /// [default: 2e-3].
    #[arg(long)]
    rate: Option<f64>,
    /// The fast shear's rate over the slow one's [default: 4].
    #[arg(long)]
    rate_factor: Option<f64>,
    /// Strain of the fast shear; its second half is averaged
    /// (default 1.5; quick: 0.4).
    #[arg(long)]
    strain_fast: Option<f64>,
    /// Strain of the slow shear (default 1.25; quick: 0.3).
    #[arg(long)]
    strain_slow: Option<f64>,
    /// Strain at the start of the slow shear left out of its average
    /// (default 0.25; quick: 0.1).
    #[arg(long)]
    discard: Option<f64>,
    /// Time step (tau = sqrt(m / (E d))) [default: 0.05].
    #[arg(long)]
    dt: Option<f64>,
    /// Normal restitution coefficient [default: 0.7].
    #[arg(long)]
    restitution: Option<f64>,
    /// Prefactor of the standard closure [default: 0.82].
    #[arg(long)]
    gamma: Option<f64>,
    /// Prefactor of the advanced closure [default: 0.81].
    #[arg(long)]
    gamma_advanced: Option<f64>,
    /// Maximum penetration ratio of the advanced closure [default:
    /// 0.08].
    #[arg(long)]
    mpr: Option<f64>,
    /// How far beyond touching the closures still correct a pair
    /// (fraction of the two radii) [default: 0.25].
    #[arg(long)]
    reach: Option<f64>,
    /// Largest relative difference of the fast and slow pressure of a
    /// quasi-static point [default: 0.05].
    #[arg(long)]
    quasi_static_tolerance: Option<f64>,
    /// Jamming points as friction:phi_c pairs in increasing friction,
    /// interpolated between (default: 0:0.636,0.1:0.61,0.3:0.596,
    /// 0.5:0.59,1:0.587, see docs/protocols.md).
    #[arg(long, value_delimiter = ',')]
    phi_c: Option<Vec<String>>,
    /// Neighbour skin (d) [default: 0.15].
    #[arg(long)]
    skin: Option<f64>,
    /// Recorded rows per unit strain [default: 100].
    #[arg(long)]
    records_per_strain: Option<f64>,
    /// Seed of the packing.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Runs at a time, one thread each (the global --threads does not
    /// apply: runs are independent, so they share the cores instead).
    #[arg(long, default_value_t = 2)]
    workers: usize,
}

impl McShearArgs {
    /// `bpm mc-shear`.
    pub fn run(self) -> Result<()> {
        let Self {
            output,
            grid,
            fractions,
            laws,
            frictions,
            poissons,
            spheres,
            rate,
            rate_factor,
            strain_fast,
            strain_slow,
            discard,
            dt,
            restitution,
            gamma,
            gamma_advanced,
            mpr,
            reach,
            quasi_static_tolerance,
            phi_c,
            skin,
            records_per_strain,
            seed,
            workers,
        } = self;
        let grid = match grid {
            ShearGrid::Default => Grid::Default,
            ShearGrid::Quick => Grid::Quick,
        };
        let mut opts = ShearOptions::grid(grid);
        if laws.is_some() || frictions.is_some() || poissons.is_some() {
            let distinct =
                |f: fn(&SeriesSpec) -> f64| shear::sorted_distinct(opts.series.iter().map(f));
            let frictions = frictions.unwrap_or_else(|| distinct(|s| s.friction));
            let poissons = poissons.unwrap_or_else(|| distinct(|s| s.poisson_ratio));
            let laws: Vec<ContactLaw> = match laws {
                Some(l) => l,
                None => vec![
                    ContactLaw::Hertz,
                    ContactLaw::Standard,
                    ContactLaw::Advanced,
                ],
            };
            opts.series.clear();
            for &law in &laws {
                for &friction in &frictions {
                    for &poisson_ratio in &poissons {
                        opts.series.push(SeriesSpec {
                            law,
                            friction,
                            poisson_ratio,
                        });
                    }
                }
            }
        }
        if let Some(phi_c) = phi_c {
            opts.jamming_points = phi_c
                .iter()
                .map(|pair| {
                    let parsed = pair.split_once(':').and_then(|(mu, phi)| {
                        Some((mu.trim().parse().ok()?, phi.trim().parse().ok()?))
                    });
                    parsed.with_context(|| {
                        format!(
                            "--phi-c takes friction:phi_c pairs such as 0.5:0.59 (got {pair:?})"
                        )
                    })
                })
                .collect::<Result<_>>()?;
        }
        macro_rules! set {
            ($($field:ident),*) => { $(if let Some(v) = $field { opts.$field = v; })* };
        }
        set!(
            fractions,
            spheres,
            rate,
            rate_factor,
            strain_fast,
            strain_slow,
            discard,
            dt,
            restitution,
            reach,
            quasi_static_tolerance,
            skin,
            records_per_strain
        );
        if let Some(v) = gamma {
            opts.closures.gamma = v;
        }
        if let Some(v) = gamma_advanced {
            opts.closures.gamma_advanced = v;
        }
        if let Some(v) = mpr {
            opts.closures.mpr = v;
        }
        opts.seed = seed;
        opts.workers = workers;
        opts.validate()?;
        let (report, scene) = shear::run_shear(
            &opts,
            &output,
            &command_line(),
            std::io::stderr().is_terminal(),
        )?;
        shear::write_report(&report, &scene, &output)?;
        print!("{}", shear::table(&report));
        println!(
            "wrote {}/shear.json, table.txt, shear.svg, beta.svg, scene.json and runs/",
            output.display()
        );
        Ok(())
    }
}

/// The arguments of `bpm mc-shear-trend`.
#[derive(clap::Args)]
pub struct McShearTrendArgs {
    /// Folders of `bpm mc-shear` studies (each with its shear.json).
    #[arg(required = true)]
    folders: Vec<PathBuf>,
    /// Output folder.
    #[arg(short, long, default_value = "results/mcdem/shear-beta")]
    output: PathBuf,
}

impl McShearTrendArgs {
    /// `bpm mc-shear-trend`.
    pub fn run(self) -> Result<()> {
        let folders: Vec<&std::path::Path> = self.folders.iter().map(|f| f.as_path()).collect();
        let trend = shear::gather_folders(&folders, &command_line())?;
        crate::studies::output::write_report(&trend, &self.output)?;
        print!("{}", shear::trend_table(&trend));
        println!(
            "wrote {}/trend.json, trend.txt and trend.svg",
            self.output.display()
        );
        Ok(())
    }
}
