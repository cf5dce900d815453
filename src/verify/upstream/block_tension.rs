//! A bonded block pulled apart to fracture (`lammps_inputs/block_tension/`),
//! run unchanged with upstream LAMMPS's styles and with ours through the
//! plugin (`-sf rs` picks `bpm/spring/rs` for the deck's `bpm/spring`):
//! stress and broken bonds against strain, and the set of broken bonds on
//! 1 and 4 ranks.
//!
//! The block is made once (`block.in`, one rank) and read by every run, so
//! that all start from the same atoms with the same IDs. The native engine
//! reads the same data file and pulls it with clamps moving as the deck's
//! `fix move linear` ([`native_tension`]).

use super::{ModernLammps, Result, Styles, UpstreamError, UpstreamRow};
use crate::engine::{BpmModel, Clamp, StageDrivers, System};
use crate::file_error::FileError;
use crate::kernels::{BondCoeffs, BondFailure, PairCoeffs};
use crate::lammps::write_templates;
use crate::scene::datafile::read_data_file;
use crate::scene::{build_system, ForceField};
use crate::verify::launch::Work;
use crate::verify::tolerances::tolerance;
use std::collections::BTreeSet;
use std::path::{Path, PathBuf};

/// A block, its styles and the pull.
#[derive(Clone, Debug)]
pub struct TensionCase {
    /// Name in the verdict table.
    pub name: &'static str,
    /// Upstream's `bond_style` words (our `-sf rs` takes the same).
    pub bond_style: &'static str,
    /// `bond_coeff` after the type.
    pub bond_coeffs: &'static str,
    /// Upstream's `pair_style` words.
    pub pair_style: &'static str,
    /// `pair_coeff` after `* *`.
    pub pair_coeffs: &'static str,
    /// `special_bonds` weights (all 1 with `overlay/pair yes`).
    pub special_bonds: &'static str,
    /// `newton_bond` on (needs `overlay/pair yes` with breaking).
    pub newton_bond: bool,
    /// Block edge in fcc cells.
    pub cells: u32,
    /// Largest random displacement of a site (d).
    pub jiggle: f64,
    /// Seed of the displacements.
    pub seed: u64,
    /// Timestep (tau).
    pub dt: f64,
    /// Speed of the top layer (d/tau).
    pub speed: f64,
    /// Steps of the pull.
    pub steps: u64,
    /// Steps between rows.
    pub every: u64,
}

impl TensionCase {
    /// The case in the native engine's terms, read from the deck's own
    /// words so that both run the same numbers; `None` for words it does
    /// not follow: a keyword other than `volume/factor` and
    /// `overlay/pair`, or coefficients it cannot read.
    pub fn native_force_field(&self) -> Option<ForceField> {
        // The style and only the keywords the native engine follows (the
        // others, such as smooth no or normalize yes, would go unread).
        let mut words = self.bond_style.split_whitespace();
        let plastic = match words.next()? {
            "bpm/spring" => false,
            "bpm/spring/plastic" => true,
            _ => return None,
        };
        let keywords: Vec<&str> = words.collect();
        let (mut volume, mut overlay) = (false, false);
        for pair in keywords.chunks(2) {
            let flag = match pair[0] {
                "volume/factor" => &mut volume,
                "overlay/pair" => &mut overlay,
                _ => return None,
            };
            *flag = match pair.get(1).copied()? {
                "yes" => true,
                "no" => false,
                _ => return None,
            };
        }
        let numbers = |words: &str| -> Option<Vec<f64>> {
            words.split_whitespace().map(|w| w.parse().ok()).collect()
        };
        // k epsilon_c gamma [epsilon_p] [a_v]
        let bond = numbers(self.bond_coeffs)?;
        let expected = 3 + usize::from(plastic) + usize::from(volume);
        let [k, eps_c, gamma] = [*bond.first()?, *bond.get(1)?, *bond.get(2)?];
        if bond.len() != expected {
            return None;
        }
        let mut field = ForceField::paper(0.0);
        field.overlay_pair = overlay;
        field.bond = BondCoeffs {
            k,
            a: if volume { *bond.last()? } else { 0.0 },
            gamma,
        };
        field.bond_failure = Some(BondFailure {
            plastic_strain: if plastic { Some(*bond.get(3)?) } else { None },
            ..BondFailure::breaking(eps_c)
        });
        // k r_c gamma [k_a]
        let anharmonic = match self.pair_style.split_whitespace().collect::<Vec<_>>()[..] {
            ["bpm/spring"] => false,
            ["bpm/spring", "anharmonic", yes_no] => yes_no == "yes",
            _ => return None,
        };
        let pair = numbers(self.pair_coeffs)?;
        if pair.len() != 3 + usize::from(anharmonic) {
            return None;
        }
        field.pair = Some(PairCoeffs {
            k: pair[0],
            d: pair[1],
            a: if anharmonic { pair[3] } else { 0.0 },
            gamma: pair[2],
        });
        Some(field)
    }
}

