//! `bpm compact`, `bpm compare-compaction` and `bpm analyse-packing`: the
//! compaction study, the comparison of studies and the analysis of a
//! LAMMPS dump from the command line.

use crate::analysis::packing::AnalysisOptions;
use crate::engine::dem::MultiContact;
use crate::lammps::cli::EngineArg;
use crate::scene::cli::{BondFailureArgs, GrainKindArg};
use crate::scene::protocols;
use crate::studies::compaction;
use crate::studies::mcdem::Closures;
use crate::studies::{command_line, print_line, RuntimeArgs};
use anyhow::{Context, Result};
use clap::ValueEnum;
use std::path::PathBuf;

/// The particle model of `bpm compact --model`.
#[derive(Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum CompactModel {
    /// Bonded grains.
    Bpm,
    /// DEM spheres, one per grain.
    Dem,
}

/// The multi-contact closure of `bpm compact --closure`.
#[derive(Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum ClosureKind {
    /// Every contact corrected by the sphere's other contacts.
    Standard,
    /// The standard closure, switched off beyond the maximum penetration
    /// ratio.
    Advanced,
}

/// The arguments of `bpm compact`.
#[derive(clap::Args)]
pub struct CompactArgs {
    /// Output folder.
    #[arg(short, long, default_value = "results/compaction")]
    output: PathBuf,
    /// Grains per built packing (paper: 1,024).
    #[arg(long, default_value_t = 32)]
    grains: usize,
    /// Grain radius R (d) (paper: 10).
    #[arg(long, default_value_t = 3.0)]
    radius: f64,
    /// Grain kind.
    #[arg(long, value_enum, default_value = "smoother")]
    kind: GrainKindArg,
    /// Different grains built per packing (each reused, rotated).
    #[arg(long, default_value_t = 4)]
    distinct_grains: usize,
    /// Volume fraction of the template's spheres (grains' outer spheres).
    #[arg(long, default_value_t = 0.57)]
    template_fraction: f64,
    /// Scale of the grain builds' times (1 = the full protocol).
    #[arg(long, default_value_t = 1.0)]
    time_scale: f64,
    /// Compress this packing instead (LAMMPS data file: atom_style
    /// bond, molecule id = grain, or with --model dem atom_style sphere,
    /// one radius; the box is taken as periodic and must be orthogonal;
    /// image flags honoured).
    #[arg(long)]
    packing: Option<PathBuf>,
    /// Multibody strength a_B (k d); the force field is the paper's
    /// (for DEM spheres: the solid's E and nu at a_B).
    #[arg(long = "a-b", allow_hyphen_values = true, default_value_t = 0.0)]
    a_b: f64,
    /// Use the zero-net-multibody variant (docs/model.md).
    #[arg(long)]
    zero_net: bool,
    /// Bonds that break or yield while the packing is compressed (the
    /// native engine only; none given: elastic bonds).
    #[command(flatten)]
    failure: BondFailureArgs,
    /// Bonded particles also touch through the contact law (as upstream
    /// LAMMPS's overlay/pair yes): a bond squeezed below the contact
    /// distance meets the contact's repulsion too. Native engine only.
    #[arg(long)]
    overlay_pair: bool,
    /// Seeds: one packing and run per seed (comma separated).
    #[arg(long, value_delimiter = ',', default_value = "1")]
    seeds: Vec<u64>,
    /// The engine.
    #[arg(long, value_enum, default_value = "native")]
    engine: EngineArg,
    /// MPI ranks of the LAMMPS engine.
    #[arg(long, default_value_t = 1)]
    ranks: usize,
    /// Timestep (tau).
    #[arg(long, default_value_t = 0.1)]
    dt: f64,
    /// Barostat target pressure while jamming (k/d).
    #[arg(long, default_value_t = 1e-6)]
    jam_pressure: f64,
    /// Barostat gain per step (d/k).
    #[arg(long, default_value_t = 1.0)]
    jam_gain: f64,
    /// Duration of the jamming stage (tau).
    #[arg(long, default_value_t = 2e4)]
    jam_time: f64,
    /// First true strain rate per dimension (1/tau).
    #[arg(long, default_value_t = 1e-7)]
    rate_start: f64,
    /// Last true strain rate (1/tau).
    #[arg(long, default_value_t = 1e-5)]
    rate_end: f64,
    /// Rates from first to last, geometrically spaced.
    #[arg(long, default_value_t = 5)]
    rate_levels: usize,
    /// Duration of each compression stage (tau).
    #[arg(long, default_value_t = 1e4)]
    stage_time: f64,
    /// Volumetric strain of the box after jamming at which to stop.
    #[arg(long, default_value_t = 0.6)]
    volumetric_strain: f64,
    /// Thermo rows per stage.
    #[arg(long, default_value_t = 100)]
    rows_per_stage: u64,
    /// Recorded (analysed) states per stage.
    #[arg(long, default_value_t = 4)]
    states_per_stage: u64,
    /// After the compression, expand the box back to its jammed size at
    /// this true strain rate (1/tau) and rest as long: the grains' strain
    /// left unloaded (0: no unloading).
    #[arg(long, default_value_t = 0.0)]
    unload_rate: f64,
    /// Monte Carlo points per state for phi_MC.
    #[arg(long, default_value_t = 1_000_000)]
    mc_points: u64,
    /// States per run at which the packing's bulk and shear moduli are
    /// measured (0 = none), spread evenly in ln(phi - phi_c); default 6
    /// for bonded grains, 0 (the only choice) for DEM spheres. This and
    /// the other --moduli-* options may differ on --resume: the packings
    /// and runs come from the checkpoint, the moduli are measured anew.
    #[arg(long)]
    moduli_states: Option<usize>,
    /// Relaxation before each modulus loading (tau) (paper: 1e4).
    #[arg(long, default_value_t = 1e3)]
    moduli_relax_time: f64,
    /// True strain rate per dimension of the bulk-modulus compression
    /// (1/tau) (paper: 1e-8); the shear runs at twice it, to 0.04%.
    #[arg(long, default_value_t = 1e-7)]
    moduli_rate: f64,
    /// Particle model: bonded grains, or one DEM sphere per grain at
    /// the same template's centres (docs/protocols.md "DEM
    /// comparison").
    #[arg(long, value_enum, default_value = "bpm")]
    model: CompactModel,
    /// DEM friction coefficients mu_s,mu_r,mu_t (sliding, rolling,
    /// twisting) [default 0.3,0,0] (paper: 0.3,0,0 and 0.15,0.1,0.1
    /// match rough grains, 0.15,0,0 and 0.1,0.05,0.05 smoother ones).
    #[arg(long, value_delimiter = ',', value_name = "MU_S,MU_R,MU_T")]
    friction: Option<Vec<f64>>,
    /// DEM restitution coefficient (Tsuji's damping) [default 0.5].
    #[arg(long)]
    restitution: Option<f64>,
    /// DEM tangential over normal damping, x_gt [default 1].
    #[arg(long)]
    tangential_damping: Option<f64>,
    /// DEM reference overlap over R_eff of the rolling and twisting
    /// springs [default 0.01]: the tangential spring at this overlap;
    /// it also sets the twisting torque cap 2/3 a_ref mu_t, a_ref =
    /// R_eff sqrt(overlap).
    #[arg(long)]
    reference_overlap: Option<f64>,
    /// DEM multi-contact closure (docs/model.md, "Multi-contact
    /// closures"); plain Hertz without.
    #[arg(long, value_enum)]
    closure: Option<ClosureKind>,
    /// Prefactor gamma of the closure [default 0.82 standard, 0.81
    /// advanced].
    #[arg(long)]
    gamma: Option<f64>,
    /// Maximum penetration ratio of the advanced closure [default 0.11].
    #[arg(long)]
    mpr: Option<f64>,
    /// How far beyond touching, as a fraction of the two radii, the
    /// closure looks for receivers [default 0.25]; the box must stay
    /// wider than twice the spheres' diameter times (1 + reach).
    #[arg(long)]
    reach: Option<f64>,
    /// Refit the runs of an earlier OUTPUT/compaction.json and rewrite
    /// its plots and table, without running anything (other options
    /// are ignored).
    #[arg(long)]
    refit: bool,
    #[command(flatten)]
    runtime: RuntimeArgs,
}

