//! Positions and messages for configuration files (TOML plans and scenes,
//! JSON plans): errors name the file, the line and column, and the key or
//! value at fault.

use crate::Position;

/// Line and column (1-based, the column in characters) of byte `offset` in `text`.
pub(crate) fn line_column(text: &str, offset: usize) -> Position {
    let mut offset = offset.min(text.len());
    while !text.is_char_boundary(offset) {
        offset -= 1;
    }
    let before = &text[..offset];
    let line_start = before.rfind('\n').map_or(0, |i| i + 1);
    Position::LineColumn(
        before.matches('\n').count() + 1,
        before[line_start..].chars().count() + 1,
    )
}

/// A TOML error's message, with the offending key or value quoted when the
/// message does not already quote it (toml says only "duplicate key").
pub(crate) fn toml_message(text: &str, e: &toml::de::Error) -> String {
    let message = e.message().trim_end().to_string();
    let snippet = e
        .span()
        .and_then(|s| text.get(s))
        .map(str::trim)
        .filter(|t| !t.is_empty() && t.len() <= 60 && !t.contains('\n'));
    match snippet {
        Some(t) if !message.contains('`') && !message.contains('"') => format!("{message} `{t}`"),
        _ => message,
    }
}

/// A configuration file as text, read within the input budget; invalid
/// UTF-8 is an error at its byte offset.
pub fn read_text(path: &std::path::Path) -> crate::Result<String> {
    let bytes =
        super::read_whole_with(path, |head| super::sniff_text(path, head, "configuration"))?;
    String::from_utf8(bytes).map_err(|e| {
        crate::Error::format(
            path,
            Position::Byte(e.utf8_error().valid_up_to() as u64),
            "UTF-8 text",
            "an invalid byte sequence",
        )
    })
}
