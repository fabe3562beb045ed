//! The library's error type: every message names what was wrong and what is allowed.

use std::path::PathBuf;

/// Errors from loading parameters, validating them, or writing results.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// A parameter is outside its allowed range; `field` names it as the user wrote it.
    #[error("{field} = {value} is out of range: allowed {allowed}")]
    OutOfRange {
        field: String,
        value: String,
        allowed: String,
    },
    /// A request would need more memory than the run's budget ([`crate::budget`]).
    #[error("{what} would need {} MiB, above the memory budget of {} MiB; lower {setting} (or raise --memory-limit)", mib(*needed_bytes), mib(*budget_bytes))]
    OverBudget {
        what: String,
        needed_bytes: u64,
        budget_bytes: u64,
        setting: String,
    },
    /// A parameter file could not be parsed (message carries line and column).
    #[error("{path}: {message}")]
    Parse { path: String, message: String },
    /// A file could not be read or written. The system's reason is part of the
    /// message, not a separate source, so that a chain of causes says it once.
    #[error("{path}: {error}")]
    Io {
        path: PathBuf,
        error: std::io::Error,
    },
    /// An image could not be encoded.
    #[error("{path}: could not encode image: {message}")]
    Image { path: PathBuf, message: String },
    /// Anything else the user asked for that cannot be done, said plainly.
    #[error("{0}")]
    Invalid(String),
}

/// Bytes as MiB with one decimal, for messages.
fn mib(bytes: u64) -> String {
    format!("{:.1}", bytes as f64 / (1u64 << 20) as f64)
}

/// Result with the library's [`Error`].
pub type Result<T> = std::result::Result<T, Error>;

impl Error {
    /// For `map_err`: an I/O error at `path` as an [`Error::Io`].
    pub fn io_at(path: &std::path::Path) -> impl Fn(std::io::Error) -> Error + Copy + '_ {
        move |error| Error::Io {
            path: path.to_path_buf(),
            error,
        }
    }

    /// Shorthand for [`Error::OutOfRange`].
    pub fn out_of_range(field: &str, value: impl std::fmt::Display, allowed: &str) -> Self {
        Error::OutOfRange {
            field: field.to_string(),
            value: value.to_string(),
            allowed: allowed.to_string(),
        }
    }
}

/// TOML `text` read into `T`; `origin` names the text in the message of a file that
/// does not parse (which carries the line and column).
pub(crate) fn from_toml<T: serde::de::DeserializeOwned>(text: &str, origin: &str) -> Result<T> {
    toml::from_str(text).map_err(|e| Error::Parse {
        path: origin.to_string(),
        message: e.to_string(),
    })
}

/// Checks that `value` is finite and in `[min, max]`, naming `field` otherwise.
pub fn check_range(field: &str, value: f64, min: f64, max: f64) -> Result<()> {
    if value.is_finite() && value >= min && value <= max {
        Ok(())
    } else {
        Err(Error::out_of_range(
            field,
            value,
            &format!("[{min}, {max}]"),
        ))
    }
}

/// Checks that `value` is finite and `> 0` (and at most `max`), naming `field` otherwise.
pub fn check_positive(field: &str, value: f64, max: f64) -> Result<()> {
    if value.is_finite() && value > 0.0 && value <= max {
        Ok(())
    } else {
        Err(Error::out_of_range(field, value, &format!("(0, {max}]")))
    }
}
