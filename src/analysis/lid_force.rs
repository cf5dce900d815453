//! A lid-force history against a reference one (LIGGGHTS's, for the same
//! bed and protocol): the two series are matched by step, and their
//! difference is measured over the loaded rows as a fraction of the
//! reference's peak, so the unloaded rows (where both are near zero and
//! the relative error means nothing) do not count.

use serde::Serialize;

/// How far one lid-force history is from a reference.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct LidComparison {
    /// Rows at the same step in both series.
    pub matched: usize,
    /// Of those, the loaded ones: reference force above `loaded` times
    /// its peak.
    pub loaded_rows: usize,
    /// The reference's peak force.
    pub peak: f64,
    /// Root mean square of the difference over the loaded rows, over the
    /// peak.
    pub rms_of_peak: f64,
    /// Largest difference over the loaded rows, over the peak.
    pub max_of_peak: f64,
    /// The step of the largest difference.
    pub max_at_step: u64,
}

/// Compares `force` at `step` with the reference `ref_force` at
/// `ref_step` (both in increasing steps); rows whose reference force
/// exceeds `loaded` times the reference's peak count. `None` if no loaded
/// row is matched.
pub fn compare_lid_force(
    step: &[u64],
    force: &[f64],
    ref_step: &[u64],
    ref_force: &[f64],
    loaded: f64,
) -> Option<LidComparison> {
    let peak = ref_force.iter().copied().fold(0.0, f64::max);
    compare_against_peak(step, force, ref_step, ref_force, loaded, peak)
}

/// [`compare_lid_force`] for each pass of the lid (`pass_steps` steps
/// each; the pass ending at step `k pass_steps` holds it), with the
/// whole reference's peak: where in the protocol the differences are.
/// A pass with no loaded row matched is `None`. Both series in increasing
/// steps, as for [`compare_lid_force`].
pub fn compare_lid_force_by_pass(
    step: &[u64],
    force: &[f64],
    ref_step: &[u64],
    ref_force: &[f64],
    loaded: f64,
    pass_steps: u64,
) -> Vec<Option<LidComparison>> {
    let peak = ref_force.iter().copied().fold(0.0, f64::max);
    let pass_of = |s: u64| s.saturating_sub(1) / pass_steps.max(1);
    let mut passes = Vec::new();
    let mut first = 0;
    while first < ref_step.len() {
        let pass = pass_of(ref_step[first]);
        let end = first + ref_step[first..].partition_point(|&s| pass_of(s) == pass);
        let range = first..end;
        if passes.len() < pass as usize {
            passes.resize(pass as usize, None);
        }
        passes.push(compare_against_peak(
            step,
            force,
            &ref_step[range.clone()],
            &ref_force[range],
            loaded,
            peak,
        ));
        first = end;
    }
    passes
}

/// [`compare_lid_force`] with the reference's peak given.
fn compare_against_peak(
    step: &[u64],
    force: &[f64],
    ref_step: &[u64],
    ref_force: &[f64],
    loaded: f64,
    peak: f64,
) -> Option<LidComparison> {
    let mut matched = 0;
    let mut differences = Vec::new();
    let mut k = step.partition_point(|&s| s < ref_step.first().copied().unwrap_or(0));
    for (&s, &f_ref) in ref_step.iter().zip(ref_force) {
        while k < step.len() && step[k] < s {
            k += 1;
        }
        if k == step.len() {
            break;
        }
        if step[k] != s {
            continue;
        }
        matched += 1;
        if f_ref > loaded * peak {
            differences.push((s, (force[k] - f_ref).abs()));
        }
    }
    if differences.is_empty() || peak <= 0.0 {
        return None;
    }
    let mean_square =
        differences.iter().map(|(_, d)| d * d).sum::<f64>() / differences.len() as f64;
    let (max_at_step, max) =
        differences
            .iter()
            .copied()
            .fold((0, 0.0), |acc, (s, d)| if d > acc.1 { (s, d) } else { acc });
    Some(LidComparison {
        matched,
        loaded_rows: differences.len(),
        peak,
        rms_of_peak: mean_square.sqrt() / peak,
        max_of_peak: max / peak,
        max_at_step,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn matches_rows_by_step_and_skips_the_unloaded_ones() {
        let ref_step = [100, 200, 300, 400];
        let ref_force = [0.0, 10.0, 5.0, 0.001];
        // Ours has an extra row (step 0) and misses step 300.
        let step = [0, 100, 200, 400];
        let force = [7.0, 3.0, 9.0, 4.0];
        let c = compare_lid_force(&step, &force, &ref_step, &ref_force, 0.01).unwrap();
        assert_eq!(c.matched, 3);
        // Steps 100 (force 0) and 400 (1e-4 of the peak) are unloaded.
        assert_eq!(c.loaded_rows, 1);
        assert_eq!(c.peak, 10.0);
        assert!((c.rms_of_peak - 0.1).abs() < 1e-15);
        assert_eq!(c.max_at_step, 200);
    }

    #[test]
    fn each_pass_is_measured_against_the_whole_peak() {
        // Passes of 200 steps: rows 100 and 200 in the first, 300 and 400
        // in the second; the third pass has no row.
        let ref_step = [100, 200, 300, 400, 700];
        let ref_force = [10.0, 5.0, 2.0, 4.0, 8.0];
        let step = [100, 200, 300, 400, 700];
        let force = [10.0, 6.0, 2.0, 2.0, 8.0];
        let passes = compare_lid_force_by_pass(&step, &force, &ref_step, &ref_force, 0.01, 200);
        assert_eq!(passes.len(), 4);
        let [Some(a), Some(b), None, Some(d)] = passes[..] else {
            panic!("{passes:?}");
        };
        assert_eq!((a.loaded_rows, a.peak, a.max_at_step), (2, 10.0, 200));
        assert!((a.rms_of_peak - (0.5f64).sqrt() / 10.0).abs() < 1e-15);
        assert!((b.rms_of_peak - (2.0f64).sqrt() / 10.0).abs() < 1e-15);
        assert_eq!((b.max_at_step, d.rms_of_peak), (400, 0.0));
        let whole = compare_lid_force(&step, &force, &ref_step, &ref_force, 0.01).unwrap();
        assert_eq!(whole.loaded_rows, 5);
    }

    #[test]
    fn no_loaded_row_is_no_comparison() {
        assert_eq!(compare_lid_force(&[1], &[1.0], &[2], &[1.0], 0.01), None);
    }
}
