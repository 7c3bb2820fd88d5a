//! File formats (SPEC §0.5): meshes and volumes in, meshes and volumes out.
//!
//! | format | read | write | extension |
//! |---|---|---|---|
//! | VTK legacy POLYDATA | ASCII + BINARY (big-endian), POLYGONS, TRIANGLE_STRIPS, 5.1 OFFSETS/CONNECTIVITY | ASCII, scalars as `POINT_DATA SCALARS` | `.vtk` |
//! | VTK legacy STRUCTURED_POINTS | ASCII + BINARY, the first point `SCALARS` | BINARY, axis-aligned volumes | `.vtk` |
//! | VTK XML ImageData / PolyData | ascii, base64, appended raw/base64, zlib, `UInt32`/`UInt64` headers, both byte orders | appended raw | `.vti`, `.vtp` |
//! | DICOM | files and series in a directory (`dicom`, on dicom-rs) | — | any, or none |
//! | PLY | ascii, binary_little_endian, binary_big_endian | binary little-endian, scalars as extra `float` vertex properties | `.ply` |
//! | Wavefront OBJ | `v`, `f` (`v/vt/vn`, negative indices, polygons) | `v`, `f` (no scalars) | `.obj` |
//! | STL | ASCII + binary, identical corners welded | binary (no scalars) | `.stl` |
//! | MovieBYU (seed 000) | one or more parts, polygons | one part (no scalars) | `.byu`, `.g` |
//! | NRRD | attached/detached, raw/gzip/ascii, both endians, multi-file | attached raw (`.nrrd`), detached header + `<stem>.raw` (`.nhdr`) | `.nrrd`, `.nhdr` |
//! | MetaImage | `LOCAL`/separate/pattern/`LIST` data, zlib, both endians | `.mha` with `LOCAL` data, `.mhd` + `<stem>.raw` | `.mha`, `.mhd` |
//! | NIfTI-1 | single file, both endians, plain or gzip | little-endian, plain or gzip | `.nii`, `.nii.gz` |
//! | raw samples | [`read_raw_volume`] with a [`RawSpec`] | — | any |
//!
//! **Which reader.** A file's first bytes pick the reader where the format
//! has a magic (`detect`); otherwise its extension does. A directory is a
//! DICOM series.
//!
//! **Why hand-written parsers.** Every reader here must report the file, the
//! position (line for text, byte for binary) and what it expected, and must
//! check every size a header announces against the file size and the memory
//! budget *before* allocating; that is easiest to guarantee, and to test,
//! when one small tokenizer (`text::Scanner`) is shared by all readers. The
//! formats themselves are short. Crates do the rest: flate2 (zlib, gzip),
//! quick-xml and base64 (VTK XML), and the dicom-rs crates for all of DICOM
//! (its element lengths and RLE fragments checked first, see `dicom`).
//!
//! **Guarantees.** Readers never panic on input data and never return a
//! partial result: a count field larger than the rest of the file is an
//! [`Error::Size`] (checked before allocating), malformed tokens, non-finite
//! coordinates, out-of-range indices and polygons with fewer than 3 corners
//! are [`Error::Format`], and orientations the data model cannot hold
//! (oblique or flipped axes) are [`Error::Unsupported`]. The memory budget
//! is [`memory_budget`]: `CHISEL_MAX_INPUT_BYTES` bytes, 16 GiB by default.
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
mod detect;
mod dicom;
mod metaimage;
mod nifti;
mod nrrd;
mod obj;
mod ply;
mod raw;
mod stl;
mod text;
mod vtk;
mod vtk_xml;

/// A configuration file (plan, scene) as text, within the input budget.
pub use config::read_text;
pub use dicom::SeriesInfo;
pub use raw::{RawSpec, read_raw_volume};

use detect::{Format, MeshFormat, VolumeFormat, format_of, mesh_by_extension, volume_by_extension};

use std::path::Path;

use crate::foundation::fs::{check_output_path, write_atomic_with};
use crate::{Error, Position, Result, TriMesh, Volume};

use crate::foundation::alloc::memory_budget;

/// Limit kind used in [`Error::Size`] for the memory budget.
pub(crate) const BUDGET_KIND: &str = "the memory budget (CHISEL_MAX_INPUT_BYTES)";
/// [`Error::Size`]'s `limit_kind` when a size does not fit the address space.
pub(crate) const ADDRESS_SPACE_KIND: &str = "the address space";

/// Whether `error` is an input past a resource limit (the memory budget,
/// the address space) rather than a file whose data ends short of what its
/// header promises (every other [`Error::Size`]).
pub fn exceeds_a_limit(error: &Error) -> bool {
    match error.root() {
        Error::Size { limit_kind, .. } => [BUDGET_KIND, ADDRESS_SPACE_KIND].contains(limit_kind),
        Error::Limit { .. } | Error::HostMemory { .. } => true,
        _ => false,
    }
}

