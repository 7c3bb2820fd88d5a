//! Output files: path checks made before any work, and atomic writes (a
//! temp file in the target's folder, renamed over it once complete), so an
//! interrupted or failed write leaves no partial output and no temp file.
//!
//! **Inputs are never outputs.** While [`guard_inputs`] is on (the command
//! line turns it on for every command, with the paths the command names as
//! inputs), every file a reader opens (`open_input`) joins the guarded
//! inputs, and [`check_output_path`] (which every write goes through, and
//! which commands call for each output before any work) refuses a path that
//! is one of them: the same canonical path, or the same file (device and
//! inode) through a symbolic or hard link. Detached data files (an NHDR's
//! `.raw`) join when their header is read, so writing over one is refused
//! before the write.

use std::fs::{File, Metadata};
use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::Mutex;

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

/// One guarded input: its path as given, its canonical path and, on Unix,
/// its device and inode.
#[derive(Debug, Clone)]
struct Guarded {
    path: PathBuf,
    canonical: Option<PathBuf>,
    id: Option<(u64, u64)>,
}

impl Guarded {
    fn of(path: &Path, meta: Option<&Metadata>) -> Guarded {
        Guarded {
            path: path.to_path_buf(),
            canonical: canonical(path),
            id: meta
                .and_then(file_id)
                .or_else(|| std::fs::metadata(path).ok().and_then(|m| file_id(&m))),
        }
    }
}

/// The guarded inputs; `None` while the guard is off.
static INPUTS: Mutex<Option<Vec<Guarded>>> = Mutex::new(None);

/// Device and inode of a file (Unix; `None` elsewhere).
fn file_id(meta: &Metadata) -> Option<(u64, u64)> {
    #[cfg(unix)]
    {
        use std::os::unix::fs::MetadataExt;
        Some((meta.dev(), meta.ino()))
    }
    #[cfg(not(unix))]
    {
        let _ = meta;
        None
    }
}

/// The canonical form of `path`; for a file that does not exist (yet), its
/// canonical folder joined with its name.
fn canonical(path: &Path) -> Option<PathBuf> {
    std::fs::canonicalize(path).ok().or_else(|| {
        let dir = path
            .parent()
            .filter(|p| !p.as_os_str().is_empty())
            .unwrap_or(Path::new("."));
        Some(std::fs::canonicalize(dir).ok()?.join(path.file_name()?))
    })
}

/// Turns the input guard on (see the module docs) with the inputs the
/// running command names; files readers open join them. Turning it on again
/// starts a new list.
pub fn guard_inputs(declared: &[&Path]) {
    let list = declared.iter().map(|p| Guarded::of(p, None)).collect();
    *INPUTS.lock().unwrap_or_else(|e| e.into_inner()) = Some(list);
}

/// Opens `path` for reading as an input: the file and its metadata (after
/// the open, so they describe the file read); the file joins the guarded
/// inputs while the guard is on.
pub(crate) fn open_input(path: &Path) -> Result<(File, Metadata)> {
    let file = File::open(path).map_err(|e| Error::io(path, e))?;
    let meta = file.metadata().map_err(|e| Error::io(path, e))?;
    if let Some(list) = INPUTS.lock().unwrap_or_else(|e| e.into_inner()).as_mut() {
        list.push(Guarded::of(path, Some(&meta)));
    }
    Ok((file, meta))
}

/// Refuses `path` as an output while it is a guarded input.
fn check_not_input(path: &Path) -> Result<()> {
    let guard = INPUTS.lock().unwrap_or_else(|e| e.into_inner());
    let Some(list) = guard.as_ref() else {
        return Ok(());
    };
    let out = Guarded::of(path, None);
    let same = |g: &&Guarded| {
        (g.id.is_some() && g.id == out.id)
            || (g.canonical.is_some() && g.canonical == out.canonical)
    };
    match list.iter().find(same) {
        Some(g) => Err(Error::OutputIsInput {
            output: path.to_path_buf(),
            input: g.path.clone(),
        }),
        None => Ok(()),
    }
}

/// Checks, before any work is done, that `path` can be an output file: not
/// a directory, in a folder that exists, not a guarded input. Commands call
/// it for every output up front, so a long job does not fail at its end;
/// every write calls it again.
pub fn check_output_path(path: &Path) -> Result<()> {
    not_a_directory(path, "an output file path")?;
    check_parent_folder(path)?;
    check_not_input(path)
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
