//! Progress callbacks and Ctrl-C for long operations: between chunks of
//! work (a structure of a scan, a frame of an animation) the engine
//! takes the GIL, checks for signals and calls the caller's
//! `progress(done, total)`; an exception from either stops the operation
//! and is raised as it was.

use chisel::Error;
use pyo3::prelude::*;

/// The caller's callback and what stopped the operation, if anything.
#[derive(Debug)]
pub struct Progress {
    callback: Option<Py<PyAny>>,
    what: String,
    stopped: Option<PyErr>,
}

impl Progress {
    pub fn new(callback: Option<Py<PyAny>>, what: impl Into<String>) -> Self {
        Progress {
            callback,
            what: what.into(),
            stopped: None,
        }
    }

    /// After a chunk: Ctrl-C, then the callback, with the GIL held.
    pub fn tick(&mut self, done: usize, total: usize) -> chisel::Result<()> {
        Python::attach(|py| {
            let outcome = py.check_signals().and_then(|()| match &self.callback {
                Some(f) => f.call1(py, (done, total)).map(|_| ()),
                None => Ok(()),
            });
            outcome.map_err(|e| {
                self.stopped = Some(e);
                Error::Cancelled {
                    what: self.what.clone(),
                }
            })
        })
    }

    /// The operation's result, with the exception that stopped it raised
    /// as it was (a `KeyboardInterrupt`, the callback's own).
    pub fn finish<T>(self, result: chisel::Result<T>) -> PyResult<T> {
        match (result, self.stopped) {
            (Ok(value), _) => Ok(value),
            (Err(_), Some(e)) => Err(e),
            (Err(e), None) => Err(crate::errors::to_py(e)),
        }
    }
}
