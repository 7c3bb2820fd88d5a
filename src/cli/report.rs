//! Printing and writing reports ([`crate::foundation::report`]): printed
//! with `--json`, written atomically with `--report`, shown as text
//! otherwise — all through [`emit`] and [`write`].

use std::path::{Path, PathBuf};

use serde_json::Value;

pub use crate::foundation::report::Report;
use crate::foundation::report::Versioned;

/// The report as pretty JSON: its schema first, then the fields in the
/// struct's order.
pub fn to_json<R: Report>(report: &R) -> anyhow::Result<String> {
    Ok(crate::foundation::report::to_json(report)?)
}

/// Writes `report` as pretty JSON to `path` (atomically).
pub fn write<R: Report>(path: &Path, report: &R) -> anyhow::Result<()> {
    let mut text = to_json(report)?;
    text.push('\n');
    crate::foundation::fs::write_atomic(path, text.as_bytes())?;
    Ok(())
}

/// `--report FILE` and `--json`, the same in every command with a report.
#[derive(Debug, Clone, clap::Args)]
pub struct ReportArgs {
    /// Write the JSON report to FILE (atomically).
    #[arg(id = "report_file", long = "report", value_name = "FILE")]
    pub file: Option<PathBuf>,
    /// Print the report as JSON on stdout.
    #[arg(long)]
    pub json: bool,
}

impl ReportArgs {
    /// Checks the report path before any work.
    pub fn check(&self) -> crate::Result<()> {
        match &self.file {
            Some(path) => crate::foundation::fs::check_output_path(path),
            None => Ok(()),
        }
    }

    /// Prints and writes `report` as these flags ask ([`emit`]).
    pub fn emit<R: Report>(&self, report: &R, show: Show) -> anyhow::Result<()> {
        emit(report, show, self.json, self.file.as_deref())
    }
}

/// Whether a report shows on stdout without `--json`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Show {
    /// The report is the command's output (`stats`, `info`, `hull`,
    /// `scan`, `polyhedrize`, `phantom`): as text without `--json`.
    Always,
    /// The command's output is a file (`mc`, `cut`, `relax`, `demo`,
    /// `bench`): the report shows only with `--json`.
    WithJson,
}

/// Prints `report` (JSON with `json`, else text where `show` says so) and
/// writes it to `path`.
pub fn emit<R: Report>(
    report: &R,
    show: Show,
    json: bool,
    path: Option<&Path>,
) -> anyhow::Result<()> {
    if json {
        println!("{}", to_json(report)?);
    } else if show == Show::Always {
        let value = serde_json::to_value(Versioned::new(report))?;
        print!("{}", to_text(&value));
    }
    if let Some(path) = path {
        write(path, report)?;
    }
    Ok(())
}

/// Rows of an array of objects the text form shows in full; a longer one
/// (a label table of an intensity volume: 256 rows) shows its first
/// [`TEXT_HEAD`] and last [`TEXT_TAIL`] rows around a line that counts the
/// rest and points at `--json` / `--report`, which keep every row.
const TEXT_ROWS: usize = 24;
const TEXT_HEAD: usize = 16;
const TEXT_TAIL: usize = 4;

/// Renders a JSON value as indented `key: value` lines for terminals.
/// Arrays of scalars print on one line; arrays of objects one object per
/// line (at most [`TEXT_ROWS`] of them).
pub fn to_text(value: &Value) -> String {
    let mut out = String::new();
    write_text(&mut out, value, 0);
    out
}

fn inline(value: &Value) -> String {
    match value {
        Value::Null => "-".into(),
        Value::String(s) => s.clone(),
        Value::Array(a) => {
            let items: Vec<String> = a.iter().map(inline).collect();
            format!("[{}]", items.join(", "))
        }
        Value::Object(m) => {
            let items: Vec<String> = m
                .iter()
                .map(|(k, v)| format!("{k}: {}", inline(v)))
                .collect();
            format!("{{{}}}", items.join(", "))
        }
        other => other.to_string(),
    }
}

fn write_text(out: &mut String, value: &Value, depth: usize) {
    let pad = "  ".repeat(depth);
    match value {
        Value::Object(m) => {
            for (k, v) in m {
                match v {
                    Value::Object(_) => {
                        out.push_str(&format!("{pad}{k}:\n"));
                        write_text(out, v, depth + 1);
                    }
                    Value::Array(a) if a.iter().any(|x| x.is_object()) => {
                        out.push_str(&format!("{pad}{k}: ({} entries)\n", a.len()));
                        let elided = a.len() > TEXT_ROWS;
                        for (i, x) in a.iter().enumerate() {
                            if elided && i == TEXT_HEAD {
                                out.push_str(&format!(
                                    "{pad}  … {} more (every entry with --json or --report)\n",
                                    a.len() - TEXT_HEAD - TEXT_TAIL
                                ));
                            }
                            if !elided || i < TEXT_HEAD || i >= a.len() - TEXT_TAIL {
                                out.push_str(&format!("{pad}  [{i}] {}\n", inline(x)));
                            }
                        }
                    }
                    _ => out.push_str(&format!("{pad}{k}: {}\n", inline(v))),
                }
            }
        }
        other => out.push_str(&format!("{pad}{}\n", inline(other))),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    #[test]
    fn long_tables_are_elided_in_text_only() {
        let rows = |n: usize| (0..n).map(|i| json!({"value": i})).collect::<Vec<_>>();
        let short = to_text(&json!({"labels": rows(TEXT_ROWS)}));
        assert_eq!(short.lines().count(), 1 + TEXT_ROWS, "{short}");
        assert!(!short.contains("more"));
        let long = to_text(&json!({"labels": rows(255)}));
        let lines: Vec<&str> = long.lines().collect();
        assert_eq!(lines.len(), 1 + TEXT_HEAD + 1 + TEXT_TAIL, "{long}");
        assert_eq!(lines[0], "labels: (255 entries)");
        assert_eq!(lines[1], "  [0] {value: 0}");
        assert_eq!(lines[TEXT_HEAD], "  [15] {value: 15}");
        assert_eq!(
            lines[TEXT_HEAD + 1],
            "  … 235 more (every entry with --json or --report)"
        );
        assert_eq!(lines[TEXT_HEAD + 2], "  [251] {value: 251}");
        assert_eq!(*lines.last().unwrap(), "  [254] {value: 254}");
    }
}
