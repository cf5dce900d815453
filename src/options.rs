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