/// The blocks compared: a multibody spring block (`volume/factor`, bonds
/// smoothed and breaking at 4% strain), the same with its bonds overlaid
/// by the contact and `newton_bond on`, and a plastic block (bonds
/// yielding at 1%, upstream's plastic style has no volume term), pulled
/// through their peak stress into fracture.
pub fn tension_cases() -> Vec<TensionCase> {
    let volume = TensionCase {
        name: "block tension volume/factor",
        bond_style: "bpm/spring volume/factor yes",
        bond_coeffs: "1.0 0.04 0.5 -0.5",
        pair_style: "bpm/spring anharmonic yes",
        pair_coeffs: "1.0 1.0 0.5 50.0",
        special_bonds: "lj 0 1 1 coul 1 1 1",
        newton_bond: false,
        cells: 4,
        jiggle: 0.05,
        seed: 7,
        dt: 0.01,
        speed: 0.01,
        steps: 4000,
        every: 20,
    };
    let overlay = TensionCase {
        name: "block tension overlay/pair newton_bond",
        bond_style: "bpm/spring volume/factor yes overlay/pair yes",
        // Contacts shorter than the shortest bond (0.9 d), so that the
        // bonded block starts unstressed.
        pair_coeffs: "1.0 0.85 0.5 50.0",
        special_bonds: "lj/coul 1 1 1",
        newton_bond: true,
        ..volume.clone()
    };
    let plastic = TensionCase {
        name: "block tension plastic",
        bond_style: "bpm/spring/plastic",
        bond_coeffs: "1.0 0.04 0.5 0.01",
        ..volume.clone()
    };
    vec![volume, overlay, plastic]
}

/// Rows of one run: stress and bonds left against strain, and the broken
/// bonds.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct TensionTrace {
    /// Steps of the rows.
    pub step: Vec<u64>,
    /// Strain of the gauge (top against bottom layer).
    pub strain: Vec<f64>,
    /// Tensile stress on the top layer (k/d).
    pub stress: Vec<f64>,
    /// Bonds left.
    pub bonds: Vec<u64>,
    /// Each broken bond once: (step, smaller atom ID, larger atom ID).
    pub broken: BTreeSet<(u64, u64, u64)>,
}

impl TensionTrace {
    /// The first row with fewer bonds than the first.
    pub fn first_break_row(&self) -> Option<usize> {
        let start = *self.bonds.first()?;
        self.bonds.iter().position(|&b| b < start)
    }

    /// The step the first bond broke (from the broken bonds' record).
    pub fn first_break_step(&self) -> Option<u64> {
        self.broken.first().map(|b| b.0)
    }

    /// The largest stress.
    pub fn peak_stress(&self) -> f64 {
        self.stress.iter().fold(f64::NEG_INFINITY, |m, &s| m.max(s))
    }

    /// Bonds broken by the last row.
    pub fn broken_count(&self) -> u64 {
        match (self.bonds.first(), self.bonds.last()) {
            (Some(a), Some(b)) => a - b,
            _ => 0,
        }
    }
}

/// Writes the block of `case` into `dir` (one rank); returns the data file.
pub fn make_block(lammps: &ModernLammps, case: &TensionCase, dir: &Path) -> Result<PathBuf> {
    let inputs = write_templates(dir).map_err(|cause| UpstreamError::Templates { cause })?;
    let data = dir.join(format!(
        "block-{}-{}-{}.data",
        case.cells, case.jiggle, case.seed
    ));
    let vars = [
        ("n", case.cells.to_string()),
        ("jiggle", format!("{:.17e}", case.jiggle)),
        ("seed", case.seed.to_string()),
        ("data", data.display().to_string()),
    ];
    let work = Work {
        particles: 4 * (case.cells as usize + 1).pow(3),
        steps: 0,
    };
    lammps.run_styles(
        Styles::Upstream,
        &inputs.join("block_tension/block.in"),
        &vars,
        1,
        work,
    )?;
    Ok(data)
}

/// One pull of `case` from `data` with `styles` on `ranks` ranks.
pub fn run_tension(
    lammps: &ModernLammps,
    case: &TensionCase,
    styles: Styles,
    ranks: usize,
    data: &Path,
    dir: &Path,
) -> Result<TensionTrace> {
    Ok(run_tension_screen(lammps, case, styles, ranks, data, dir)?.0)
}