impl CompactArgs {
    /// `bpm compact`.
    pub fn run(self, threads: usize) -> Result<()> {
        let Self {
            output,
            grains,
            radius,
            kind,
            distinct_grains,
            template_fraction,
            time_scale,
            packing,
            a_b,
            zero_net,
            failure,
            overlay_pair,
            seeds,
            engine,
            ranks,
            dt,
            jam_pressure,
            jam_gain,
            jam_time,
            rate_start,
            rate_end,
            rate_levels,
            stage_time,
            volumetric_strain,
            rows_per_stage,
            states_per_stage,
            unload_rate,
            mc_points,
            moduli_states,
            moduli_relax_time,
            moduli_rate,
            model,
            friction,
            restitution,
            tangential_damping,
            reference_overlap,
            closure,
            gamma,
            mpr,
            reach,
            refit,
            runtime,
        } = self;
        if refit {
            let report = compaction::refit(&output)?;
            print!("{}", compaction::table(&report));
            println!(
                "refitted {} run(s); rewrote {}/compaction.json, compaction.svg, jamming.svg, distributions.svg and moduli.svg (grains; moduli if measured) and compaction.txt",
                report.runs.len(),
                output.display()
            );
            return Ok(());
        }
        let dem = match model {
            CompactModel::Bpm => {
                let given = [
                    ("--friction", friction.is_some()),
                    ("--restitution", restitution.is_some()),
                    ("--tangential-damping", tangential_damping.is_some()),
                    ("--reference-overlap", reference_overlap.is_some()),
                    ("--closure", closure.is_some()),
                    ("--gamma", gamma.is_some()),
                    ("--mpr", mpr.is_some()),
                    ("--reach", reach.is_some()),
                ];
                if let Some((name, _)) = given.iter().find(|g| g.1) {
                    anyhow::bail!("{name} is a DEM option: add --model dem");
                }
                None
            }
            CompactModel::Dem => {
                let closure_given = [("--gamma", gamma), ("--mpr", mpr), ("--reach", reach)];
                if closure.is_none() {
                    if let Some((name, _)) = closure_given.iter().find(|g| g.1.is_some()) {
                        anyhow::bail!("{name} sets the multi-contact closure: add --closure standard or --closure advanced");
                    }
                }
                if closure == Some(ClosureKind::Standard) && mpr.is_some() {
                    anyhow::bail!("--mpr belongs to the advanced closure: use --closure advanced");
                }
                // The defaults are the study's Appendix B values, as in mc-box.
                let paper = Closures::default();
                let multicontact = closure.map(|kind| {
                    let mut m = match kind {
                        ClosureKind::Standard => {
                            MultiContact::standard(gamma.unwrap_or(paper.gamma))
                        }
                        ClosureKind::Advanced => MultiContact::advanced(
                            gamma.unwrap_or(paper.gamma_advanced),
                            mpr.unwrap_or(paper.mpr),
                        ),
                    };
                    if let Some(reach) = reach {
                        m.reach = reach;
                    }
                    m
                });
                let d = compaction::DemContact::default();
                Some(compaction::DemContact {
                    friction: match friction {
                        Some(given) => given.try_into().map_err(|given: Vec<f64>| {
                            anyhow::anyhow!(
                                "--friction takes three values, mu_s,mu_r,mu_t; got {}",
                                given.len()
                            )
                        })?,
                        None => d.friction,
                    },
                    restitution: restitution.unwrap_or(d.restitution),
                    tangential_damping: tangential_damping.unwrap_or(d.tangential_damping),
                    reference_overlap: reference_overlap.unwrap_or(d.reference_overlap),
                    multicontact,
                })
            }
        };
        let bond_failure = failure.failure(None)?;
        let opts = compaction::CompactOptions {
            source: match packing {
                Some(path) => compaction::PackingSource::File { path },
                None => compaction::PackingSource::Build {
                    grains,
                    kind: kind.into(),
                    radius,
                    distinct_grains,
                    template_fraction,
                    time_scale,
                },
            },
            a_b,
            zero_net,
            seeds,
            protocol: protocols::CompactionProtocol {
                dt,
                jam_pressure,
                jam_gain,
                jam_time,
                rate_start,
                rate_end,
                rate_levels,
                stage_time,
                volumetric_strain,
                rows_per_stage,
                states_per_stage,
                unload_rate,
            },
            engine: match engine {
                EngineArg::Native => compaction::CompactionEngine::Native,
                EngineArg::Lammps => compaction::CompactionEngine::Lammps { ranks },
            },
            analysis: AnalysisOptions {
                mc_points,
                ..Default::default()
            },
            moduli: compaction::ModuliOptions {
                // A modulus run cannot restart with broken bonds.
                states: moduli_states.unwrap_or(match model {
                    CompactModel::Bpm if bond_failure.is_none() && !overlay_pair => 6,
                    CompactModel::Bpm | CompactModel::Dem => 0,
                }),
                protocol: protocols::PackingModuliProtocol {
                    dt,
                    relax_time: moduli_relax_time,
                    compression_rate: moduli_rate,
                    shear_rate: 2.0 * moduli_rate,
                    ..protocols::PackingModuliProtocol::paper()
                },
            },
            dem,
            bond_failure,
            overlay_pair,
        };
        opts.validate()?;
        let exe = std::env::current_exe().context("locating the bpm executable")?;
        let runtime = runtime.runtime("compact", &opts.checkpoint_identity(), threads)?;
        let report = compaction::run_compaction(
            &opts,
            &runtime,
            Some(&exe),
            &output,
            &command_line(),
            &mut print_line,
        )?;
        print!("{}", compaction::table(&report));
        println!(
            "{} run(s); wrote {}/compaction.json, compaction.svg, jamming.svg, distributions.svg and moduli.svg (grains; moduli if measured) and compaction.txt",
            report.runs.len(),
            output.display()
        );
        Ok(())
    }
}

