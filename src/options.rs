//! Checks of user options. Every options type of the library validates
//! itself (`validate()`), with an error that names the command-line
//! argument, so the `bpm` binary only parses arguments.

/// An option outside its range: names the argument as on the command line
/// and says what it must be (`--size must be a number above 3 (d), got 2`).
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[error("{option} {requirement}")]
pub struct InvalidOption {
    /// The argument(s) (`--size`, `--rate and --strain`).
    pub option: &'static str,
    /// What it must be, and the value given.
    pub requirement: String,
}

impl InvalidOption {
    /// `option` must satisfy `requirement`.
    pub fn new(option: &'static str, requirement: impl Into<String>) -> Self {
        Self {
            option,
            requirement: requirement.into(),
        }
    }
}

/// `--threads`: at least 1.
pub fn validate_threads(threads: usize) -> Result<(), InvalidOption> {
    if threads == 0 {
        return Err(InvalidOption::new("--threads", "must be at least 1"));
    }
    Ok(())
}

/// `--rate` and `--strain` of a deformation: both finite and positive.
pub fn validate_strain_and_rate(strain: f64, rate: f64) -> Result<(), InvalidOption> {
    if !(rate.is_finite() && rate > 0.0 && strain.is_finite() && strain > 0.0) {
        return Err(InvalidOption::new(
            "--rate and --strain",
            "must be positive",
        ));
    }
    Ok(())
}

/// A list of a_B values (`option` names it): each finite and above -1
/// (k d), where the multibody factor stays positive.
pub fn validate_a_b_values<'a>(
    option: &'static str,
    values: impl IntoIterator<Item = &'a f64>,
) -> Result<(), InvalidOption> {
    if let Some(bad) = values.into_iter().find(|a| !(a.is_finite() && **a > -1.0)) {
        return Err(InvalidOption::new(
            option,
            format!("must be finite and above -1 (k d), got {bad}"),
        ));
    }
    Ok(())
}

/// Every value of `option` in `(0, max]` (`unit` names the unit in the
/// message); a list must not be empty.
pub fn require_positive_up_to(
    option: &'static str,
    values: &[f64],
    max: f64,
    unit: &str,
) -> Result<(), InvalidOption> {
    require_each(
        option,
        values,
        &|v| v > 0.0 && v <= max,
        &format!("in (0, {max}] {unit}"),
    )
}

/// Every value of `option` in `[lo, hi]`, or 0 when `zero_skips` (0 then
/// switches the part off); a list must not be empty.
pub fn require_within(
    option: &'static str,
    values: &[f64],
    (lo, hi): (f64, f64),
    zero_skips: bool,
    unit: &str,
) -> Result<(), InvalidOption> {
    let range = format!("in [{lo}, {hi}] {unit}");
    let what = if zero_skips {
        format!("0 (skip) or {range}")
    } else {
        range
    };
    require_each(
        option,
        values,
        &|v| (zero_skips && v == 0.0) || (lo..=hi).contains(&v),
        &what,
    )
}

fn require_each(
    option: &'static str,
    values: &[f64],
    ok: &dyn Fn(f64) -> bool,
    what: &str,
) -> Result<(), InvalidOption> {
    if values.is_empty() {
        return Err(InvalidOption::new(option, "needs at least one value"));
    }
    match values.iter().find(|v| !ok(**v)) {
        Some(v) => Err(InvalidOption::new(
            option,
            format!("must be {what}, got {v}"),
        )),
        None => Ok(()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn messages_name_the_argument() {
        assert_eq!(
            validate_threads(0).unwrap_err().to_string(),
            "--threads must be at least 1"
        );
        assert_eq!(
            validate_strain_and_rate(0.005, -1.0)
                .unwrap_err()
                .to_string(),
            "--rate and --strain must be positive"
        );
        assert_eq!(
            validate_a_b_values("a_B values", &[0.0, -1.0])
                .unwrap_err()
                .to_string(),
            "a_B values must be finite and above -1 (k d), got -1"
        );
        assert!(validate_a_b_values("--a-b values", &[-0.8, 0.0, 3.0]).is_ok());
    }
}