/// [`run_tension`] and LAMMPS's screen output (its timings).
pub fn run_tension_screen(
    lammps: &ModernLammps,
    case: &TensionCase,
    styles: Styles,
    ranks: usize,
    data: &Path,
    dir: &Path,
) -> Result<(TensionTrace, String)> {
    let inputs = write_templates(dir).map_err(|cause| UpstreamError::Templates { cause })?;
    let tag = format!(
        "{}-{}-np{ranks}",
        case.name.replace([' ', '/'], "_"),
        styles.name()
    );
    let out = dir.join(format!("{tag}.txt"));
    let broken_out = dir.join(format!("{tag}.broken"));
    let vars = [
        ("data", data.display().to_string()),
        ("bstyle", case.bond_style.to_string()),
        ("bcoeff", case.bond_coeffs.to_string()),
        ("pstyle", case.pair_style.to_string()),
        ("pcoeff", case.pair_coeffs.to_string()),
        ("specials", case.special_bonds.to_string()),
        (
            "newton_bond",
            if case.newton_bond { "on" } else { "off" }.into(),
        ),
        ("dt", format!("{:.17e}", case.dt)),
        ("speed", format!("{:.17e}", case.speed)),
        ("steps", case.steps.to_string()),
        ("every", case.every.to_string()),
        ("out", out.display().to_string()),
        ("broken_out", broken_out.display().to_string()),
    ];
    let work = Work {
        particles: 4 * (case.cells as usize + 1).pow(3),
        steps: case.steps,
    };
    let input = inputs.join("block_tension/tension.in");
    let screen = lammps.run_styles(styles, &input, &vars, ranks, work)?;
    let read = |path: &Path| std::fs::read_to_string(path).map_err(FileError::on("reading", path));
    let bad = |path: &Path, e: String| UpstreamError::Output(format!("{}: {e}", path.display()));
    let mut trace = parse_rows(&read(&out)?).map_err(|e| bad(&out, e))?;
    trace.broken = parse_broken(&read(&broken_out)?).map_err(|e| bad(&broken_out, e))?;
    Ok((trace, screen))
}

/// The pull of `case` in the native engine, from the deck's data file:
/// the layers within 0.5 d of the bottom and top held and moved as the
/// deck's `fix move linear` moves them, the rest integrated, rows every
/// `case.every` steps as the deck's `fix print` writes them, and each
/// broken bond with its step and atom IDs. `None` for a case the native
/// engine does not run ([`TensionCase::native_force_field`]).
pub fn native_tension(case: &TensionCase, data: &Path) -> Result<Option<TensionTrace>> {
    let Some(field) = case.native_force_field() else {
        return Ok(None);
    };
    let bad = |e: String| UpstreamError::Output(format!("native block {}: {e}", case.name));
    let scene = read_data_file(data, [false; 3], field, 1).map_err(|e| bad(e.to_string()))?;
    let ids: Vec<u64> = match &scene.particles.ids {
        Some(ids) => ids.clone(),
        None => (1..=scene.particles.positions.len() as u64).collect(),
    };
    let mut sys = build_system(&scene, 1);
    let x = &sys.particles.x;
    let bound = |d: usize| {
        x.iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), p| {
                (lo.min(p[d]), hi.max(p[d]))
            })
    };
    let ((x_lo, x_hi), (y_lo, y_hi), (z_lo, z_hi)) = (bound(0), bound(1), bound(2));
    // The deck's regions are closed: a site on the plane belongs to it.
    let layer = |inside: &dyn Fn(f64) -> bool| -> Vec<usize> {
        (0..x.len()).filter(|&i| inside(x[i][2])).collect()
    };
    let top = layer(&|z| z >= z_hi - 0.5);
    let bottom = layer(&|z| z <= z_lo + 0.5);
    let clamp = |group: &[usize], v: f64| {
        Clamp::new(group.to_vec(), [0.0, 0.0, v], x).map_err(|e| bad(e.to_string()))
    };
    let drivers = StageDrivers {
        dt: case.dt,
        clamps: vec![clamp(&bottom, 0.0)?, clamp(&top, case.speed)?],
        ..Default::default()
    };
    let area = (x_hi - x_lo) * (y_hi - y_lo);
    let centre = |sys: &System, group: &[usize]| {
        group.iter().map(|&i| sys.particles.x[i][2]).sum::<f64>() / group.len() as f64
    };
    let gauge0 = centre(&sys, &top) - centre(&sys, &bottom);
    let record = |sys: &System, step: u64, trace: &mut TensionTrace| {
        let pull = drivers.clamps[1].force(&sys.particles.f)[2];
        let bonds = sys.model_as::<BpmModel>().map_or(0, |m| m.bonds().len());
        trace.step.push(step);
        trace
            .strain
            .push((centre(sys, &top) - centre(sys, &bottom)) / gauge0 - 1.0);
        trace.stress.push(-pull / area);
        trace.bonds.push(bonds as u64);
    };
    // Bonds broken since the last call, at `step` (a set-up's at 0).
    let mut seen = 0;
    let mut note_breaks = |sys: &System, step: u64, trace: &mut TensionTrace| {
        let broken = sys
            .model_as::<BpmModel>()
            .map_or(&[][..], |m| m.broken_bonds());
        for &[i, j] in &broken[seen..] {
            let (a, b) = (ids[i], ids[j]);
            trace.broken.insert((step, a.min(b), a.max(b)));
        }
        seen = broken.len();
    };
    sys.setup(&drivers).map_err(|e| bad(e.to_string()))?;
    let mut trace = TensionTrace::default();
    note_breaks(&sys, 0, &mut trace);
    record(&sys, 0, &mut trace);
    let stage_box = sys.simbox.clone();
    for step in 1..=case.steps {
        sys.step(&drivers, step, &stage_box)
            .map_err(|e| bad(e.to_string()))?;
        note_breaks(&sys, step, &mut trace);
        if step % case.every == 0 {
            record(&sys, step, &mut trace);
        }
    }
    Ok(Some(trace))
}

