//! File formats (SPEC §0.5): meshes and volumes in, meshes and volumes out.
//!
//! | format | read | write | extension |
//! |---|---|---|---|
//! | VTK legacy POLYDATA | ASCII + BINARY (big-endian), POLYGONS, TRIANGLE_STRIPS, 5.1 OFFSETS/CONNECTIVITY | ASCII, scalars as `POINT_DATA SCALARS` | `.vtk` |
//! | PLY | ascii, binary_little_endian, binary_big_endian | binary little-endian, scalars as extra `float` vertex properties | `.ply` |
//! | Wavefront OBJ | `v`, `f` (`v/vt/vn`, negative indices, polygons) | `v`, `f` (no scalars) | `.obj` |
//! | STL | ASCII + binary, identical corners welded | binary (no scalars) | `.stl` |
//! | MovieBYU (seed 000) | one or more parts, polygons | one part (no scalars) | `.byu`, `.g` |
//! | NRRD | attached/detached, raw/gzip/ascii, both endians, multi-file | attached raw (`.nrrd`), detached header + `<stem>.raw` (`.nhdr`) | `.nrrd`, `.nhdr` |
//! | MetaImage | `LOCAL`/separate/pattern/`LIST` data, zlib, both endians | `.mha` with `LOCAL` data, `.mhd` + `<stem>.raw` | `.mha`, `.mhd` |
//! | NIfTI-1 | single file, both endians, plain or gzip | little-endian, plain or gzip | `.nii`, `.nii.gz` |
//! | raw samples | [`read_raw_volume`] with a [`RawSpec`] | — | any |
//!
//! **Why hand-written parsers.** Every reader here must report the file, the
//! position (line for text, byte for binary) and what it expected, and must
//! check every size a header announces against the file size and the memory
//! budget *before* allocating; that is easiest to guarantee, and to test,
//! when one small tokenizer (`text::Scanner`) is shared by all readers. The
//! formats themselves are short. Only (de)compression uses a crate (`flate2`).
//!
//! **Guarantees.** Readers never panic on input data and never return a
//! partial result: a count field larger than the rest of the file is an
//! [`Error::Size`] (checked before allocating), malformed tokens, non-finite
//! coordinates, out-of-range indices and polygons with fewer than 3 corners
//! are [`Error::Format`], and orientations the data model cannot hold
//! (oblique or flipped axes) are [`Error::Unsupported`]. The memory budget
//! is [`input_budget`]: `CHISEL_MAX_INPUT_BYTES` bytes, 16 GiB by default.
//! Polygons are fan-triangulated `(p0, pi, pi+1)`; the winding of the file is
//! kept as it is. Volume samples stay in file order (x fastest, never flipped).
//!
//! **Outputs** are written to a temporary file in the target's folder and
//! renamed over the target ([`write_atomic`](crate::foundation::fs::write_atomic), [`write_atomic_with`]): an
//! interrupted or failed write leaves no partial output and no temp file.
//! Inputs are only ever opened for reading. OBJ, STL and BYU cannot carry
//! per-vertex scalars ([`mesh_format_carries_scalars`] says which formats do,
//! so callers can warn before a scalar field is dropped).

mod byu;
pub(crate) mod config;
mod metaimage;
mod nifti;
mod nrrd;
mod obj;
mod ply;
mod raw;
mod stl;
mod text;
mod vtk;

pub use raw::{RawSpec, read_raw_volume};

use std::path::Path;

use crate::foundation::fs::{
    check_output_path, extension_text, file_name_lower, not_a_directory, write_atomic_with,
};
use crate::{Error, Position, Result, TriMesh, Volume};

/// Environment variable overriding the memory budget for inputs, in bytes.
pub const BUDGET_ENV: &str = "CHISEL_MAX_INPUT_BYTES";

/// Default memory budget for one input: 16 GiB.
pub const DEFAULT_BUDGET: u64 = 16 << 30;

