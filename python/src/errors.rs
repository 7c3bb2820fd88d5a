//! The engine's errors as Python exceptions: one class per kind, all
//! subclasses of `chisel.ChiselError` (defined in `chisel/errors.py`, so
//! that `ParameterError` is also a `ValueError` and `IoError` an
//! `OSError`), carrying the engine's message (file, position, expected).

use chisel::Error;
use pyo3::prelude::*;
use pyo3::types::PyType;

/// The exception class (in `chisel.errors`) of an engine error.
fn class_name(e: &Error) -> &'static str {
    match e.root() {
        Error::Io { .. } => "IoError",
        Error::Format { .. } | Error::Unsupported { .. } => "FormatError",
        _ if chisel::io::exceeds_a_limit(e) => "LimitError",
        // Past the data a file holds: a truncated file.
        Error::Size { .. } => "FormatError",
        Error::Limit { .. } | Error::HostMemory { .. } => "LimitError",
        Error::InvalidParameter { .. }
        | Error::Mismatch { .. }
        | Error::Empty { .. }
        | Error::InvalidData { .. }
        | Error::Unknown { .. }
        | Error::OutputIsInput { .. } => "ParameterError",
        Error::Refused(_) => "RefusedError",
        Error::NoAdapter { .. }
        | Error::RequestDevice { .. }
        | Error::DeviceLost(_)
        | Error::OutOfMemory { .. }
        | Error::Kernel { .. }
        | Error::Validation { .. }
        | Error::Readback { .. } => "GpuError",
        Error::Cancelled { .. } => "CancelledError",
        Error::Internal(_) | Error::In { .. } => "InternalError",
    }
}

/// `e` as the `chisel.errors` exception of its kind, its message the
/// engine's. An `IoError` (an `OSError`) also carries the errno. Should the
/// classes not import, a `RuntimeError` with the message.
pub fn to_py(e: Error) -> PyErr {
    let message = e.to_string();
    Python::attach(|py| {
        let class = py
            .import("chisel.errors")
            .and_then(|m| m.getattr(class_name(&e)))
            .and_then(|c| Ok(c.cast_into::<PyType>()?));
        match (class, e.root()) {
            (Ok(class), Error::Io { error, .. }) => match error.raw_os_error() {
                Some(errno) => PyErr::from_type(class, (errno, message)),
                None => PyErr::from_type(class, message),
            },
            (Ok(class), _) => PyErr::from_type(class, message),
            (Err(_), _) => pyo3::exceptions::PyRuntimeError::new_err(message),
        }
    })
}

/// `Result<T, chisel::Error>` → `PyResult<T>`.
pub trait IntoPy<T> {
    fn py_err(self) -> PyResult<T>;
}

impl<T> IntoPy<T> for chisel::Result<T> {
    fn py_err(self) -> PyResult<T> {
        self.map_err(to_py)
    }
}