/// The rows of `fix print` (`step strain stress bonds`).
fn parse_rows(text: &str) -> std::result::Result<TensionTrace, String> {
    let mut trace = TensionTrace::default();
    for line in text.lines().filter(|l| !l.starts_with('#')) {
        let v: Vec<&str> = line.split_whitespace().collect();
        let [step, strain, stress, bonds] = v[..] else {
            return Err(format!("a row of {} values: {line}", v.len()));
        };
        let bad = |what: &str| format!("{what} in: {line}");
        trace.step.push(step.parse().map_err(|_| bad("a step"))?);
        trace
            .strain
            .push(strain.parse().map_err(|_| bad("a strain"))?);
        trace
            .stress
            .push(stress.parse().map_err(|_| bad("a stress"))?);
        let bonds: f64 = bonds.parse().map_err(|_| bad("a bond count"))?;
        trace.bonds.push(bonds.round() as u64);
    }
    Ok(trace)
}

/// The entries of the local dump (`step id1 id2` after each `ITEM:
/// ENTRIES` line), each bond once: with `newton_bond off`, a bond whose
/// atoms sit on two ranks breaks, and is recorded, on both.
fn parse_broken(text: &str) -> std::result::Result<BTreeSet<(u64, u64, u64)>, String> {
    let mut broken = BTreeSet::new();
    let mut entries = false;
    for line in text.lines() {
        if line.starts_with("ITEM:") {
            entries = line.starts_with("ITEM: ENTRIES");
            continue;
        }
        if !entries {
            continue;
        }
        let v: Vec<u64> = line
            .split_whitespace()
            .map(|w| w.parse::<f64>().map(|x| x as u64))
            .collect::<std::result::Result<_, _>>()
            .map_err(|_| format!("a broken bond row of numbers: {line}"))?;
        let [step, a, b] = v[..] else {
            return Err(format!("a broken bond row of 3 values: {line}"));
        };
        broken.insert((step, a.min(b), a.max(b)));
    }
    Ok(broken)
}

/// The four judgements of a pull against upstream's: the largest stress
/// difference up to upstream's first break over upstream's peak, the
/// first break step's difference, the peak stress's relative difference
/// and the broken count's; each with the tolerance it is judged by.
fn against_upstream(
    trace: &TensionTrace,
    upstream: &TensionTrace,
) -> [(&'static str, f64, &'static str); 4] {
    let peak = upstream.peak_stress();
    let count = upstream.broken_count() as f64;
    let first = upstream.first_break_row().unwrap_or(upstream.step.len());
    let before = (0..first).fold(0.0f64, |m, k| {
        m.max((trace.stress[k] - upstream.stress[k]).abs())
    }) / peak;
    let first_dev = match (trace.first_break_step(), upstream.first_break_step()) {
        (Some(a), Some(b)) => a.abs_diff(b) as f64,
        _ => f64::INFINITY,
    };
    [
        ("stress up to the first break", before, "stress"),
        ("first break step", first_dev, "first break"),
        (
            "peak stress",
            (trace.peak_stress() - peak).abs() / peak,
            "peak stress",
        ),
        (
            "broken bonds at the end",
            (trace.broken_count() as f64 - count).abs() / count,
            "broken count",
        ),
    ]
}

