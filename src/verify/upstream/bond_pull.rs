//! One bond pulled to failure, in the native engine and in upstream LAMMPS
//! (`lammps_inputs/bond_pull/pull.in`): the force against strain with and
//! without smoothing, the step the bond breaks, and the plastic plateau
//! and unloading of `bpm/spring/plastic`.
//!
//! Atom 1 is held and atom 2 moved along x in legs of constant speed; the
//! native engine evaluates its forces at the same prescribed positions and
//! velocities, so both see the same bond history step by step.

use super::{ModernLammps, Result, Styles, UpstreamError, UpstreamRow};
use crate::engine::{BpmModel, StageDrivers, System};
use crate::file_error::FileError;
use crate::kernels::{BondCoeffs, BondFailure, PairCoeffs};
use crate::lammps::write_templates;
use crate::scene::{build_system, ForceField, Scene};
use crate::verify::launch::Work;
use crate::verify::tolerances::tolerance;
use std::path::Path;

/// Time step of every pull (tau).
const DT: f64 = 0.01;

/// The bond's length at the start (d), as `pull.in` creates it.
const R0: f64 = 1.0;

/// A bond style, its coefficients and the legs of the pull.
#[derive(Clone, Debug)]
pub struct PullCase {
    /// Name in the verdict table.
    pub name: &'static str,
    /// Bond stiffness `k`.
    pub k: f64,
    /// Bond damping `gamma`.
    pub gamma: f64,
    /// How the bond breaks and yields.
    pub failure: BondFailure,
    /// Legs: speed of atom 2 (d/tau) and steps.
    pub legs: Vec<(f64, u64)>,
}

impl PullCase {
    /// Upstream's `bond_style` with its keywords.
    pub fn bond_style(&self) -> String {
        let f = &self.failure;
        let yes_no = |b: bool| if b { "yes" } else { "no" };
        format!(
            "{} break {} smooth {} normalize {}",
            if f.plastic_strain.is_some() {
                "bpm/spring/plastic"
            } else {
                "bpm/spring"
            },
            yes_no(f.breaks),
            yes_no(f.smooth),
            yes_no(f.normalize)
        )
    }

    /// Upstream's `bond_coeff` after the type: `k epsilon_c gamma
    /// [epsilon_p]`.
    pub fn bond_coeffs(&self) -> String {
        let mut c = format!(
            "{:.17e} {:.17e} {:.17e}",
            self.k, self.failure.critical_strain, self.gamma
        );
        if let Some(eps_p) = self.failure.plastic_strain {
            c.push_str(&format!(" {eps_p:.17e}"));
        }
        c
    }

    fn steps(&self) -> u64 {
        self.legs.iter().map(|l| l.1).sum()
    }
}

/// The pulls compared: a plain and a smoothed damped spring to failure,
/// and a plastic bond stretched, pushed back and pulled to failure. The
/// speed keeps every critical strain off a step's exact position.
pub fn pull_cases() -> Vec<PullCase> {
    let v = 0.0123;
    let spring = |smooth| BondFailure {
        smooth,
        ..BondFailure::breaking(0.1)
    };
    vec![
        PullCase {
            name: "bond pull spring",
            k: 1.0,
            gamma: 0.5,
            failure: spring(false),
            legs: vec![(v, 1200)],
        },
        PullCase {
            name: "bond pull spring smooth",
            k: 1.0,
            gamma: 0.5,
            failure: spring(true),
            legs: vec![(v, 1200)],
        },
        PullCase {
            name: "bond pull plastic",
            k: 2.0,
            gamma: 0.0,
            failure: BondFailure {
                smooth: false,
                plastic_strain: Some(0.05),
                ..BondFailure::breaking(0.3)
            },
            legs: vec![(v, 1200), (-v, 1600), (v, 3000)],
        },
    ]
}

/// Each step's bond length, force on atom 1 along x, and bonds left.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct PullTrace {
    /// Steps, from 0.
    pub step: Vec<u64>,
    /// Bond length (d).
    pub r: Vec<f64>,
    /// Force on atom 1 along x (positive: towards atom 2).
    pub force: Vec<f64>,
    /// Bonds left (1 or 0).
    pub bonds: Vec<u32>,
}

impl PullTrace {
    /// The first step with no bond left.
    pub fn break_step(&self) -> Option<u64> {
        self.step
            .iter()
            .zip(&self.bonds)
            .find(|(_, &b)| b == 0)
            .map(|(&s, _)| s)
    }
}

