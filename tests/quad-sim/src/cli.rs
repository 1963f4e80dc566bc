//! Argument parsing shared by the `lqg` and `sysid` host commands: `--name value` pairs,
//! numbers and comma-separated lists, with errors that say which flag was wrong.

use std::collections::HashMap;
use std::fmt;

/// A command-line problem.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum ArgError {
    /// A flag without its value.
    MissingValue(String),
    /// A word that is not a `--flag`.
    Unexpected(String),
    /// A value that is not a number (flag, value).
    NotANumber(String, String),
    /// A list with the wrong number of entries (flag, wanted).
    WrongLength(String, usize),
    /// A required flag is absent.
    Required(String),
}

impl fmt::Display for ArgError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            ArgError::MissingValue(k) => write!(f, "--{k} needs a value"),
            ArgError::Unexpected(w) => write!(f, "unexpected argument {w:?}"),
            ArgError::NotANumber(k, v) => write!(f, "--{k}: {v:?} is not a number"),
            ArgError::WrongLength(k, n) => write!(f, "--{k} needs {n} comma-separated numbers"),
            ArgError::Required(k) => write!(f, "--{k} is required"),
        }
    }
}

impl std::error::Error for ArgError {}

/// Parsed `--flag value` pairs (a flag followed by another flag, or last, is a switch).
#[derive(Debug, Clone, Default)]
pub struct Args {
    values: HashMap<String, String>,
}

impl Args {
    /// Parses words after the sub-command.
    pub fn parse(words: &[String]) -> Result<Self, ArgError> {
        let mut values = HashMap::new();
        let mut it = words.iter().peekable();
        while let Some(w) = it.next() {
            let key = w
                .strip_prefix("--")
                .ok_or_else(|| ArgError::Unexpected(w.clone()))?;
            // Values may be negative numbers ("-4"), which are not flags.
            let value = match it.peek() {
                Some(v) if !v.starts_with("--") => it.next().cloned().unwrap_or_default(),
                _ => String::new(),
            };
            values.insert(key.to_string(), value);
        }
        Ok(Self { values })
    }

    /// Whether a switch or flag is present.
    pub fn has(&self, key: &str) -> bool {
        self.values.contains_key(key)
    }

    /// A string value.
    pub fn text(&self, key: &str) -> Option<&str> {
        self.values
            .get(key)
            .map(String::as_str)
            .filter(|s| !s.is_empty())
    }

    /// An optional number.
    pub fn number(&self, key: &str) -> Result<Option<f64>, ArgError> {
        match self.values.get(key) {
            None => Ok(None),
            Some(v) if v.is_empty() => Err(ArgError::MissingValue(key.to_string())),
            Some(v) => v
                .parse()
                .map(Some)
                .map_err(|_| ArgError::NotANumber(key.to_string(), v.clone())),
        }
    }

    /// A number with a default.
    pub fn number_or(&self, key: &str, default: f64) -> Result<f64, ArgError> {
        Ok(self.number(key)?.unwrap_or(default))
    }

    /// A required number.
    pub fn required(&self, key: &str) -> Result<f64, ArgError> {
        self.number(key)?
            .ok_or_else(|| ArgError::Required(key.to_string()))
    }

    /// An optional list of exactly `N` numbers.
    pub fn list<const N: usize>(&self, key: &str) -> Result<Option<[f64; N]>, ArgError> {
        let Some(v) = self.values.get(key) else {
            return Ok(None);
        };
        let items: Result<Vec<f64>, _> = v.split(',').map(|s| s.trim().parse::<f64>()).collect();
        let items = items.map_err(|_| ArgError::NotANumber(key.to_string(), v.clone()))?;
        <[f64; N]>::try_from(items)
            .map(Some)
            .map_err(|_| ArgError::WrongLength(key.to_string(), N))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn words(s: &str) -> Vec<String> {
        s.split_whitespace().map(String::from).collect()
    }

    #[test]
    fn parses_numbers_lists_and_switches() {
        let a = Args::parse(&words(
            "--tau 0.03 --q 4,0.04,10000 --ln-tau -4 --compare-pid",
        ))
        .unwrap();
        assert_eq!(a.required("tau").unwrap(), 0.03);
        assert_eq!(a.list::<3>("q").unwrap().unwrap(), [4.0, 0.04, 10000.0]);
        assert_eq!(a.number("ln-tau").unwrap(), Some(-4.0));
        assert!(a.has("compare-pid"));
        assert_eq!(
            a.list::<2>("q").unwrap_err(),
            ArgError::WrongLength("q".into(), 2)
        );
        assert_eq!(
            a.required("ts").unwrap_err(),
            ArgError::Required("ts".into())
        );
        assert!(Args::parse(&words("tau 3")).is_err());
        assert!(
            Args::parse(&words("--tau x"))
                .unwrap()
                .number("tau")
                .is_err()
        );
    }
}
