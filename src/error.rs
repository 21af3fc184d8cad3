//! The crate's error type. Every message names what was wrong, where, and what is valid, so a
//! user can fix the input without reading the source.

use std::path::PathBuf;

/// Everything shikki can fail with.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// A parameter (material field, CLI value, camera setting…) is outside its valid range.
    /// `reason` states the valid range and, where there is one, the fix.
    #[error("invalid {field} = {value}: {reason}")]
    InvalidParameter {
        field: String,
        value: String,
        reason: String,
    },
    /// A text input (CSV, TOML…) is malformed at a known line.
    #[error("{file}:{line}: {message}")]
    Parse {
        file: String,
        line: usize,
        message: String,
    },
    /// Reading an input file failed.
    #[error("cannot read {path}: {source}")]
    Read {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    /// Writing an output failed; no partial file was left behind.
    #[error("cannot write {path}: {message}")]
    Write { path: PathBuf, message: String },
    /// Vulkan: no loader, no device, a failed call or validation messages.
    #[error(transparent)]
    Gpu(#[from] crate::gpu::GpuError),
}

/// `Result` with [`Error`] as the default error.
pub type Result<T, E = Error> = std::result::Result<T, E>;

impl Error {
    /// Shorthand for [`Error::InvalidParameter`].
    pub fn invalid(
        field: impl Into<String>,
        value: impl std::fmt::Display,
        reason: impl Into<String>,
    ) -> Self {
        Error::InvalidParameter {
            field: field.into(),
            value: value.to_string(),
            reason: reason.into(),
        }
    }

    /// Shorthand for [`Error::Parse`].
    pub fn parse(file: impl Into<String>, line: usize, message: impl Into<String>) -> Self {
        Error::Parse {
            file: file.into(),
            line,
            message: message.into(),
        }
    }
}