/// Two particles 1 d apart, bonded, in a closed box; contacts as
/// upstream's `pair_style bpm/spring` with `pair_coeff * * 1 1 0`.
fn pull_scene(case: &PullCase) -> Scene {
    let mut force_field = ForceField::paper(0.0);
    force_field.bond = BondCoeffs {
        k: case.k,
        a: 0.0,
        gamma: case.gamma,
    };
    force_field.pair = Some(PairCoeffs {
        k: 1.0,
        d: 1.0,
        a: 0.0,
        gamma: 0.0,
    });
    force_field.bond_failure = Some(case.failure);
    // A list that never needs rebuilding over the pull's reach.
    force_field.skin = 2.0;
    let scene = serde_json::json!({
        "seed": 1,
        "box": {"lo": [-4, -4, -4], "lengths": [8, 8, 8], "periodic": [false, false, false]},
        "particles": {"positions": [[0.0, 0.0, 0.0], [R0, 0.0, 0.0]]},
        "bonds": {"pairs": [[0, 1]]},
        "force_field": force_field,
        "stages": [{"name": "pull", "steps": case.steps(), "dt": DT}]
    });
    serde_json::from_value(scene).expect("a valid pull scene")
}

/// The pull in the native engine: forces evaluated at each step's
/// prescribed positions and velocities.
pub fn native_pull(case: &PullCase) -> PullTrace {
    let scene = pull_scene(case);
    let mut sys = build_system(&scene, 1);
    let drivers = StageDrivers {
        dt: DT,
        ..Default::default()
    };
    sys.setup(&drivers)
        .expect("two particles in a closed box set up");
    let mut trace = PullTrace::default();
    record(&sys, 0, &mut trace);
    let mut step = 0;
    for &(speed, steps) in &case.legs {
        let start = sys.particles.x[1];
        sys.particles.v[1] = [speed, 0.0, 0.0];
        for n in 1..=steps {
            sys.particles.x[1][0] = start[0] + speed * (n as f64 * DT);
            sys.compute_forces(&drivers, 0.0, false);
            step += 1;
            record(&sys, step, &mut trace);
        }
    }
    trace
}

fn record(sys: &System, step: u64, trace: &mut PullTrace) {
    let x = &sys.particles.x;
    let bonds = sys.model_as::<BpmModel>().map_or(0, |m| m.bonds().len());
    trace.step.push(step);
    trace.r.push(x[1][0] - x[0][0]);
    trace.force.push(sys.particles.f[0][0]);
    trace.bonds.push(bonds as u32);
}

/// The pull in LAMMPS: `pull.in` with upstream's styles, or with our
/// drop-ins (`-sf rs`).
pub fn deck_pull(
    lammps: &ModernLammps,
    case: &PullCase,
    styles: Styles,
    dir: &Path,
) -> Result<PullTrace> {
    let inputs = write_templates(dir).map_err(|cause| UpstreamError::Templates { cause })?;
    let tag = format!("{}-{}", case.name.replace(' ', "_"), styles.name());
    let out = dir.join(format!("{tag}.txt"));
    let leg = |k: usize| case.legs.get(k).copied().unwrap_or((0.0, 0));
    let mut vars = vec![
        ("bstyle", case.bond_style()),
        ("bcoeff", case.bond_coeffs()),
        ("dt", format!("{DT}")),
        ("out", out.display().to_string()),
    ];
    let names = [("v1", "n1"), ("v2", "n2"), ("v3", "n3")];
    for (k, (v, n)) in names.iter().enumerate() {
        vars.push((v, format!("{:.17e}", leg(k).0)));
        vars.push((n, leg(k).1.to_string()));
    }
    let work = Work {
        particles: 2,
        steps: case.steps(),
    };
    lammps.run_styles(styles, &inputs.join("bond_pull/pull.in"), &vars, 1, work)?;
    let text = std::fs::read_to_string(&out).map_err(FileError::on("reading", &out))?;
    parse_rows(&text).map_err(|e| UpstreamError::Output(format!("{}: {e}", out.display())))
}

