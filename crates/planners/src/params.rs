//! Planner parameters: a robot's `params` table from the scenario, read with
//! defaults, type checks and a complaint about every key the planner does
//! not know.

use std::collections::BTreeMap;

/// One parameter value as written in a scenario.
#[derive(Debug, Clone, PartialEq)]
pub enum ParamValue {
    /// A number (TOML integers become numbers too).
    Number(f64),
    /// A string, e.g. `shape = "ellipse"`.
    Text(String),
    /// A boolean.
    Bool(bool),
    /// A list of numbers, e.g. `speeds = [0.1, 0.2]`.
    Numbers(Vec<f64>),
    /// A list of points, e.g. `points = [[0, 0], [1, 2]]`.
    Points(Vec<[f64; 2]>),
}

impl ParamValue {
    fn type_name(&self) -> &'static str {
        match self {
            ParamValue::Number(_) => "a number",
            ParamValue::Text(_) => "a string",
            ParamValue::Bool(_) => "a boolean",
            ParamValue::Numbers(_) => "a list of numbers",
            ParamValue::Points(_) => "a list of points",
        }
    }
}

/// A robot's planner parameters, by name.
pub type Params = BTreeMap<String, ParamValue>;

/// Why a planner's parameters were refused.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ParamError {
    /// The planner has no parameter of that name.
    #[error("planner `{planner}` has no parameter `{key}` (it knows: {known})")]
    Unknown {
        /// The planner's name.
        planner: String,
        /// The offending key.
        key: String,
        /// Comma-separated list of the keys it knows.
        known: String,
    },
    /// The value has the wrong type.
    #[error("parameter `{key}` of planner `{planner}` must be {expected}, not {found}")]
    WrongType {
        /// The planner's name.
        planner: String,
        /// The offending key.
        key: String,
        /// What was expected.
        expected: String,
        /// What was found.
        found: String,
    },
    /// The value is out of its allowed range or not one of the choices.
    #[error("parameter `{key}` of planner `{planner}`: {reason}")]
    Invalid {
        /// The planner's name.
        planner: String,
        /// The offending key.
        key: String,
        /// Why.
        reason: String,
    },
}

impl ParamError {
    /// The parameter key the error is about.
    pub fn key(&self) -> &str {
        match self {
            ParamError::Unknown { key, .. }
            | ParamError::WrongType { key, .. }
            | ParamError::Invalid { key, .. } => key,
        }
    }
}

/// Reads a planner's parameters one by one, remembering which keys it used
/// so that [`ParamReader::finish`] can refuse the rest.
///
/// ```
/// use mrsim_planners::{ParamReader, Params, ParamValue};
/// let mut p = Params::new();
/// p.insert("f_g".into(), ParamValue::Number(2.0));
/// let mut r = ParamReader::new("chung-1", &p);
/// assert_eq!(r.number("f_g", 1.0).unwrap(), 2.0);
/// assert_eq!(r.number("alpha", 0.8).unwrap(), 0.8);
/// r.finish().unwrap();
/// ```
pub struct ParamReader<'a> {
    planner: &'a str,
    params: &'a Params,
    used: Vec<&'static str>,
}

impl<'a> ParamReader<'a> {
    /// Starts reading `params` for the planner called `planner`.
    pub fn new(planner: &'a str, params: &'a Params) -> Self {
        Self {
            planner,
            params,
            used: Vec::new(),
        }
    }

    fn wrong_type(&self, key: &str, expected: &str, found: &ParamValue) -> ParamError {
        ParamError::WrongType {
            planner: self.planner.to_string(),
            key: key.to_string(),
            expected: expected.to_string(),
            found: found.type_name().to_string(),
        }
    }

    /// An error about `key`'s value, for checks the planner does itself.
    pub fn invalid(&self, key: &str, reason: impl Into<String>) -> ParamError {
        ParamError::Invalid {
            planner: self.planner.to_string(),
            key: key.to_string(),
            reason: reason.into(),
        }
    }

    /// A finite number, or `default` when absent.
    pub fn number(&mut self, key: &'static str, default: f64) -> Result<f64, ParamError> {
        self.used.push(key);
        match self.params.get(key) {
            None => Ok(default),
            Some(ParamValue::Number(v)) if v.is_finite() => Ok(*v),
            Some(ParamValue::Number(v)) => Err(self.invalid(key, format!("{v} is not finite"))),
            Some(other) => Err(self.wrong_type(key, "a number", other)),
        }
    }

    /// A finite number that must be strictly positive.
    pub fn positive(&mut self, key: &'static str, default: f64) -> Result<f64, ParamError> {
        let v = self.number(key, default)?;
        if v > 0.0 {
            Ok(v)
        } else {
            Err(self.invalid(key, format!("must be > 0, got {v}")))
        }
    }

