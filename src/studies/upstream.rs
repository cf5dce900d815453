//! The comparison with upstream (`bpm upstream-check`): our styles (loaded
//! with `plugin load`) against upstream LAMMPS's own implementation of the
//! model (`bond_style bpm/spring volume/factor yes`, `pair_style bpm/spring
//! anharmonic yes`) in the same modern LAMMPS, and the speed ratio
//! ([`run_upstream_check`]).
//!
//! Upstream takes reference lengths at the first run, so both inputs read
//! the same data file at the reference state and deform it in LAMMPS
//! (`lammps_inputs/upstream_compare/`, run from the embedded copy written
//! into the work folder).

pub mod cli;

use crate::verify::upstream::Result;
pub use crate::verify::upstream::{
    block_tension, bond_pull, row_header, ModernLammps, Styles, UpstreamError, UpstreamRow,
    TOLERANCE_PREFIX,
};

use crate::engine::SimBox;
use crate::file_error::FileError;
use crate::kernels::Separation;
use crate::lammps::{write_run_data_file, write_templates};
use crate::scene::Scene;
use crate::verify::compare::max_position_deviation;
use crate::verify::launch::Work;
use crate::verify::scenes::{contact_solid_reference, grain_pair};
use crate::verify::single_point::{max_relative_deviation, read_dump};
use crate::verify::tolerances::tolerance;
use serde::Serialize;
use std::path::{Path, PathBuf};

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
    /// That run's timing breakdown (s per section).
    pub sections: LoopSections,
}

/// The seconds of one LAMMPS run's loop in each section of its timing
/// breakdown (`Pair | ...`, `Bond | ...`), NaN where the table has no
/// such line: where a loop's time goes.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct LoopSections {
    /// Pair forces.
    pub pair: f64,
    /// Bond forces.
    pub bond: f64,
    /// Neighbour list builds.
    pub neigh: f64,
    /// Communication (ghost atoms, also on one rank).
    pub comm: f64,
    /// Fixes (the integrator).
    pub modify: f64,
    /// Output.
    pub output: f64,
    /// The rest.
    pub other: f64,
}