/// The rows of `fix print` (`step r F bonds`), each step once (a run's
/// set-up repeats the last step of the run before).
fn parse_rows(text: &str) -> std::result::Result<PullTrace, String> {
    let mut trace = PullTrace::default();
    for line in text.lines().filter(|l| !l.starts_with('#')) {
        let v: Vec<&str> = line.split_whitespace().collect();
        let [step, r, force, bonds] = v[..] else {
            return Err(format!("a row of {} values: {line}", v.len()));
        };
        let bad = |what: &str| format!("{what} in: {line}");
        let step: u64 = step.parse().map_err(|_| bad("a step"))?;
        if trace.step.last() == Some(&step) {
            continue;
        }
        trace.step.push(step);
        trace.r.push(r.parse().map_err(|_| bad("a length"))?);
        trace.force.push(force.parse().map_err(|_| bad("a force"))?);
        let bonds: f64 = bonds.parse().map_err(|_| bad("a bond count"))?;
        trace.bonds.push(bonds.round() as u32);
    }
    Ok(trace)
}

/// Compares `case` in the native engine and in LAMMPS with our drop-in
/// styles against upstream LAMMPS; pushes its verdict rows (judged by the
/// tolerance entries `upstream bond pull ...`).
pub fn compare_pull(
    lammps: &ModernLammps,
    case: &PullCase,
    dir: &Path,
    rows: &mut Vec<UpstreamRow>,
) -> Result<()> {
    let upstream = deck_pull(lammps, case, Styles::Upstream, dir)?;
    let native = native_pull(case);
    let dropin = deck_pull(lammps, case, Styles::Ours, dir)?;
    for (engine, trace) in [("native", &native), ("plugin -sf rs", &dropin)] {
        if trace.step != upstream.step {
            return Err(UpstreamError::Output(format!(
                "{} ({engine}): upstream printed {} steps, ours {}",
                case.name,
                upstream.step.len(),
                trace.step.len()
            )));
        }
        judge_pull(case, engine, trace, &upstream, rows);
    }
    Ok(())
}

/// The rows of one engine's pull against upstream's.
fn judge_pull(
    case: &PullCase,
    engine: &str,
    ours: &PullTrace,
    upstream: &PullTrace,
    rows: &mut Vec<UpstreamRow>,
) {
    let mut push = |observable: &str, dev: f64, what: &str| {
        let tol = tolerance(&format!("{} bond pull {what}", super::TOLERANCE_PREFIX));
        rows.push(UpstreamRow {
            configuration: format!("{} ({engine})", case.name),
            ranks: 1,
            pair_gamma: 0.0,
            observable: observable.into(),
            max_deviation: dev,
            tolerance: Some(tol),
            pass: dev <= tol,
        });
    };
    let scale = upstream.force.iter().fold(0.0f64, |m, f| m.max(f.abs()));
    let force_dev = ours
        .force
        .iter()
        .zip(&upstream.force)
        .fold(0.0f64, |m, (a, b)| m.max((a - b).abs()))
        / scale;
    push("force against strain", force_dev, "forces");
    let break_dev = match (ours.break_step(), upstream.break_step()) {
        (Some(a), Some(b)) => a.abs_diff(b) as f64,
        (None, None) => 0.0,
        _ => f64::INFINITY,
    };
    push("break step", break_dev, "break step");
    if let Some(eps_p) = case.failure.plastic_strain {
        // The end of the first leg lies on the plateau k eps_p r0.
        let end = case.legs[0].1 as usize;
        let plateau = case.k * eps_p * R0;
        let dev = (ours.force[end] - plateau)
            .abs()
            .max((upstream.force[end] - plateau).abs())
            / plateau;
        push("plateau k eps_p r0", dev, "plateau");
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fix_print_rows_are_read_once_per_step() {
        let text =
            "# Fix print output for fix record\n0 1 0 1\n1 1.01 0.01 1\n1 1.01 0.01 1\n2 1.2 0 0\n";
        let trace = parse_rows(text).unwrap();
        assert_eq!(trace.step, vec![0, 1, 2]);
        assert_eq!(trace.break_step(), Some(2));
        assert!(parse_rows("0 1 x 1\n").unwrap_err().contains("a force"));
        assert!(parse_rows("0 1\n").unwrap_err().contains("2 values"));
    }

    #[test]
    fn the_native_pull_breaks_the_spring_past_its_critical_strain() {
        let case = &pull_cases()[0];
        let trace = native_pull(case);
        let at = trace.break_step().expect("it breaks") as usize;
        assert!(trace.r[at] > 1.1 && trace.r[at - 1] <= 1.1);
        assert_eq!(trace.force[at], 0.0);
        // Before: spring plus damping, k (r0 - r) - gamma v on atom 2,
        // the opposite on atom 1.
        let expected = case.k * (trace.r[500] - 1.0) + case.gamma * 0.0123;
        assert!((trace.force[500] - expected).abs() < 1e-12);
    }
}