    /// A finite number that must be zero or positive.
    pub fn non_negative(&mut self, key: &'static str, default: f64) -> Result<f64, ParamError> {
        let v = self.number(key, default)?;
        if v >= 0.0 {
            Ok(v)
        } else {
            Err(self.invalid(key, format!("must be >= 0, got {v}")))
        }
    }

    /// A whole number >= `min`.
    pub fn count(
        &mut self,
        key: &'static str,
        default: usize,
        min: usize,
    ) -> Result<usize, ParamError> {
        let v = self.number(key, default as f64)?;
        if v.fract() != 0.0 || v < min as f64 || v > 1e9 {
            return Err(self.invalid(key, format!("must be a whole number >= {min}, got {v}")));
        }
        Ok(v as usize)
    }

    /// A boolean, or `default` when absent.
    pub fn boolean(&mut self, key: &'static str, default: bool) -> Result<bool, ParamError> {
        self.used.push(key);
        match self.params.get(key) {
            None => Ok(default),
            Some(ParamValue::Bool(b)) => Ok(*b),
            Some(other) => Err(self.wrong_type(key, "a boolean", other)),
        }
    }

    /// One of `choices` (the first is not implied: `default` is).
    pub fn choice(
        &mut self,
        key: &'static str,
        choices: &[&'static str],
        default: &'static str,
    ) -> Result<&'static str, ParamError> {
        self.used.push(key);
        match self.params.get(key) {
            None => Ok(default),
            Some(ParamValue::Text(s)) => {
                choices.iter().copied().find(|c| c == s).ok_or_else(|| {
                    self.invalid(key, format!("`{s}` is not one of: {}", choices.join(", ")))
                })
            }
            Some(other) => Err(self.wrong_type(key, "a string", other)),
        }
    }

    /// A list of finite numbers, or `default` when absent. A single number
    /// is taken as a list of one.
    pub fn numbers(&mut self, key: &'static str, default: &[f64]) -> Result<Vec<f64>, ParamError> {
        self.used.push(key);
        let v = match self.params.get(key) {
            None => return Ok(default.to_vec()),
            Some(ParamValue::Numbers(v)) => v.clone(),
            Some(ParamValue::Number(x)) => vec![*x],
            Some(other) => return Err(self.wrong_type(key, "a list of numbers", other)),
        };
        if v.iter().any(|x| !x.is_finite()) {
            return Err(self.invalid(key, "every number must be finite"));
        }
        Ok(v)
    }

    /// A list of points, or `default` when absent.
    pub fn points(
        &mut self,
        key: &'static str,
        default: &[[f64; 2]],
    ) -> Result<Vec<[f64; 2]>, ParamError> {
        self.used.push(key);
        let v = match self.params.get(key) {
            None => return Ok(default.to_vec()),
            Some(ParamValue::Points(v)) => v.clone(),
            Some(ParamValue::Numbers(v)) if v.is_empty() => Vec::new(),
            Some(other) => return Err(self.wrong_type(key, "a list of [x, y] points", other)),
        };
        if v.iter().flatten().any(|x| !x.is_finite()) {
            return Err(self.invalid(key, "every coordinate must be finite"));
        }
        Ok(v)
    }

    /// Refuses any key that was never read.
    pub fn finish(self) -> Result<(), ParamError> {
        for key in self.params.keys() {
            if !self.used.iter().any(|u| u == key) {
                let mut known: Vec<&str> = self.used.clone();
                known.sort_unstable();
                known.dedup();
                return Err(ParamError::Unknown {
                    planner: self.planner.to_string(),
                    key: key.clone(),
                    known: if known.is_empty() {
                        "none".to_string()
                    } else {
                        known.join(", ")
                    },
                });
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn params(pairs: &[(&str, ParamValue)]) -> Params {
        pairs
            .iter()
            .map(|(k, v)| (k.to_string(), v.clone()))
            .collect()
    }

    #[test]
    fn unknown_key_is_refused_and_names_the_known_ones() {
        let p = params(&[("f_q", ParamValue::Number(1.0))]);
        let mut r = ParamReader::new("chung-1", &p);
        r.number("f_g", 1.0).unwrap();
        let err = r.finish().unwrap_err();
        assert_eq!(err.key(), "f_q");
        assert!(err.to_string().contains("f_g"), "{err}");
    }

    #[test]
    fn wrong_type_and_range_are_refused() {
        let p = params(&[
            ("a", ParamValue::Text("x".into())),
            ("b", ParamValue::Number(-1.0)),
            ("c", ParamValue::Text("oval".into())),
        ]);
        let mut r = ParamReader::new("t", &p);
        assert!(matches!(
            r.number("a", 0.0),
            Err(ParamError::WrongType { .. })
        ));
        assert!(matches!(
            r.positive("b", 1.0),
            Err(ParamError::Invalid { .. })
        ));
        assert!(r.choice("c", &["circle", "ellipse"], "circle").is_err());
    }
}
