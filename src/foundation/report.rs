//! Reports: one typed serde struct per operation. Every report starts
//! with its `schema`, `chisel.<command>/<version>`: the version goes up
//! when a field changes meaning or goes away (new fields keep it). The
//! command line prints and writes them (`--json`, `--report`); the Python
//! package returns the same JSON as dictionaries.

use serde::Serialize;

/// An operation's report.
pub trait Report: Serialize {
    /// `chisel.<command>/<version>`.
    const SCHEMA: &'static str;
}

/// A report with its schema as the first field.
#[derive(Debug, Serialize)]
pub struct Versioned<'a, R> {
    pub schema: &'static str,
    #[serde(flatten)]
    pub report: &'a R,
}

impl<'a, R: Report> Versioned<'a, R> {
    pub fn new(report: &'a R) -> Self {
        Versioned {
            schema: R::SCHEMA,
            report,
        }
    }
}

/// The report as pretty JSON: its schema first, then the fields in the
/// struct's order.
pub fn to_json<R: Report>(report: &R) -> crate::Result<String> {
    serde_json::to_string_pretty(&Versioned::new(report))
        .map_err(|e| crate::Error::Internal(format!("{}: report to JSON: {e}", R::SCHEMA)))
}