impl LoopSections {
    /// The sections' names in LAMMPS's table, in the order of
    /// [`Self::from_values`] and [`Self::values`].
    pub const NAMES: [&'static str; 7] =
        ["Pair", "Bond", "Neigh", "Comm", "Modify", "Output", "Other"];

    /// No section timed.
    pub const UNTIMED: Self = Self::from_values([f64::NAN; 7]);

    /// The sections from their values in the order of [`Self::NAMES`].
    pub const fn from_values([pair, bond, neigh, comm, modify, output, other]: [f64; 7]) -> Self {
        Self {
            pair,
            bond,
            neigh,
            comm,
            modify,
            output,
            other,
        }
    }

    /// The values in the order of [`Self::NAMES`].
    pub fn values(&self) -> [f64; 7] {
        [
            self.pair,
            self.bond,
            self.neigh,
            self.comm,
            self.modify,
            self.output,
            self.other,
        ]
    }

    /// The sections of the last timing breakdown in a LAMMPS `log` (the
    /// average column of `Section | min time | avg time | ...`).
    pub fn of_log(log: &str) -> Self {
        let Some(start) = log.rfind("MPI task timing breakdown") else {
            return Self::UNTIMED;
        };
        let table = &log[start..];
        let seconds = |name: &str| {
            table
                .lines()
                .find(|l| l.split('|').next().is_some_and(|h| h.trim() == name))
                .and_then(|l| l.split('|').nth(2))
                .and_then(|t| t.trim().parse::<f64>().ok())
                .unwrap_or(f64::NAN)
        };
        Self::from_values(Self::NAMES.map(seconds))
    }

    /// Each section times `factor` (seconds to ns per particle-step).
    pub fn scaled(&self, factor: f64) -> Self {
        Self::from_values(self.values().map(|v| v * factor))
    }

    /// `pair 1.2, bond 3.4, ...`, one decimal.
    pub fn text(&self) -> String {
        Self::NAMES
            .iter()
            .zip(self.values())
            .filter(|(_, v)| v.is_finite())
            .map(|(name, v)| format!("{} {v:.1}", name.to_lowercase()))
            .collect::<Vec<_>>()
            .join(", ")
    }
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
    let output = UpstreamError::Output;
    let line = out
        .lines()
        .find(|l| l.starts_with(key))
        .ok_or_else(|| output(format!("no {key} line in the LAMMPS output")))?;
    let v: Vec<f64> = line
        .split_whitespace()
        .skip(1)
        .map(|t| {
            t.parse::<f64>()
                .map_err(|e| output(format!("bad {key} value {t}: {e}")))
        })
        .collect::<Result<_>>()?;
    v.try_into()
        .map_err(|_| output(format!("{key} needs 6 values")))
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
    std::fs::write(&data, write_run_data_file(&config.scene))
        .map_err(FileError::on("writing", &data))?;
    let dump = dir.join(format!("{tag}.dump"));
    let inputs = write_templates(dir).map_err(|cause| UpstreamError::Templates { cause })?;
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
    let out = lammps.run(&input, &vars, ranks, Work::steps_of(&config.scene, steps))?;
    let read = |k: usize| -> Result<Vec<Vec<f64>>> {
        Ok(read_dump(Path::new(&format!("{}.{k}", dump.display())))?)
    };
    let (d0, d1) = (read(0)?, read(1)?);
    let cols = |rows: &[Vec<f64>], c: usize| {
        rows.iter()
            .map(|r| [r[c], r[c + 1], r[c + 2]])
            .collect::<Vec<_>>()
    };
    let loop_seconds = loop_seconds(&out)?;
    Ok(StyleResult {
        forces: [cols(&d0, 0), cols(&d1, 0)],
        positions: [cols(&d0, 3), cols(&d1, 3)],
        velocities: cols(&d0, 6),
        pressure: [
            numbers(&out, "BPM_PRESSURE0")?,
            numbers(&out, "BPM_PRESSURE1")?,
        ],
        loop_seconds,
        sections: LoopSections::of_log(&out),
    })
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

/// ns per particle-step of ours and upstream on a configuration (its
/// scene squeezed to its box scale), `steps` steps, one rank, same LAMMPS,
/// same run.
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
    /// Our run's loop by section (ns per particle-step), of the fastest run.
    pub ours_sections: LoopSections,
    /// Upstream's likewise.
    pub upstream_sections: LoopSections,
}

impl SpeedRow {
    /// The row as one line of text.
    pub fn line(&self) -> String {
        format!(
            "speed {:<30} {} particles: ours {:.1} ns, upstream {:.1} ns per particle-step, ratio {:.2}",
            self.configuration, self.particles, self.ours_ns, self.upstream_ns, self.ratio
        )
    }
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
    let mut fastest = [(f64::INFINITY, LoopSections::UNTIMED); 2];
    for _ in 0..repeats.max(1) {
        for (kept, ours) in fastest.iter_mut().zip([true, false]) {
            let run = run_style(lammps, config, ours, 1.0, steps, 1, dir)?;
            if run.loop_seconds < kept.0 {
                *kept = (run.loop_seconds, run.sections);
            }
        }
    }
    let [(ours, ours_sections), (upstream, upstream_sections)] = fastest;
    let per = 1e9 / (n * steps as f64);
    Ok(SpeedRow {
        configuration: config.name.clone(),
        particles: n as usize,
        ours_ns: ours * per,
        upstream_ns: upstream * per,
        ratio: ours / upstream,
        ours_sections: ours_sections.scaled(per),
        upstream_sections: upstream_sections.scaled(per),
    })
}

/// The loop time (s) of the last run in LAMMPS's screen output.
fn loop_seconds(screen: &str) -> Result<f64> {
    screen
        .lines()
        .rfind(|l| l.starts_with("Loop time of"))
        .and_then(|l| l.split_whitespace().nth(3))
        .and_then(|t| t.parse::<f64>().ok())
        .ok_or_else(|| UpstreamError::Output("no loop time in the LAMMPS output".into()))
}

/// Times upstream's `bpm/spring` and our drop-in (`-sf rs`) on the block
/// pulled to fracture, `cells` fcc cells a side, for `steps` steps at a
/// pull speed that breaks bonds from about the middle of the run on;
/// alternates them `repeats` times and keeps each one's fastest run.
pub fn breaking_speed(
    lammps: &ModernLammps,
    cells: u32,
    steps: u64,
    repeats: usize,
    dir: &Path,
) -> Result<SpeedRow> {
    let case = block_tension::TensionCase {
        name: "speed",
        cells,
        steps,
        // About 6% strain by the end, past the peak (4.4%).
        speed: 0.06 * cells as f64 * std::f64::consts::SQRT_2 / (steps as f64 * 0.01),
        every: steps / 10,
        ..block_tension::tension_cases().remove(0)
    };
    let data = block_tension::make_block(lammps, &case, dir)?;
    let mut fastest = [(f64::INFINITY, LoopSections::UNTIMED, 0); 2];
    for _ in 0..repeats.max(1) {
        for (kept, styles) in fastest.iter_mut().zip([Styles::Ours, Styles::Upstream]) {
            let (trace, screen) =
                block_tension::run_tension_screen(lammps, &case, styles, 1, &data, dir)?;
            let seconds = loop_seconds(&screen)?;
            if seconds < kept.0 {
                *kept = (seconds, LoopSections::of_log(&screen), trace.broken_count());
            }
        }
    }
    let atoms = std::fs::read_to_string(&data)
        .map_err(FileError::on("reading", &data))?
        .lines()
        .find_map(|l| {
            l.strip_suffix(" atoms")
                .and_then(|n| n.trim().parse::<f64>().ok())
        })
        .ok_or_else(|| UpstreamError::Output(format!("no atom count in {}", data.display())))?;
    let [(ours, ours_sections, ours_broken), (upstream, upstream_sections, upstream_broken)] =
        fastest;
    let per = 1e9 / (atoms * steps as f64);
    Ok(SpeedRow {
        configuration: format!(
            "block pulled to fracture, {cells} cells, bonds broken {ours_broken} (ours) {upstream_broken} (upstream)"
        ),
        particles: atoms as usize,
        ours_ns: ours * per,
        upstream_ns: upstream * per,
        ratio: ours / upstream,
        ours_sections: ours_sections.scaled(per),
        upstream_sections: upstream_sections.scaled(per),
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

/// What `bpm upstream-check` compares.
#[derive(Clone, Debug)]
pub struct UpstreamOptions {
    /// Box side of the contact solid (d).
    pub size: f64,
    /// Grain radius of the grain pair (d).
    pub grain_radius: f64,
    /// Steps of the trajectories (and of the speed runs).
    pub steps: u64,
    /// Box side of the solid for the speed comparison (0: no speed runs).
    pub speed_size: f64,
    /// Seed of the scenes.
    pub seed: u64,
}

impl UpstreamOptions {
    /// Checks every option; the message names it.
    pub fn validate(&self) -> std::result::Result<(), crate::options::InvalidOption> {
        use crate::options::InvalidOption;
        let side = |v: f64| v.is_finite() && v > 3.0 && v <= crate::scene::builders::bulk::MAX_SIZE;
        if !side(self.size) {
            return Err(InvalidOption::new(
                "--size",
                format!("must be above 3 and at most 400 (d), got {}", self.size),
            ));
        }
        if !(self.speed_size == 0.0 || side(self.speed_size)) {
            return Err(InvalidOption::new(
                "--speed-size",
                format!(
                    "must be 0 (no speed runs) or above 3 (d), got {}",
                    self.speed_size
                ),
            ));
        }
        if !(self.grain_radius.is_finite() && self.grain_radius >= 2.0 && self.grain_radius <= 50.0)
        {
            return Err(InvalidOption::new(
                "--grain-radius",
                format!("must be in [2, 50] (d), got {}", self.grain_radius),
            ));
        }
        if self.steps == 0 {
            return Err(InvalidOption::new("--steps", "must be at least 1"));
        }
        Ok(())
    }
}

/// What [`run_upstream_check`] measured and wrote.
#[derive(Clone, Debug)]
pub struct UpstreamReport {
    /// The modern LAMMPS and plugin used.
    pub lammps: ModernLammps,
    /// The verdict rows, in order.
    pub rows: Vec<UpstreamRow>,
    /// The speed comparisons.
    pub speeds: Vec<SpeedRow>,
    /// `upstream.json`.
    pub json: PathBuf,
}

impl UpstreamReport {
    /// Rows that failed.
    pub fn failures(&self) -> usize {
        self.rows.iter().filter(|r| !r.pass).count()
    }

    /// Rows judged against a tolerance (not documented differences).
    pub fn judged(&self) -> usize {
        self.rows.iter().filter(|r| r.tolerance.is_some()).count()
    }
}

/// `bpm upstream-check`: finds the modern LAMMPS and our plugin for it
/// ([`ModernLammps::locate`]), compares ours and upstream on the contact
/// solid and the grain pair at a_B = 0, -0.5 and 1 on 1 and 2 ranks, with
/// pair damping at a_B = -0.5, times both, and writes `upstream.json` into
/// `output` (LAMMPS files in `output/lammps/`); `command` is recorded.
/// `log` receives the lines of the verdict table (header first) and the
/// speed lines as they are measured. Failed comparisons are rows, not
/// errors ([`UpstreamReport::failures`]).
pub fn run_upstream_check(
    opts: &UpstreamOptions,
    output: &Path,
    command: &str,
    log: &mut dyn FnMut(&str),
) -> Result<UpstreamReport> {
    opts.validate()?;
    let lammps = ModernLammps::locate()?;
    let work = output.join("lammps");
    std::fs::create_dir_all(&work).map_err(FileError::on("creating", &work))?;
    log(&row_header());
    let mut rows = Vec::new();
    let mut logged = 0;
    let mut flush = |rows: &Vec<UpstreamRow>| {
        for r in &rows[logged..] {
            log(&r.line());
        }
        logged = rows.len();
    };
    for a_b in [0.0, -0.5, 1.0] {
        for config in configurations(opts.size, opts.grain_radius, opts.seed, a_b)? {
            for ranks in [1, 2] {
                compare_configuration(&lammps, &config, 0.0, opts.steps, ranks, &work, &mut rows)?;
                flush(&rows);
            }
        }
    }
    // Pair damping: upstream multiplies it by 1 - (r/r_c)^8, we do not
    // (docs/model.md's damping is the plain gamma (v_ij . n) n).
    for config in configurations(opts.size, opts.grain_radius, opts.seed, -0.5)? {
        compare_configuration(&lammps, &config, 1.0, 0, 1, &work, &mut rows)?;
        flush(&rows);
    }
    // Bonds that break and yield: one bond pulled to failure, and a block
    // pulled to fracture (upstream's decks, run unchanged on our styles).
    for case in bond_pull::pull_cases() {
        bond_pull::compare_pull(&lammps, &case, &work, &mut rows)?;
        flush(&rows);
    }
    for case in block_tension::tension_cases() {
        block_tension::compare_tension(&lammps, &case, &work, &mut rows)?;
        flush(&rows);
    }
    crate::verify::upstream::impact::compare_impact(&lammps, &work, &mut rows)?;
    flush(&rows);
    let mut speeds = Vec::new();
    if opts.speed_size > 0.0 {
        // The squeeze sets the volume strain, which picks the cube-root
        // path: 4.5% (compaction-like) and 0.6% (calibration-like).
        for (a_b, squeeze) in [(0.0, 0.985), (-0.5, 0.985), (-0.5, 0.998)] {
            let config = Configuration {
                name: format!(
                    "contact solid L={} a_B={a_b} squeeze {squeeze}",
                    opts.speed_size
                ),
                scene: contact_solid_reference(opts.speed_size, opts.seed, a_b)?,
                squeeze,
            };
            let row = speed(&lammps, &config, opts.steps, 3, &work)?;
            log(&row.line());
            speeds.push(row);
        }
        // Bonds that break: upstream's bpm/spring against our drop-in.
        let row = breaking_speed(&lammps, 10, 4000, 3, &work)?;
        log(&row.line());
        speeds.push(row);
    }
    let report = serde_json::json!({
        "program": "bpm upstream-check",
        "version": crate::VERSION,
        "command": command,
        "lammps": lammps,
        "size": opts.size, "grain_radius": opts.grain_radius, "steps": opts.steps, "seed": opts.seed,
        "tolerances": crate::verify::tolerances::TOLERANCES
            .iter()
            .filter(|t| t.observable.starts_with(TOLERANCE_PREFIX))
            .map(|t| serde_json::json!({
                "observable": t.observable, "tolerance": t.tolerance, "why": t.why,
            }))
            .collect::<Vec<_>>(),
        "rows": rows,
        "speed": speeds,
    });
    let json = output.join("upstream.json");
    crate::studies::output::write_json(&json, &report)
        .map_err(|e| UpstreamError::Report(Box::new(e)))?;
    Ok(UpstreamReport {
        lammps,
        rows,
        speeds,
        json,
    })
}

#[cfg(test)]
mod tests {
    use super::LoopSections;

    #[test]
    fn loop_sections_are_read_from_the_last_timing_breakdown() {
        // Two runs: only the second table counts; Bond is missing in it.
        let log = "\
MPI task timing breakdown:
Section |  min time  |  avg time  |  max time  |%varavg| %total
---------------------------------------------------------------
Pair    | 9          | 9          | 9          |   0.0 | 90
Loop time of 2 on 1 procs for 10 steps with 5 atoms
MPI task timing breakdown:
Section |  min time  |  avg time  |  max time  |%varavg| %total
---------------------------------------------------------------
Pair    | 0.5        | 0.625      | 0.75       |   0.0 | 50.00
Neigh   | 0.125      | 0.25       | 0.375      |   0.0 | 20.00
Comm    | 0.0625     | 0.0625     | 0.0625     |   0.0 |  5.00
Output  | 1e-05      | 1e-05      | 1e-05      |   0.0 |  0.00
Modify  | 0.25       | 0.25       | 0.25       |   0.0 | 20.00
Other   |            | 0.0625     |            |       |  5.00

Nlocal:              5 ave           5 max           5 min
";
        let s = LoopSections::of_log(log);
        assert_eq!(
            (s.pair, s.neigh, s.comm, s.output, s.modify, s.other),
            (0.625, 0.25, 0.0625, 1e-5, 0.25, 0.0625)
        );
        assert!(s.bond.is_nan());
        assert_eq!(
            s.scaled(2.0).text(),
            "pair 1.2, neigh 0.5, comm 0.1, modify 0.5, output 0.0, other 0.1"
        );
        let none = LoopSections::of_log("Loop time of 1 on 1 procs");
        assert!([none.pair, none.bond, none.other]
            .iter()
            .all(|v| v.is_nan()));
    }
}