/// Limit kind used in [`Error::Size`] for the memory budget.
pub(crate) const BUDGET_KIND: &str = "the memory budget (CHISEL_MAX_INPUT_BYTES)";

/// The most bytes one input may make the readers allocate:
/// `CHISEL_MAX_INPUT_BYTES` when set to an integer, else [`DEFAULT_BUDGET`].
pub fn input_budget() -> u64 {
    std::env::var(BUDGET_ENV)
        .ok()
        .and_then(|v| v.trim().parse().ok())
        .unwrap_or(DEFAULT_BUDGET)
}

/// Checks `needed` bytes for `what` against the budget before allocating.
pub(crate) fn check_budget(path: &Path, at: Position, what: &str, needed: u64) -> Result<()> {
    let limit = input_budget();
    if needed > limit {
        return Err(Error::Size {
            path: path.into(),
            at,
            what: what.into(),
            needed,
            limit_kind: BUDGET_KIND,
            limit,
        });
    }
    Ok(())
}

/// Bytes a reader looks at before reading the rest of a file.
pub(crate) const SNIFF_BYTES: usize = 1 << 16;

/// The whole file, read boundedly whatever its kind (see [`read_whole_with`]).
pub(crate) fn read_whole(path: &Path) -> Result<Vec<u8>> {
    read_whole_with(path, |_| Ok(None))
}

/// The whole file, read boundedly whatever its kind: a regular file after
/// checking its length against the budget and never past that length (a
/// file that grows while read is an error); a stream (a pipe, a FIFO, a
/// device such as `/dev/zero`) up to the budget, in steps allocated
/// fallibly. `sniff` sees the first [`SNIFF_BYTES`] (or the whole file when
/// shorter) before anything else is read: it refuses bytes that cannot
/// begin the format, or returns the size the format's header implies,
/// which caps the read at one byte more (so the reader sees trailing data).
pub(crate) fn read_whole_with(
    path: &Path,
    sniff: impl FnOnce(&[u8]) -> Result<Option<u64>>,
) -> Result<Vec<u8>> {
    use std::io::Read;
    let (file, meta) = crate::foundation::fs::open_input(path)?;
    let regular = meta.is_file();
    let limit = input_budget();
    let what = if regular {
        "reading the file"
    } else {
        "reading the stream (not a regular file)"
    };
    let mut cap = if regular {
        check_budget(path, Position::Whole, what, meta.len())?;
        meta.len()
    } else {
        limit
    };
    let mut out: Vec<u8> = Vec::new();
    let mut reader = file.take(cap.saturating_add(1));
    let mut chunk = vec![0u8; SNIFF_BYTES];
    let mut sniff = Some(sniff);
    loop {
        let k = match reader.read(&mut chunk) {
            Ok(k) => k,
            Err(e) if e.kind() == std::io::ErrorKind::Interrupted => continue,
            Err(e) => return Err(Error::io(path, e)),
        };
        let len = out.len() as u64 + k as u64;
        if k > 0 && len > cap {
            return Err(if regular {
                Error::format(
                    path,
                    Position::Byte(cap),
                    format!("the end of the file at byte {cap}"),
                    "more data (the file grew while it was read)",
                )
            } else {
                Error::Size {
                    path: path.into(),
                    at: Position::Byte(cap),
                    what: what.into(),
                    needed: len,
                    limit_kind: BUDGET_KIND,
                    limit,
                }
            });
        }
        out.try_reserve(k).map_err(|_| Error::HostMemory {
            what: format!("{}: {what}", path.display()),
            bytes: len,
        })?;
        out.extend_from_slice(&chunk[..k]);
        if sniff.is_some() && (k == 0 || out.len() >= SNIFF_BYTES) {
            let implied = (sniff.take().expect("checked"))(&out)?;
            if let Some(n) = implied {
                // One byte past what the header implies: enough for the
                // reader to see trailing data, never more.
                let allowed = n.saturating_add(1);
                if allowed < cap {
                    cap = allowed;
                    let left = cap.saturating_sub(out.len() as u64);
                    reader = reader.into_inner().take(left);
                }
            }
        }
        if k == 0 {
            break;
        }
    }
    Ok(out)
}

