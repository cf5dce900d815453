//! Series-against-series comparison of two runs of the same scene.

use super::single_point::nan_max;
use crate::engine::SimBox;
use crate::kernels::Separation;
use crate::scene::run::StageOutput;
use serde::Serialize;

/// Largest deviation of one observable over every recorded row (or
/// checkpoint) of every stage.
#[derive(Clone, Debug, Serialize)]
pub struct Deviation {
    /// Observable name (a key of the tolerance table).
    pub observable: String,
    /// Largest deviation: relative to the observable's largest magnitude in
    /// the reference series, or in d for positions.
    pub max_deviation: f64,
    /// Step of the largest deviation.
    pub at_step: u64,
}

/// Why two runs cannot be compared.
#[derive(Debug, thiserror::Error)]
pub enum CompareError {
    /// Different stages, columns, rows or checkpoints.
    #[error("the runs differ in shape: {0}")]
    Shape(String),
}

/// Deviations of `run` from `reference`, per observable, plus positions.
pub fn compare_runs(
    reference: &[StageOutput],
    run: &[StageOutput],
) -> Result<Vec<Deviation>, CompareError> {
    let shape = |m: String| CompareError::Shape(m);
    if reference.len() != run.len() {
        return Err(shape(format!(
            "{} vs {} stages",
            reference.len(),
            run.len()
        )));
    }
    // Every observable the reference records, in the order its columns
    // are declared; `step` is the key the rows are matched on.
    let mut observables: Vec<&str> = Vec::new();
    for stage in reference {
        for c in &stage.columns {
            if c.observable != "step" && !observables.contains(&c.observable.as_str()) {
                observables.push(&c.observable);
            }
        }
    }
    let mut out = Vec::new();
    for observable in observables {
        let mut scale = 0.0f64;
        let mut worst = (0.0f64, 0u64);
        let mut any = false;
        for (a, b) in reference.iter().zip(run) {
            if a.rows.len() != b.rows.len() {
                return Err(shape(format!(
                    "stage `{}`: {} vs {} rows",
                    a.name,
                    a.rows.len(),
                    b.rows.len()
                )));
            }
            let step = a.column("step").unwrap_or_default();
            if step != b.column("step").unwrap_or_default() {
                return Err(shape(format!("stage `{}`: recorded steps differ", a.name)));
            }
            for c in a.columns.iter().filter(|c| c.observable == observable) {
                let (Some(x), Some(y)) = (a.column(&c.name), b.column(&c.name)) else {
                    return Err(shape(format!(
                        "stage `{}`: column `{}` is missing from the compared run",
                        a.name, c.name
                    )));
                };
                any = true;
                for k in 0..x.len() {
                    scale = scale.max(x[k].abs());
                    let d = (x[k] - y[k]).abs();
                    if is_worse(d, worst.0) {
                        worst = (d, step[k] as u64);
                    }
                }
            }
        }
        if any {
            out.push(Deviation {
                observable: observable.to_string(),
                max_deviation: if scale > 0.0 {
                    worst.0 / scale
                } else {
                    worst.0
                },
                at_step: worst.1,
            });
        }
    }
    let mut worst = (0.0f64, 0u64);
    let mut any = false;
    for (a, b) in reference.iter().zip(run) {
        if a.checkpoints.len() != b.checkpoints.len() {
            return Err(shape(format!(
                "stage `{}`: {} vs {} position checkpoints",
                a.name,
                a.checkpoints.len(),
                b.checkpoints.len()
            )));
        }
        for (p, q) in a.checkpoints.iter().zip(&b.checkpoints) {
            if p.positions.len() != q.positions.len() || p.step != q.step {
                return Err(shape(format!("stage `{}`: checkpoints differ", a.name)));
            }
            any = true;
            let [lo, lengths, tilt] = p.simbox;
            // Periodic in every dimension: the two engines may wrap a particle
            // differently (by a box vector), and a deviation far below half
            // the box is unchanged by the minimum image in a closed dimension.
            let simbox = SimBox {
                lo,
                lengths,
                tilt,
                periodic: [true; 3],
            };
            let r = max_position_deviation(&p.positions, &q.positions, &simbox);
            if is_worse(r, worst.0) {
                worst = (r, p.step);
            }
        }
    }
    if any {
        out.push(Deviation {
            observable: "positions".to_string(),
            max_deviation: worst.0,
            at_step: worst.1,
        });
    }
    Ok(out)
}

