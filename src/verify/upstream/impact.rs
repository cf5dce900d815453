//! A projectile breaking a plate (`lammps_inputs/impact/impact.in`, written
//! like upstream LAMMPS's BPM impact example), run unchanged with
//! upstream's styles and with ours (`-sf rs`): the broken bonds against
//! time.

use super::{ModernLammps, Result, Styles, UpstreamError, UpstreamRow};
use crate::file_error::FileError;
use crate::lammps::write_templates;
use crate::verify::launch::Work;
use crate::verify::tolerances::tolerance;
use std::path::Path;

/// The impact compared: a disk of radius 12 sigma struck edge-on at 0.5
/// sigma/tau by a ball of radius 3 (plate bonds break at 4% strain, the
/// ball's at 20%), 800 steps of 0.1 tau, rows every 10 steps.
pub const IMPACT_VARS: [(&str, &str); 7] = [
    ("plate", "12"),
    ("ball", "3"),
    ("speed", "0.5"),
    ("seed", "5"),
    ("dt", "0.1"),
    ("steps", "800"),
    ("every", "10"),
];

/// Steps and bonds left of one run.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ImpactTrace {
    /// Steps of the rows.
    pub step: Vec<u64>,
    /// Bonds left.
    pub bonds: Vec<u64>,
}

impl ImpactTrace {
    /// Bonds broken by each row.
    pub fn broken(&self) -> Vec<u64> {
        let start = self.bonds.first().copied().unwrap_or(0);
        self.bonds.iter().map(|&b| start - b.min(start)).collect()
    }
}

/// One run of the impact with `styles`.
pub fn run_impact(lammps: &ModernLammps, styles: Styles, dir: &Path) -> Result<ImpactTrace> {
    let inputs = write_templates(dir).map_err(|cause| UpstreamError::Templates { cause })?;
    let out = dir.join(format!("impact-{}.txt", styles.name()));
    let mut vars: Vec<(&str, String)> = IMPACT_VARS
        .iter()
        .map(|&(k, v)| (k, v.to_string()))
        .collect();
    vars.push(("out", out.display().to_string()));
    let work = Work {
        particles: 1500,
        steps: 800,
    };
    lammps.run_styles(styles, &inputs.join("impact/impact.in"), &vars, 1, work)?;
    let text = std::fs::read_to_string(&out).map_err(FileError::on("reading", &out))?;
    parse_rows(&text).map_err(|e| UpstreamError::Output(format!("{}: {e}", out.display())))
}

/// The rows of `fix print` (`step bonds`).
fn parse_rows(text: &str) -> std::result::Result<ImpactTrace, String> {
    let mut trace = ImpactTrace::default();
    for line in text.lines().filter(|l| !l.starts_with('#')) {
        let v: Vec<&str> = line.split_whitespace().collect();
        let [step, bonds] = v[..] else {
            return Err(format!("a row of {} values: {line}", v.len()));
        };
        trace
            .step
            .push(step.parse().map_err(|_| format!("a step in: {line}"))?);
        let bonds: f64 = bonds
            .parse()
            .map_err(|_| format!("a bond count in: {line}"))?;
        trace.bonds.push(bonds.round() as u64);
    }
    Ok(trace)
}

/// Runs the impact with upstream's styles and ours; pushes the row of the
/// broken bonds against time (the largest difference over the rows, over
/// upstream's final count; tolerance `upstream impact broken bonds`).
pub fn compare_impact(
    lammps: &ModernLammps,
    dir: &Path,
    rows: &mut Vec<UpstreamRow>,
) -> Result<()> {
    let upstream = run_impact(lammps, Styles::Upstream, dir)?;
    let ours = run_impact(lammps, Styles::Ours, dir)?;
    if ours.step != upstream.step {
        return Err(UpstreamError::Output(
            "impact: the two runs printed different steps".into(),
        ));
    }
    let (theirs, mine) = (upstream.broken(), ours.broken());
    let total = theirs.last().copied().unwrap_or(0);
    if total == 0 {
        return Err(UpstreamError::Output(
            "impact: no bond broke in upstream's run".into(),
        ));
    }
    let largest = theirs
        .iter()
        .zip(&mine)
        .map(|(a, b)| a.abs_diff(*b))
        .max()
        .unwrap_or(0);
    let dev = largest as f64 / total as f64;
    let tol = tolerance(&format!("{} impact broken bonds", super::TOLERANCE_PREFIX));
    rows.push(UpstreamRow {
        configuration: format!("impact ({total} bonds broken)"),
        ranks: 1,
        pair_gamma: 1.0,
        observable: "broken bonds against time".into(),
        max_deviation: dev,
        tolerance: Some(tol),
        pass: dev <= tol,
    });
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rows_are_read_and_broken_bonds_counted_from_the_first() {
        let trace = parse_rows("# Fix print\n0 100\n10 97\n20 90\n").unwrap();
        assert_eq!(trace.broken(), vec![0, 3, 10]);
        assert!(parse_rows("0 x\n").unwrap_err().contains("a bond count"));
        assert!(parse_rows("0 1 2\n").unwrap_err().contains("3 values"));
    }
}