/// A sniff for text formats: the first bytes hold no NUL byte.
pub(crate) fn sniff_text(path: &Path, head: &[u8], format: &str) -> Result<Option<u64>> {
    match head.iter().position(|&b| b == 0) {
        Some(at) => Err(Error::format(
            path,
            Position::Byte(at as u64),
            format!("{format} text"),
            "a NUL byte (binary data)",
        )),
        None => Ok(None),
    }
}

/// Checks an output mesh path: [`check_output_path`] and a known extension.
pub fn check_mesh_output(path: &Path) -> Result<()> {
    check_output_path(path)?;
    mesh_format(path).map(|_| ())
}

/// Mesh formats by extension.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum MeshFormat {
    Vtk,
    Ply,
    Obj,
    Stl,
    Byu,
}

fn mesh_format(path: &Path) -> Result<MeshFormat> {
    not_a_directory(path, "a mesh file")?;
    let name = file_name_lower(path);
    let ext = name.rsplit_once('.').map_or("", |(_, e)| e);
    Ok(match ext {
        "vtk" => MeshFormat::Vtk,
        "ply" => MeshFormat::Ply,
        "obj" => MeshFormat::Obj,
        "stl" => MeshFormat::Stl,
        "byu" | "g" => MeshFormat::Byu,
        _ => {
            return Err(Error::Unsupported {
                path: path.into(),
                what: format!(
                    "mesh {} (known: .vtk .ply .obj .stl .byu .g)",
                    extension_text(ext)
                ),
            });
        }
    })
}

/// Reads a triangle mesh; the format follows the extension (see the module
/// table). Polygons are fan-triangulated, strips unrolled with alternating
/// winding; the result passes [`TriMesh::validate`].
pub fn read_mesh(path: &Path) -> Result<TriMesh> {
    let format = mesh_format(path)?;
    // The first bytes must begin the format before the rest is read.
    let bytes = read_whole_with(path, |head| match format {
        MeshFormat::Vtk => vtk::magic(path, head).map(|_| None),
        MeshFormat::Ply => ply::magic(path, head).map(|_| None),
        MeshFormat::Stl => Ok(stl::implied_len(head)),
        MeshFormat::Obj => sniff_text(path, head, "OBJ"),
        MeshFormat::Byu => sniff_text(path, head, "MovieBYU"),
    })?;
    let mesh = match format {
        MeshFormat::Vtk => vtk::read(path, &bytes)?,
        MeshFormat::Ply => ply::read(path, &bytes)?,
        MeshFormat::Obj => obj::read(path, &bytes)?,
        MeshFormat::Stl => stl::read(path, &bytes)?,
        MeshFormat::Byu => byu::read(path, &bytes)?,
    };
    mesh.validate().map_err(|e| match e {
        Error::InvalidData { at, problem, .. } => Error::format(path, at, "a valid mesh", problem),
        Error::Mismatch {
            what,
            expected,
            found,
        } => Error::format(
            path,
            Position::Whole,
            format!("{expected} {what}"),
            found.to_string(),
        ),
        other => other,
    })?;
    Ok(mesh)
}

/// Reads a triangle mesh ([`read_mesh`]) for a command that needs
/// triangles: a file without any (vertices only, or nothing) is an error
/// that says so.
pub fn read_surface(path: &Path) -> Result<TriMesh> {
    let mesh = read_mesh(path)?;
    if mesh.triangles.is_empty() {
        return Err(Error::format(
            path,
            Position::Whole,
            "a mesh with triangles",
            format!("none ({} vertices and no faces)", mesh.positions.len()),
        ));
    }
    Ok(mesh)
}

/// Whether the format chosen by `path`'s extension stores per-vertex scalar
/// fields (PLY and VTK do; OBJ, STL and BYU drop them).
pub fn mesh_format_carries_scalars(path: &Path) -> bool {
    matches!(mesh_format(path), Ok(MeshFormat::Ply | MeshFormat::Vtk))
}