/// Whether the deviation `d` replaces `worst` as the largest so far: NaN
/// counts as the worst deviation and, once found, stays (a later finite
/// value must not replace it, as `nan_max(worst, d) != worst` did: NaN is
/// unequal to itself).
fn is_worse(d: f64, worst: f64) -> bool {
    !worst.is_nan() && (d.is_nan() || d > worst)
}

/// Largest distance (d) between the positions `a[k]` and `b[k]` under the
/// minimum image of `simbox` (NaN if any position is NaN).
pub fn max_position_deviation(a: &[[f64; 3]], b: &[[f64; 3]], simbox: &SimBox) -> f64 {
    let image = simbox.minimum_image();
    a.iter()
        .zip(b)
        .map(|(x, y)| image.distance(x, y))
        .fold(0.0, nan_max)
}

/// Per recorded step, the largest deviation over `columns` relative to
/// their largest magnitude in `reference` (for plots of divergence).
pub fn deviation_series(
    reference: &[StageOutput],
    run: &[StageOutput],
    columns: &[&str],
) -> Vec<(f64, f64)> {
    let mut scale = 0.0f64;
    let mut raw = Vec::new();
    for (a, b) in reference.iter().zip(run) {
        let step = a.column("step").unwrap_or_default();
        for (k, (ra, rb)) in a.rows.iter().zip(&b.rows).enumerate() {
            let mut worst = 0.0f64;
            for c in columns {
                if let (Some(i), Some(j)) = (
                    a.columns.iter().position(|n| n.name == *c),
                    b.columns.iter().position(|n| n.name == *c),
                ) {
                    scale = scale.max(ra[i].abs());
                    worst = worst.max((ra[i] - rb[j]).abs());
                }
            }
            raw.push((step[k], worst));
        }
    }
    let scale = if scale > 0.0 { scale } else { 1.0 };
    raw.into_iter().map(|(s, d)| (s, d / scale)).collect()
}

/// How far a compaction run in one engine is from the same run in the
/// other: the largest pressure deviation of any stage relative to that
/// stage's largest |P| (stages span decades of pressure, so one scale for
/// the whole run would hide the early ones), and the largest relative
/// deviation of the box length `lx`.
pub fn compaction_deviation(
    reference: &[StageOutput],
    run: &[StageOutput],
) -> Result<[Deviation; 2], CompareError> {
    let shape = |m: String| CompareError::Shape(m);
    if reference.len() != run.len() {
        return Err(shape(format!(
            "{} stages against {}",
            reference.len(),
            run.len()
        )));
    }
    let mut pressure = Deviation {
        observable: "compaction pressure".into(),
        max_deviation: 0.0,
        at_step: 0,
    };
    let mut length = Deviation {
        observable: "compaction box".into(),
        max_deviation: 0.0,
        at_step: 0,
    };
    for (a, b) in reference.iter().zip(run) {
        let column = |s: &StageOutput, name: &str| {
            s.column(name)
                .ok_or_else(|| shape(format!("stage {} records no `{name}`", s.name)))
        };
        let (pa, pb) = (column(a, "pressure")?, column(b, "pressure")?);
        let (la, lb) = (column(a, "lx")?, column(b, "lx")?);
        let steps = column(a, "step")?;
        if pa.len() != pb.len() {
            return Err(shape(format!(
                "stage {}: {} rows against {}",
                a.name,
                pa.len(),
                pb.len()
            )));
        }
        let scale = pa.iter().fold(0.0f64, |m, p| m.max(p.abs()));
        for k in 0..pa.len() {
            let dp = (pa[k] - pb[k]).abs() / scale.max(f64::MIN_POSITIVE);
            if dp.is_nan() || dp > pressure.max_deviation {
                pressure.max_deviation = dp;
                pressure.at_step = steps[k] as u64;
            }
            let dl = (la[k] - lb[k]).abs() / la[k].abs();
            if dl.is_nan() || dl > length.max_deviation {
                length.max_deviation = dl;
                length.at_step = steps[k] as u64;
            }
        }
    }
    Ok([pressure, length])
}