/// Compares `case` with upstream's styles, ours on one rank and the native
/// engine (where it runs the case), and ours on 1 and 4 ranks; pushes the
/// verdict rows (tolerances `upstream block tension ...`).
pub fn compare_tension(
    lammps: &ModernLammps,
    case: &TensionCase,
    dir: &Path,
    rows: &mut Vec<UpstreamRow>,
) -> Result<()> {
    let data = make_block(lammps, case, dir)?;
    let upstream = run_tension(lammps, case, Styles::Upstream, 1, &data, dir)?;
    let ours = run_tension(lammps, case, Styles::Ours, 1, &data, dir)?;
    let ours4 = run_tension(lammps, case, Styles::Ours, 4, &data, dir)?;
    // A native engine that fails is a failing row, not the end of the
    // plugin's rows.
    let (native, native_failure) = match native_tension(case, &data) {
        Ok(trace) => (trace, None),
        Err(e) => (None, Some(e.to_string())),
    };
    if let Some(why) = native_failure {
        rows.push(UpstreamRow {
            configuration: case.name.into(),
            ranks: 1,
            pair_gamma: 0.0,
            observable: format!("native: failed: {why}"),
            max_deviation: f64::INFINITY,
            tolerance: Some(0.0),
            pass: false,
        });
    }
    let native_steps = native.as_ref().map_or(&upstream.step, |n| &n.step);
    if ours.step != upstream.step || ours4.step != upstream.step || *native_steps != upstream.step {
        return Err(UpstreamError::Output(format!(
            "{}: the runs printed different steps",
            case.name
        )));
    }
    let mut push = |ranks: usize, observable: &str, dev: f64, what: &str| {
        let tol = tolerance(&format!("{} block tension {what}", super::TOLERANCE_PREFIX));
        rows.push(UpstreamRow {
            configuration: case.name.into(),
            ranks,
            pair_gamma: 0.0,
            observable: observable.into(),
            max_deviation: dev,
            tolerance: Some(tol),
            pass: dev <= tol,
        });
    };
    if upstream.broken_count() == 0 {
        return Err(UpstreamError::Output(format!(
            "{}: no bond broke in upstream's run; pull further",
            case.name
        )));
    }
    for (engine, trace) in [("", Some(&ours)), ("native: ", native.as_ref())] {
        let Some(trace) = trace else { continue };
        let judged = against_upstream(trace, &upstream);
        for (observable, dev, what) in judged {
            push(1, &format!("{engine}{observable}"), dev, what);
        }
    }
    let differ = ours.broken.symmetric_difference(&ours4.broken).count();
    push(
        4,
        "broken bonds, ours on 4 ranks against 1",
        differ as f64,
        "rank count",
    );
    // A bond broken on one of two ranks would still be in the set above;
    // the bonds left, counted over every rank's atoms, would not match.
    let counts = ours
        .bonds
        .iter()
        .zip(&ours4.bonds)
        .map(|(a, b)| a.abs_diff(*b))
        .max()
        .unwrap_or(0);
    push(
        4,
        "bonds left at every row, 4 ranks against 1",
        counts as f64,
        "rank count",
    );
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rows_and_broken_bonds_are_read() {
        let trace = parse_rows("# Fix print\n0 0 0 10\n20 0.1 0.5 10\n40 0.2 0.7 8\n").unwrap();
        assert_eq!(trace.first_break_row(), Some(2));
        assert_eq!(trace.peak_stress(), 0.7);
        assert_eq!(trace.broken_count(), 2);
        assert!(parse_rows("0 0 x 10\n").unwrap_err().contains("a stress"));
        let dump = "ITEM: TIMESTEP\n40\nITEM: NUMBER OF ENTRIES\n3\nITEM: ENTRIES c_1 c_2 c_3\n\
                    40 7 3\n40 3 7\n40 5 9\nITEM: TIMESTEP\n60\nITEM: NUMBER OF ENTRIES\n0\n\
                    ITEM: ENTRIES c_1 c_2 c_3\n";
        let broken = parse_broken(dump).unwrap();
        assert_eq!(
            broken.iter().copied().collect::<Vec<_>>(),
            vec![(40, 3, 7), (40, 5, 9)]
        );
        let trace = TensionTrace { broken, ..trace };
        assert_eq!(trace.first_break_step(), Some(40));
        assert!(parse_broken("ITEM: ENTRIES\n1 2\n").is_err());
    }
}