/// Writes a mesh atomically; the format follows the extension: `.ply`
/// (binary little-endian, scalars as `float` vertex properties), `.vtk`
/// (ASCII legacy, scalars as `POINT_DATA SCALARS`), `.obj`, `.stl` (binary),
/// `.byu`/`.g`. Scalar names are written with whitespace replaced by `_`
/// (and `x`/`y`/`z` prefixed with `scalar_`), so they read back as one token.
/// The mesh is validated first; nothing is written if it is invalid.
pub fn write_mesh(path: &Path, mesh: &TriMesh) -> Result<()> {
    let format = mesh_format(path)?;
    mesh.validate()?;
    write_atomic_with(path, |w| match format {
        MeshFormat::Vtk => vtk::write(w, mesh),
        MeshFormat::Ply => ply::write(w, mesh),
        MeshFormat::Obj => obj::write(w, mesh),
        MeshFormat::Stl => stl::write(w, mesh),
        MeshFormat::Byu => byu::write(w, mesh),
    })
}

/// Volume formats by extension.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum VolumeFormat {
    Nrrd,
    Nhdr,
    Mha,
    Mhd,
    Nii,
    NiiGz,
}

/// Checks an output volume path: [`check_output_path`] and a known extension.
pub fn check_volume_output(path: &Path) -> Result<()> {
    check_output_path(path)?;
    volume_format(path).map(|_| ())
}

fn volume_format(path: &Path) -> Result<VolumeFormat> {
    not_a_directory(path, "a volume file")?;
    let name = file_name_lower(path);
    if name.ends_with(".nii.gz") {
        return Ok(VolumeFormat::NiiGz);
    }
    let ext = name.rsplit_once('.').map_or("", |(_, e)| e);
    Ok(match ext {
        "nrrd" => VolumeFormat::Nrrd,
        "nhdr" => VolumeFormat::Nhdr,
        "mha" => VolumeFormat::Mha,
        "mhd" => VolumeFormat::Mhd,
        "nii" => VolumeFormat::Nii,
        _ => {
            return Err(Error::Unsupported {
                path: path.into(),
                what: format!(
                    "volume {} (known: .nrrd .nhdr .mha .mhd .nii .nii.gz; headerless raw \
                     samples are read through a .nhdr or .mhd header naming them)",
                    extension_text(ext)
                ),
            });
        }
    })
}

/// Reads a volume; the format follows the extension (see the module table).
/// Spacing and origin are kept; 2-D images have `dims = [nx, ny, 1]`.
pub fn read_volume(path: &Path) -> Result<Volume> {
    match volume_format(path)? {
        VolumeFormat::Nrrd | VolumeFormat::Nhdr => nrrd::read(path),
        VolumeFormat::Mha | VolumeFormat::Mhd => metaimage::read(path),
        VolumeFormat::Nii | VolumeFormat::NiiGz => nifti::read(path),
    }
}

/// Writes a volume atomically; the format follows the extension:
/// `.nrrd` (attached header, raw little-endian), `.nhdr` (detached header +
/// `<stem>.raw`), `.mha` (`ElementDataFile = LOCAL`), `.mhd` (+ `<stem>.raw`),
/// `.nii` and `.nii.gz` (NIfTI-1, little-endian, `vox_offset` 352). For the
/// two-file forms the data file is written (atomically) before the header.
pub fn write_volume(path: &Path, v: &Volume) -> Result<()> {
    match volume_format(path)? {
        VolumeFormat::Nrrd => nrrd::write_attached(path, v),
        VolumeFormat::Nhdr => nrrd::write_detached(path, v),
        VolumeFormat::Mha => metaimage::write_local(path, v),
        VolumeFormat::Mhd => metaimage::write_detached(path, v),
        VolumeFormat::Nii => nifti::write(path, v, false),
        VolumeFormat::NiiGz => nifti::write(path, v, true),
    }
}
