//! NaN and infinities in JSON. serde_json writes a number it cannot hold
//! (NaN, an infinity) as `null`, and a plain `f64` does not read `null`
//! back; a measured value that may be undefined (a run that blew up, a
//! failed fit) is read with these instead, `null` becoming NaN, so a
//! report the program wrote can always be read again.

use serde::{Deserialize, Deserializer};

/// An `f64` that may have been written as `null` (for
/// `#[serde(deserialize_with = "crate::json_nan::nan_if_null")]`).
pub fn nan_if_null<'de, D: Deserializer<'de>>(d: D) -> Result<f64, D::Error> {
    Ok(Option::<f64>::deserialize(d)?.unwrap_or(f64::NAN))
}

/// A column of `f64` whose entries may have been written as `null`.
pub fn nan_if_null_each<'de, D: Deserializer<'de>>(d: D) -> Result<Vec<f64>, D::Error> {
    Ok(Vec::<Option<f64>>::deserialize(d)?
        .into_iter()
        .map(|v| v.unwrap_or(f64::NAN))
        .collect())
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde::Serialize;

    #[derive(Deserialize, Serialize)]
    struct Measured {
        #[serde(deserialize_with = "nan_if_null")]
        value: f64,
        #[serde(deserialize_with = "nan_if_null_each")]
        column: Vec<f64>,
    }

    #[test]
    fn undefined_numbers_read_back_as_nan() {
        let written = Measured {
            value: f64::NAN,
            column: vec![1.5, f64::INFINITY, f64::NAN],
        };
        let json = serde_json::to_string(&written).unwrap();
        assert_eq!(json, r#"{"value":null,"column":[1.5,null,null]}"#);
        let read: Measured = serde_json::from_str(&json).unwrap();
        assert!(read.value.is_nan());
        assert_eq!(read.column[0], 1.5);
        assert!(read.column[1].is_nan() && read.column[2].is_nan());
        let read: Measured = serde_json::from_str(r#"{"value":2.5,"column":[]}"#).unwrap();
        assert_eq!(read.value, 2.5);
    }
}
