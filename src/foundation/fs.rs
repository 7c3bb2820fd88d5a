//! Output files: path checks made before any work, and atomic writes (a
//! temp file in the target's folder, renamed over it once complete), so an
//! interrupted or failed write leaves no partial output and no temp file.

use std::io::Write;
use std::path::Path;

use crate::error::{Error, Position, Result};

/// Refuses a directory where a file is expected (before the extension is
/// looked at, so the message says what is wrong).
pub(crate) fn not_a_directory(path: &Path, expected: &str) -> Result<()> {
    if path.is_dir() {
        return Err(Error::format(
            path,
            Position::Whole,
            expected,
            "a directory",
        ));
    }
    Ok(())
}

/// Checks, before any work is done, that `path` can be an output file: not
/// a directory, in a folder that exists. Commands call it for every output
/// up front, so a long job does not fail at its end.
pub fn check_output_path(path: &Path) -> Result<()> {
    not_a_directory(path, "an output file path")?;
    check_parent_folder(path)
}

/// Checks an output image path: [`check_output_path`] and a `.png` name
/// (previews are PNG; a `.jpg` name would hold PNG data).
pub fn check_png_output(path: &Path) -> Result<()> {
    check_output_path(path)?;
    if file_name_lower(path).ends_with(".png") {
        return Ok(());
    }
    let ext = path
        .extension()
        .map_or(String::new(), |e| e.to_string_lossy().into_owned());
    Err(Error::Unsupported {
        path: path.into(),
        what: format!(
            "image {} (previews are PNG: name the file .png)",
            extension_text(&ext)
        ),
    })
}

/// Checks that the folder `path` would be written into exists.
pub fn check_parent_folder(path: &Path) -> Result<()> {
    let dir = path
        .parent()
        .filter(|p| !p.as_os_str().is_empty())
        .unwrap_or(Path::new("."));
    if dir.is_dir() {
        return Ok(());
    }
    let why = if dir.exists() {
        format!("{} is a file, not a folder", dir.display())
    } else {
        format!("folder {} does not exist", dir.display())
    };
    Err(Error::io(
        path,
        std::io::Error::new(std::io::ErrorKind::NotFound, why),
    ))
}

/// Lower-case file name, for extension dispatch (`.nii.gz` is one extension).
pub(crate) fn file_name_lower(path: &Path) -> String {
    path.file_name()
        .map(|n| n.to_string_lossy().to_ascii_lowercase())
        .unwrap_or_default()
}

/// `extension `.ext`` for messages, or `file name without extension`.
pub(crate) fn extension_text(ext: &str) -> String {
    if ext.is_empty() {
        "file name without extension".into()
    } else {
        format!("extension `.{ext}`")
    }
}

/// Writes `bytes` to `path` atomically (temp file in the same folder + rename).
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<()> {
    write_atomic_with(path, |w| w.write_all(bytes))
}

/// Streams `fill`'s output to a temp file next to `path` and renames it over
/// `path` once `fill` succeeded and the data is flushed and synced. On any
/// error the temp file is removed and `path` is left as it was.
pub fn write_atomic_with<F>(path: &Path, fill: F) -> Result<()>
where
    F: FnOnce(&mut dyn Write) -> std::io::Result<()>,
{
    check_output_path(path)?;
    let dir = path
        .parent()
        .filter(|p| !p.as_os_str().is_empty())
        .unwrap_or(Path::new("."));
    let prefix = format!(
        ".{}.",
        path.file_name()
            .map(|n| n.to_string_lossy())
            .unwrap_or_default()
    );
    let mut builder = tempfile::Builder::new();
    builder.prefix(&prefix).suffix(".tmp");
    // Outputs are ordinary files (0644 less the umask), not the 0600 of a
    // private temp file.
    #[cfg(unix)]
    builder.permissions(std::os::unix::fs::PermissionsExt::from_mode(0o644));
    let tmp = builder.tempfile_in(dir).map_err(|e| Error::io(path, e))?;
    let mut w = std::io::BufWriter::new(tmp);
    fill(&mut w).map_err(|e| Error::io(path, e))?;
    let tmp = w
        .into_inner()
        .map_err(|e| Error::io(path, e.into_error()))?;
    tmp.as_file().sync_all().map_err(|e| Error::io(path, e))?;
    tmp.persist(path).map_err(|e| Error::io(path, e.error))?;
    Ok(())
}
