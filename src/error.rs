//! The crate's error and warning types. Every message names what was wrong, where, and what is
//! valid, so a user can fix the input without reading the source.
//!
//! The library never prints: a [`Warning`] (something the user should know that did not stop the
//! work) is returned to the caller, which decides where it goes — the CLI prints `warning: …` on
//! stderr, the C API hands it to the callback a program set.

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
    /// A file named at a line of another could not be read (a scene's mesh or material file, a
    /// material's Fresnel table): located like [`Error::Parse`], but an I/O failure (the C
    /// API's `SHIKKI_IO_ERROR`), not malformed text. `message` quotes the read's error.
    #[error("{file}:{line}: {message}")]
    ReadNamedAt {
        file: String,
        line: usize,
        message: String,
        #[source]
        source: std::io::Error,
    },
    /// Writing an output failed; no partial file was left behind.
    #[error("cannot write {path}: {message}")]
    Write { path: PathBuf, message: String },
    /// Vulkan: no loader, no device, a failed call or validation messages.
    #[error(transparent)]
    Gpu(#[from] crate::gpu::GpuError),
    /// A bug in shikki, not in the input: a state the code should have made impossible.
    #[error("internal error (a bug in shikki; please report it): {0}")]
    Internal(String),
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
            value: compact_number(value.to_string()),
            reason: reason.into(),
        }
    }

    /// This error as found at `file:line`, its message after `prefix` (a column): a file that
    /// could not be read stays a read failure ([`Error::ReadNamedAt`]); anything else, content
    /// included, is a parse error there.
    pub fn located_at(self, file: &str, line: usize, prefix: &str) -> Self {
        let message = format!("{prefix}{self}");
        match self {
            Error::Read { source, .. } | Error::ReadNamedAt { source, .. }
                if source.kind() != std::io::ErrorKind::InvalidData =>
            {
                Error::ReadNamedAt {
                    file: file.into(),
                    line,
                    message,
                    source,
                }
            }
            _ => Error::parse(file, line, message),
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

/// A number as an error message shows it: plain where that is short, else in scientific notation
/// (f64's `Display` writes 1e-300 with 300 digits).
pub fn show_number(x: f64) -> String {
    let plain = x.to_string();
    match plain.len() > 16 && x.is_finite() {
        true => format!("{x:e}"),
        false => plain,
    }
}

/// Numbers as [`show_number`] writes them, in brackets: `[1, 2.5, 1e300]`.
pub fn show_numbers(xs: &[f64]) -> String {
    let shown: Vec<String> = xs.iter().map(|&x| show_number(x)).collect();
    format!("[{}]", shown.join(", "))
}

/// `value` as [`show_number`] writes it where it is one long number, else unchanged.
fn compact_number(value: String) -> String {
    match value.parse::<f64>() {
        Ok(x) if value.len() > 16 => show_number(x),
        _ => value,
    }
}

/// Something a caller should know that did not stop the work. Its `Display` is the sentence the
/// CLI prints after `warning: `.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Warning {
    /// Pixel values of an environment map that were NaN, infinite or negative, now 0.
    ReplacedPixels { environment: String, count: usize },
    /// An environment map whose width is not twice its height: read as equirectangular (SPEC
    /// §4) all the same, stretched. A mirror-ball or angular map drew a wrong image silently.
    NotEquirectangular {
        environment: String,
        width: u32,
        height: u32,
    },
    /// An environment cache file failed a check and was ignored; the next prefilter rewrites it.
    CacheFileInvalid { path: PathBuf, reason: String },
    /// An environment cache file was valid but could not be put on the device.
    CacheFileNotUploaded { path: PathBuf, reason: String },
    /// The prefiltered environment could not be stored in the cache (the render went on).
    CacheNotWritten { reason: String },
    /// A scene asked for light between objects (SPEC §6) on a device without ray queries: it
    /// was drawn without (once per renderer). `message` says what is missing and what to install.
    NoRayQueries { message: String },
    /// A mesh file loaded with changes: primitives skipped, degenerate triangles dropped,
    /// normals generated (`mesh_io::LoadReport`). Once per file per renderer.
    MeshLoadNotes { mesh: PathBuf, notes: Vec<String> },
}

impl std::fmt::Display for Warning {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Warning::ReplacedPixels { environment, count } => write!(
                f,
                "{environment}: {count} pixel value(s) were NaN, infinite or negative and were \
                 replaced by 0"
            ),
            Warning::NotEquirectangular {
                environment,
                width,
                height,
            } => write!(
                f,
                "{environment} is {width} × {height}, not 2:1: it is read as an equirectangular \
                 map (longitude across, latitude down) and stretched; convert a mirror-ball, \
                 angular or cube-cross map to equirectangular first"
            ),
            Warning::CacheFileInvalid { path, reason } => write!(
                f,
                "ignoring the environment cache file {}: {reason}; it will be rebuilt",
                path.display()
            ),
            Warning::CacheFileNotUploaded { path, reason } => write!(
                f,
                "ignoring the environment cache file {}: {reason}",
                path.display()
            ),
            Warning::CacheNotWritten { reason } => {
                write!(f, "the prefiltered environment was not cached: {reason}")
            }
            Warning::NoRayQueries { message } => f.write_str(message),
            Warning::MeshLoadNotes { mesh, notes } => {
                write!(f, "{}: {}", mesh.display(), notes.join("; "))
            }
        }
    }
}