/// The arguments of `bpm compare-compaction`.
#[derive(clap::Args)]
pub struct CompareCompactionArgs {
    /// Study folders, each with a compaction.json; the first is the
    /// reference.
    #[arg(required = true, num_args = 1..)]
    studies: Vec<PathBuf>,
    /// A label per study (comma separated); default the folder names.
    #[arg(long, value_delimiter = ',')]
    labels: Vec<String>,
    /// Output folder.
    #[arg(short, long)]
    output: PathBuf,
}

impl CompareCompactionArgs {
    /// `bpm compare-compaction`.
    pub fn run(self) -> Result<()> {
        let Self {
            studies,
            labels,
            output,
        } = self;
        if !labels.is_empty() && labels.len() != studies.len() {
            anyhow::bail!(
                "--labels: {} labels for {} studies",
                labels.len(),
                studies.len()
            );
        }
        let read: Vec<compaction::compare::Study> = studies
            .iter()
            .enumerate()
            .map(|(k, dir)| {
                let label = labels.get(k).cloned().unwrap_or_else(|| {
                    dir.file_name()
                        .map_or(dir.display().to_string(), |n| n.to_string_lossy().into())
                });
                compaction::compare::read_study(dir, &label)
            })
            .collect::<Result<_, _>>()?;
        let table = compaction::compare::write_comparison(&read, &output, &command_line())?;
        print!("{table}");
        println!(
            "wrote {}/comparison.svg and comparison.txt",
            output.display()
        );
        Ok(())
    }
}

