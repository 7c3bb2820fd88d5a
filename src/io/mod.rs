//! File formats (SPEC §0.5). PLACEHOLDER — replaced by the io work.
use crate::{Error, Result, TriMesh, Volume};
use std::path::Path;

/// Reads a triangle mesh; the format follows the extension.
pub fn read_mesh(path: &Path) -> Result<TriMesh> {
    Err(Error::Unsupported {
        path: path.into(),
        what: "not yet".into(),
    })
}

/// Writes a mesh atomically; the format follows the extension.
pub fn write_mesh(path: &Path, _mesh: &TriMesh) -> Result<()> {
    Err(Error::Unsupported {
        path: path.into(),
        what: "not yet".into(),
    })
}

/// Reads a volume; the format follows the extension.
pub fn read_volume(path: &Path) -> Result<Volume> {
    Err(Error::Unsupported {
        path: path.into(),
        what: "not yet".into(),
    })
}

/// Writes `bytes` to `path` atomically (temp file in the same folder + rename).
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<()> {
    let dir = path
        .parent()
        .filter(|p| !p.as_os_str().is_empty())
        .unwrap_or(Path::new("."));
    let mut tmp = tempfile::NamedTempFile::new_in(dir).map_err(|e| Error::io(path, e))?;
    std::io::Write::write_all(&mut tmp, bytes).map_err(|e| Error::io(path, e))?;
    tmp.persist(path).map_err(|e| Error::io(path, e.error))?;
    Ok(())
}
