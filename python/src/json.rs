//! Results cross to Python as JSON text (parsed into dicts there): the
//! engine's serde structs, the very form its reports take.

use chisel::Error;
use pyo3::PyResult;

/// `value` as JSON text.
pub fn to_json<T: serde::Serialize + ?Sized>(what: &str, value: &T) -> PyResult<String> {
    serde_json::to_string(value)
        .map_err(|e| crate::errors::to_py(Error::Internal(format!("{what} to JSON: {e}"))))
}