/// Checks `needed` bytes for `what` against the budget before allocating.
pub(crate) fn check_budget(path: &Path, at: Position, what: &str, needed: u64) -> Result<()> {
    let limit = memory_budget();
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

/// The product of sizes read from a file, saturating: the size and budget
/// checks that follow refuse a saturated product.
pub(crate) fn saturating_product(sizes: impl Iterator<Item = u64>) -> u64 {
    sizes.fold(1, u64::saturating_mul)
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
    let limit = memory_budget();
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
    mesh_by_extension(path).map(|_| ())
}

/// What a reader passed over or changed on the way (arrays it skipped,
/// polygons it triangulated), for the user to see.
pub type Notes = Vec<String>;

/// Whether `path` holds a volume rather than a mesh: a directory (DICOM),
/// or a file whose first bytes or extension name a volume format.
pub fn is_volume(path: &Path) -> Result<bool> {
    Ok(match format_of(path)? {
        Some(format) => matches!(format, Format::Volume(_)),
        None => names_volume(path),
    })
}

/// Whether `path`'s extension names a volume format (`.vtk` names both
/// kinds and counts as a mesh here).
pub fn names_volume(path: &Path) -> bool {
    mesh_by_extension(path).is_err() && volume_by_extension(path).is_ok()
}

fn wrong_kind(path: &Path, expected: &str, found: &str) -> Error {
    Error::format(path, Position::Whole, expected, found)
}

/// Reads a triangle mesh; the format follows the first bytes, else the
/// extension (see the module table). Polygons are fan-triangulated, strips
/// unrolled with alternating winding; the result passes
/// [`TriMesh::validate`].
pub fn read_mesh(path: &Path) -> Result<TriMesh> {
    read_mesh_noted(path).map(|(mesh, _)| mesh)
}

/// [`read_mesh`], with the reader's [`Notes`].
pub fn read_mesh_noted(path: &Path) -> Result<(TriMesh, Notes)> {
    let format = match format_of(path)? {
        Some(Format::Mesh(m)) => m,
        Some(other) => return Err(wrong_kind(path, "a mesh", other.name())),
        None => mesh_by_extension(path)?,
    };
    // The first bytes must begin the format before the rest is read.
    let bytes = read_whole_with(path, |head| match format {
        MeshFormat::Vtk => vtk::magic(path, head).map(|_| None),
        MeshFormat::Vtp => vtk_xml_head(path, head),
        MeshFormat::Ply => ply::magic(path, head).map(|_| None),
        MeshFormat::Stl => Ok(stl::implied_len(head)),
        MeshFormat::Obj => sniff_text(path, head, "OBJ"),
        MeshFormat::Byu => sniff_text(path, head, "MovieBYU"),
    })?;
    let mut notes = Notes::new();
    let mesh = match format {
        MeshFormat::Vtk => vtk::read(path, &bytes)?,
        MeshFormat::Vtp => {
            let (mesh, poly) = vtk_xml::read_poly(path, &bytes)?;
            notes = poly.notes();
            mesh
        }
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
    Ok((mesh, notes))
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
/// fields (PLY, VTK and VTP do; OBJ, STL and BYU drop them).
pub fn mesh_format_carries_scalars(path: &Path) -> bool {
    matches!(
        mesh_by_extension(path),
        Ok(MeshFormat::Ply | MeshFormat::Vtk | MeshFormat::Vtp)
    )
}

/// Writes a mesh atomically; the format follows the extension: `.ply`
/// (binary little-endian, scalars as `float` vertex properties), `.vtk`
/// (ASCII legacy, scalars as `POINT_DATA SCALARS`), `.vtp` (VTK XML
/// PolyData, appended raw data, scalars as `Float32` point data), `.obj`,
/// `.stl` (binary), `.byu`/`.g`. Scalar names are written with whitespace
/// replaced by `_` (and `x`/`y`/`z` prefixed with `scalar_`), so they read
/// back as one token. The mesh is validated first; nothing is written if
/// it is invalid.
pub fn write_mesh(path: &Path, mesh: &TriMesh) -> Result<()> {
    let format = mesh_by_extension(path)?;
    mesh.validate()?;
    write_atomic_with(path, |w| match format {
        MeshFormat::Vtk => vtk::write(w, mesh),
        MeshFormat::Vtp => vtk_xml::write_poly(w, mesh),
        MeshFormat::Ply => ply::write(w, mesh),
        MeshFormat::Obj => obj::write(w, mesh),
        MeshFormat::Stl => stl::write(w, mesh),
        MeshFormat::Byu => byu::write(w, mesh),
    })
}

/// Checks an output volume path: [`check_output_path`] and a known extension.
pub fn check_volume_output(path: &Path) -> Result<()> {
    check_output_path(path)?;
    match volume_by_extension(path)? {
        VolumeFormat::Dicom => Err(Error::Unsupported {
            path: path.into(),
            what: "writing DICOM (chisel reads DICOM series; write .nrrd, .nii.gz, .mha or .vti)"
                .into(),
        }),
        _ => Ok(()),
    }
}

/// How to read a volume.
#[derive(Debug, Clone, Default)]
pub struct ReadOptions {
    /// The SeriesInstanceUID to read from a DICOM directory holding several
    /// series ([`dicom_series`] lists them).
    pub series: Option<String>,
}

/// The series of the DICOM image files under `dir` (up to four levels
/// down), by SeriesInstanceUID.
pub fn dicom_series(dir: &Path) -> Result<Vec<SeriesInfo>> {
    dicom::list_series(dir)
}

/// Reads a volume; the format follows the first bytes, else the extension
/// (see the module table); a directory is a DICOM series. Spacing, origin,
/// axes and anatomical space are kept; 2-D images have `dims = [nx, ny, 1]`.
pub fn read_volume(path: &Path) -> Result<Volume> {
    read_volume_with(path, &ReadOptions::default()).map(|(v, _)| v)
}

/// [`read_volume`] with options, and the reader's [`Notes`].
pub fn read_volume_with(path: &Path, options: &ReadOptions) -> Result<(Volume, Notes)> {
    let format = match format_of(path)? {
        Some(Format::Volume(v)) => v,
        Some(other) => return Err(wrong_kind(path, "a volume", other.name())),
        None => volume_by_extension(path)?,
    };
    if options.series.is_some() && format != VolumeFormat::Dicom {
        return Err(Error::param(
            "series",
            options.series.clone().unwrap_or_default(),
            "applies to DICOM directories only",
        ));
    }
    let mut notes = Notes::new();
    let volume = match format {
        VolumeFormat::Nrrd | VolumeFormat::Nhdr => nrrd::read(path)?,
        VolumeFormat::Mha | VolumeFormat::Mhd => metaimage::read(path)?,
        VolumeFormat::Nii | VolumeFormat::NiiGz => nifti::read(path)?,
        VolumeFormat::Dicom => dicom::read(path, options.series.as_deref())?,
        VolumeFormat::Vtk => {
            let bytes = read_whole_with(path, |head| vtk::magic(path, head).map(|_| None))?;
            let points = vtk::read_structured_points(path, &bytes)?;
            notes = skipped_arrays(points.skipped);
            points.volume
        }
        VolumeFormat::Vti => {
            let bytes = read_whole_with(path, |head| vtk_xml_head(path, head))?;
            let (volume, skipped) = vtk_xml::read_image(path, &bytes)?;
            notes = skipped_arrays(skipped);
            volume
        }
    };
    Ok((volume, notes))
}

/// A sniff for VTK XML: the first bytes open a `<VTKFile type="...">`.
fn vtk_xml_head(path: &Path, head: &[u8]) -> Result<Option<u64>> {
    match vtk_xml::dataset_type(head) {
        Some(_) => Ok(None),
        None => Err(Error::format(
            path,
            Position::Byte(0),
            "a VTK XML file (`<VTKFile type=...>`)",
            "other bytes",
        )),
    }
}

fn skipped_arrays(names: Vec<String>) -> Notes {
    if names.is_empty() {
        Notes::new()
    } else {
        vec![format!(
            "skipped data arrays (one scalar array is read as the volume): {}",
            names.join(", ")
        )]
    }
}

/// Writes a volume atomically; the format follows the extension:
/// `.nrrd` (attached header, raw little-endian), `.nhdr` (detached header +
/// `<stem>.raw`), `.mha` (`ElementDataFile = LOCAL`), `.mhd` (+ `<stem>.raw`),
/// `.nii` and `.nii.gz` (NIfTI-1, little-endian, `vox_offset` 352), `.vti`
/// (VTK XML ImageData with `Direction`), `.vtk` (legacy STRUCTURED_POINTS,
/// BINARY; axis-aligned volumes only, the format has no direction). For the
/// two-file forms the data file is written (atomically) before the header.
pub fn write_volume(path: &Path, v: &Volume) -> Result<()> {
    match volume_by_extension(path)? {
        VolumeFormat::Nrrd => nrrd::write_attached(path, v),
        VolumeFormat::Nhdr => nrrd::write_detached(path, v),
        VolumeFormat::Mha => metaimage::write_local(path, v),
        VolumeFormat::Mhd => metaimage::write_detached(path, v),
        VolumeFormat::Nii => nifti::write(path, v, false),
        VolumeFormat::NiiGz => nifti::write(path, v, true),
        VolumeFormat::Vti => write_atomic_with(path, |w| vtk_xml::write_image(w, v)),
        VolumeFormat::Vtk => {
            if !vtk::structured_points_can_hold(v) {
                return Err(Error::Unsupported {
                    path: path.into(),
                    what: "a rotated or mirrored volume in legacy VTK STRUCTURED_POINTS (the \
                           format has no direction; write .vti, .nrrd or .nii.gz)"
                        .into(),
                });
            }
            write_atomic_with(path, |w| vtk::write_structured_points(w, v))
        }
        VolumeFormat::Dicom => check_volume_output(path),
    }
}
