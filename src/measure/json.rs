//! Reading the manifest's JSON values with errors that name the manifest,
//! the key and what is wrong.

use std::path::Path;

use serde_json::{Map, Value};

use crate::error::{Error, Result};

/// An [`Error::Measurement`].
pub(super) fn bad(file: &Path, line: Option<u64>, message: impl Into<String>) -> Error {
    Error::Measurement { file: file.to_path_buf(), line, message: message.into() }
}

/// What kind of JSON value `v` is, for messages.
pub(super) fn kind(v: &Value) -> &'static str {
    match v {
        Value::Null => "null",
        Value::Bool(_) => "a boolean",
        Value::Number(_) => "a number",
        Value::String(_) => "a string",
        Value::Array(_) => "an array",
        Value::Object(_) => "an object",
    }
}

/// Accepted range of a number.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) enum Bound {
    /// Any finite number.
    Finite,
    /// Finite, in `[lo, hi]` (`lo` itself refused when `lo_open`): the
    /// physically sensible ranges of [`crate::engine::model::limits`].
    Range { lo: f64, hi: f64, lo_open: bool },
}

impl Bound {
    /// `[lo, hi]`.
    pub(super) const fn within(lo: f64, hi: f64) -> Bound {
        Bound::Range { lo, hi, lo_open: false }
    }

    /// `(0, hi]`.
    pub(super) const fn positive(hi: f64) -> Bound {
        Bound::Range { lo: 0.0, hi, lo_open: true }
    }

    /// `None` if `value` is acceptable, else what is wrong with it.
    pub(super) fn violation(self, value: f64, unit: &str) -> Option<String> {
        use crate::engine::model::{fmt_bound, fmt_value};
        let shown = fmt_value(value);
        let unit = if unit.is_empty() { String::new() } else { format!(" {unit}") };
        if !value.is_finite() {
            return Some(format!("{shown} is not a finite number"));
        }
        match self {
            Bound::Finite => None,
            Bound::Range { lo, .. } if value < 0.0 && lo >= 0.0 => {
                Some(format!("{shown} must not be negative (≥ {}{unit})", fmt_bound(lo)))
            }
            Bound::Range { lo, lo_open, .. } if value == 0.0 && (lo > 0.0 || (lo_open && lo == 0.0)) => {
                Some(format!("{shown} must be positive ({} {}{unit})", if lo_open { ">" } else { "≥" }, fmt_bound(lo)))
            }
            Bound::Range { lo, lo_open, .. } if value < lo || (lo_open && value == lo) => {
                Some(format!("{shown} must be {} {}{unit}", if lo_open { ">" } else { "≥" }, fmt_bound(lo)))
            }
            Bound::Range { hi, .. } if value > hi => {
                Some(format!("{shown} must be ≤ {}{unit} (a physically sensible range)", fmt_bound(hi)))
            }
            _ => None,
        }
    }
}

/// Helpers that read manifest values with messages naming the manifest.
pub(super) struct Json<'a> {
    pub(super) file: &'a Path,
}

impl Json<'_> {
    pub(super) fn missing(&self, key: &str) -> Error {
        bad(self.file, None, format!("missing required key `{key}`"))
    }

    pub(super) fn object<'v>(&self, value: &'v Value, ctx: &str) -> Result<&'v Map<String, Value>> {
        value
            .as_object()
            .ok_or_else(|| bad(self.file, None, format!("`{ctx}` must be an object, found {}", kind(value))))
    }

    /// The required number `ctx.key`, checked against `bound`.
    pub(super) fn number(
        &self,
        obj: &Map<String, Value>,
        ctx: &str,
        key: &str,
        bound: Bound,
        unit: &str,
    ) -> Result<f64> {
        let value = obj.get(key).ok_or_else(|| self.missing(&format!("{ctx}.{key}")))?;
        let number = match value {
            Value::Number(n) => n.as_f64(),
            _ => None,
        }
        .ok_or_else(|| {
            let found = crate::text::excerpt(&value.to_string(), crate::text::EXCERPT_CHARS);
            bad(self.file, None, format!("`{ctx}.{key}` must be a number, found {found}"))
        })?;
        match bound.violation(number, unit) {
            None => Ok(number),
            Some(problem) => Err(bad(self.file, None, format!("`{ctx}.{key}` = {problem}"))),
        }
    }
}
