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
        Error::Size { .. } | Error::Limit { .. } | Error::HostMemory { .. } => "LimitError",
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

/// `e` as the `chisel.errors` exception of its kind.
pub fn to_py(e: Error) -> PyErr {
    Python::attach(|py| {
        let class = py
            .import("chisel.errors")
            .and_then(|m| m.getattr(class_name(&e)))
            .and_then(|c| Ok(c.cast_into::<PyType>()?));
        match class {
            Ok(class) => PyErr::from_type(class, e.to_string()),
            Err(import_error) => import_error,
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
