//! JSON reports: printed with `--json`, written atomically with `--report`,
//! and the human-readable text form of the same data.

use std::path::Path;

use serde_json::Value;

/// Writes `value` as pretty JSON to `path` (atomically).
pub fn write_json(path: &Path, value: &Value) -> anyhow::Result<()> {
    let mut text = serde_json::to_string_pretty(value)?;
    text.push('\n');
    crate::foundation::fs::write_atomic(path, text.as_bytes())?;
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

/// Prints `value` as JSON (`json`) or text on stdout and writes it to `report`.
pub fn emit(value: &Value, json: bool, report: Option<&Path>) -> anyhow::Result<()> {
    if json {
        println!("{}", serde_json::to_string_pretty(value)?);
    } else {
        print!("{}", to_text(value));
    }
    if let Some(path) = report {
        write_json(path, value)?;
    }
    Ok(())
}

/// Writes `value` to `report` and prints it only with `json` (commands whose
/// main output is a file, not a table).
pub fn emit_optional(value: &Value, json: bool, report: Option<&Path>) -> anyhow::Result<()> {
    if json {
        println!("{}", serde_json::to_string_pretty(value)?);
    }
    if let Some(path) = report {
        write_json(path, value)?;
    }
    Ok(())
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