/// The arguments of `bpm analyse-packing`.
#[derive(clap::Args)]
pub struct AnalysePackingArgs {
    /// The packing's data file (atom_style bond, molecule id = grain):
    /// bonds, grains, and the reference (stress-free) state.
    #[arg(long)]
    data: PathBuf,
    /// The dump (columns id mol x y z, optional ix iy iz).
    #[arg(long)]
    dump: PathBuf,
    /// Monte Carlo points per frame for phi_MC.
    #[arg(long, default_value_t = 1_000_000)]
    mc_points: u64,
    /// Output JSON.
    #[arg(short, long)]
    output: PathBuf,
}

impl AnalysePackingArgs {
    /// `bpm analyse-packing`.
    pub fn run(self) -> Result<()> {
        let Self {
            data,
            dump,
            mc_points,
            output,
        } = self;
        if mc_points < 1000 {
            anyhow::bail!("--mc-points must be at least 1000, got {mc_points}");
        }
        let analysis = AnalysisOptions {
            mc_points,
            ..Default::default()
        };
        let report = compaction::analyse_dump(&data, &dump, &analysis, &command_line())?;
        crate::studies::output::write_json(&output, &report)?;
        for f in &report.frames {
            println!(
                "step {:>10}: phi_MC = {:.4} +- {:.4}, Z_force = {:.2}, Z_geometry = {:.2}, eps_V = {:.4}, alpha - alpha0 = {:.2e}",
                f.step,
                f.packing.phi_mc,
                f.packing.phi_mc_error,
                f.packing.z_force,
                f.packing.z_geometry,
                f.packing.eps_v_mean,
                f.packing.asphericity_excess_mean
            );
        }
        println!("wrote {}", output.display());
        Ok(())
    }
}
