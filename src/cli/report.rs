//! JSON reports: printed with `--json`, written atomically with `--report`,
//! and the human-readable text form of the same data.

use std::path::Path;

use serde_json::Value;

/// Writes `value` as pretty JSON to `path` (atomically).
pub fn write_json(path: &Path, value: &Value) -> anyhow::Result<()> {
    let mut text = serde_json::to_string_pretty(value)?;
    text.push('\n');
    crate::io::write_atomic(path, text.as_bytes())?;
    Ok(())
}

/// Renders a JSON value as indented `key: value` lines for terminals.
/// Arrays of scalars print on one line; arrays of objects one object per line.
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
                        for (i, x) in a.iter().enumerate() {
                            out.push_str(&format!("{pad}  [{i}] {}\n", inline(x)));
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
