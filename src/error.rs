//! The library's one error type.
//!
//! Every fallible operation in `chisel` returns [`Result<T>`]. File readers
//! report *where* (file + [`Position`]) and *what was expected*; GPU failures
//! (no adapter, device loss, out-of-memory, validation) are values, never
//! panics.

use std::fmt;
use std::path::PathBuf;

/// A place inside an input file, for error messages.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Position {
    /// 1-based line number of a text file or text header.
    Line(usize),
    /// 1-based line and column (in characters) of a text file.
    LineColumn(usize, usize),
    /// 0-based byte offset into a (binary) file.
    Byte(u64),
    /// A named header field (e.g. `sizes` of an NRRD header).
    Field(String),
    /// The file as a whole (e.g. its length).
    Whole,
}

impl fmt::Display for Position {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Position::Line(n) => write!(f, "line {n}"),
            Position::LineColumn(n, c) => write!(f, "line {n}, column {c}"),
            Position::Byte(n) => write!(f, "byte {n}"),
            Position::Field(k) => write!(f, "field `{k}`"),
            Position::Whole => write!(f, "whole file"),
        }
    }
}

/// Everything that can go wrong in the library.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// An operating-system I/O error on `path`.
    /// (The OS error is part of the message, not a `source`, so that a
    /// printed error chain names it once.)
    #[error("{path}: {error}")]
    Io {
        path: PathBuf,
        error: std::io::Error,
    },
    /// Malformed input: `path` at `at`, with what was expected and what was found.
    #[error("{path}: {at}: expected {expected}, found {found}")]
    Format {
        path: PathBuf,
        at: Position,
        expected: String,
        found: String,
    },
    /// A header announces more data than the file holds or the memory budget allows.
    #[error("{path}: {at}: {what} needs {needed} bytes but {limit_kind} is {limit} bytes")]
    Size {
        path: PathBuf,
        at: Position,
        what: String,
        needed: u64,
        limit_kind: &'static str,
        limit: u64,
    },
    /// The file's format is not one chisel reads or writes.
    #[error("{path}: unsupported format: {what}")]
    Unsupported { path: PathBuf, what: String },
    /// Well-formed input that violates a documented precondition.
    #[error("invalid input: {0}")]
    InvalidInput(String),
    /// No GPU adapter matched the request.
    #[error(
        "no GPU adapter matches `{requested}`; found: [{}]. {hint}",
        available.join("; ")
    )]
    NoAdapter {
        requested: String,
        available: Vec<String>,
        hint: &'static str,
    },
    /// The device could not be created (limits or features refused).
    #[error("could not open device on `{adapter}`: {message}")]
    RequestDevice { adapter: String, message: String },
    /// The device was lost (driver reset, crash, timeout).
    #[error("GPU device lost: {0}")]
    DeviceLost(String),
    /// A host allocation failed (the request is too large for this machine).
    #[error("not enough memory: {0}")]
    HostMemory(String),
    /// An allocation on the device failed.
    #[error("GPU out of memory while {0}")]
    OutOfMemory(String),
    /// A WGSL kernel or shader failed to parse, validate or build a pipeline.
    #[error("kernel `{name}`: {message}")]
    Kernel { name: String, message: String },
    /// wgpu validation failed outside pipeline creation (bind groups, dispatch).
    #[error("GPU validation error in `{label}`: {message}")]
    Validation { label: String, message: String },
    /// Mapping a buffer for readback failed.
    #[error("readback of `{label}` failed: {message}")]
    Readback { label: String, message: String },
}

/// Library result type.
pub type Result<T, E = Error> = std::result::Result<T, E>;

impl Error {
    /// Shorthand for [`Error::Format`].
    pub fn format(
        path: impl Into<PathBuf>,
        at: Position,
        expected: impl Into<String>,
        found: impl Into<String>,
    ) -> Self {
        Error::Format {
            path: path.into(),
            at,
            expected: expected.into(),
            found: found.into(),
        }
    }

    /// Shorthand for [`Error::Io`].
    pub fn io(path: impl Into<PathBuf>, error: std::io::Error) -> Self {
        Error::Io {
            path: path.into(),
            error,
        }
    }
}
