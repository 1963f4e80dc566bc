//! The reports' JSON layout: `serde_json` with `", "` and `": "` between items (the layout
//! the README shows and scripts already read) and floats written with a fixed number of
//! decimals (`decimals::<3, _>` → `0.500`), so a report's field list is written once, in its
//! struct, with `#[derive(Serialize)]`.

use std::io;

use serde::{Serialize, Serializer};
use serde_json::ser::Formatter;
use serde_json::value::RawValue;

/// Compact JSON with a space after every `,` and `:` between object items.
struct Spaced;

impl Formatter for Spaced {
    fn begin_object_key<W: ?Sized + io::Write>(
        &mut self,
        writer: &mut W,
        first: bool,
    ) -> io::Result<()> {
        if first {
            Ok(())
        } else {
            writer.write_all(b", ")
        }
    }

    fn begin_object_value<W: ?Sized + io::Write>(&mut self, writer: &mut W) -> io::Result<()> {
        writer.write_all(b": ")
    }
}

/// `value` as one JSON object (or other value) in the reports' layout.
pub fn to_string<T: Serialize + ?Sized>(value: &T) -> String {
    let mut out = Vec::new();
    let mut ser = serde_json::Serializer::with_formatter(&mut out, Spaced);
    // Serializing plain structs of numbers and strings into a Vec cannot fail; a report
    // that somehow did still prints as valid JSON rather than half an object.
    if value.serialize(&mut ser).is_err() {
        return "null".into();
    }
    String::from_utf8(out).unwrap_or_else(|_| "null".into())
}

/// `serialize_with` for an `f64` written with `D` decimals (`null` if not finite, which
/// JSON cannot carry).
pub fn decimals<const D: usize, S: Serializer>(v: &f64, s: S) -> Result<S::Ok, S::Error> {
    if !v.is_finite() {
        return s.serialize_none();
    }
    let raw = RawValue::from_string(format!("{v:.D$}")).map_err(serde::ser::Error::custom)?;
    raw.serialize(s)
}

/// `serialize_with` for an `Option<f64>`: `null` or the value with `D` decimals.
pub fn decimals_or_null<const D: usize, S: Serializer>(
    v: &Option<f64>,
    s: S,
) -> Result<S::Ok, S::Error> {
    match v {
        Some(v) => decimals::<D, S>(v, s),
        None => s.serialize_none(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[derive(Serialize)]
    struct Sample {
        name: &'static str,
        #[serde(serialize_with = "decimals::<3, _>")]
        x: f64,
        #[serde(serialize_with = "decimals_or_null::<1, _>")]
        y: Option<f64>,
        #[serde(serialize_with = "decimals_or_null::<1, _>")]
        z: Option<f64>,
        #[serde(serialize_with = "decimals::<2, _>")]
        nan: f64,
        n: u32,
    }

    #[test]
    fn layout_and_decimals_are_the_documented_ones() {
        let s = Sample {
            name: "a",
            x: 0.5,
            y: Some(12.345),
            z: None,
            nan: f64::NAN,
            n: 7,
        };
        assert_eq!(
            to_string(&s),
            r#"{"name": "a", "x": 0.500, "y": 12.3, "z": null, "nan": null, "n": 7}"#
        );
    }
}
