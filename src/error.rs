//! The library's error type. Every variant names what was wrong so that the
//! command line can print it as it is.

use std::path::PathBuf;

/// Errors from the stickslip library.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// A model file (or `--set` override) that cannot be read as TOML or does
    /// not match the schema (unknown key, missing key, wrong type).
    #[error("model {source_name}: {message}")]
    ModelSyntax { source_name: String, message: String },

    /// A model parameter outside its physical range; `key` is the dotted key.
    #[error("model parameter `{key}` = {value}: {message}")]
    InvalidParameter { key: String, value: String, message: String },

    /// A bad run setting: step size, cycle counts, grid, realisations, shard.
    #[error("invalid {what}: {message}")]
    InvalidSetting { what: String, message: String },

    /// Reading or writing a file failed.
    #[error("{}: {source}", crate::text::shown(path))]
    Io { path: PathBuf, source: std::io::Error },

    /// A measurement set (or shard accumulator file) that is refused.
    #[error("{}{}: {message}", crate::text::shown(file), line.map(|l| format!(":{l}")).unwrap_or_default())]
    Measurement { file: PathBuf, line: Option<u64>, message: String },

    /// An integrator produced a non-finite value (the model drives it out
    /// of range); `point` names the grid point, nothing is reduced.
    #[error("the simulation diverged at {point}: {message}")]
    Diverged { point: String, message: String },

    /// No usable GPU adapter / device.
    #[error("GPU unavailable: {0}")]
    NoGpu(String),

    /// A GPU operation failed (buffer mapping, validation, device lost).
    #[error("GPU error: {0}")]
    Gpu(String),

    /// Inputs that cannot be combined (e.g. shards of different runs).
    #[error("{0}")]
    Mismatch(String),
}

impl Error {
    pub(crate) fn io(path: impl Into<PathBuf>, source: std::io::Error) -> Self {
        Error::Io { path: path.into(), source }
    }

    pub(crate) fn setting(what: impl Into<String>, message: impl Into<String>) -> Self {
        Error::InvalidSetting { what: what.into(), message: message.into() }
    }

    /// Whether the engine cannot run the model it was given: it diverged,
    /// or a parameter lies outside its range or where no allowed step count
    /// resolves it. A search discards a trial model that fails so (its
    /// parameters are the search's); a model a user gave is refused by it.
    pub(crate) fn cannot_run(&self) -> bool {
        matches!(self, Error::Diverged { .. } | Error::InvalidParameter { .. })
    }
}

pub type Result<T, E = Error> = std::result::Result<T, E>;

#[cfg(test)]
mod tests {
    use super::*;

    /// A search discards a trial the engine cannot run, and only that: a
    /// step count refused for a trial's parameters is such a failure, a
    /// measurement or a file that cannot be read is not.
    #[test]
    fn only_a_model_the_engine_cannot_run_is_a_discarded_trial() {
        let refused = Error::InvalidParameter {
            key: "friction.b".into(),
            value: "-900".into(),
            message: "needs 3e7 steps per period".into(),
        };
        assert!(refused.cannot_run(), "{refused}");
        assert!(Error::Diverged { point: "7 Hz".into(), message: "NaN".into() }.cannot_run());
        let measurement = Error::Measurement { file: "run.csv".into(), line: Some(3), message: "bad".into() };
        assert!(!measurement.cannot_run());
        assert!(!Error::setting("cycles", "0").cannot_run());
    }
}
