//! Which format a file is in: by its first bytes where the format has a
//! magic (DICOM, NRRD, NIfTI, gzip, VTK legacy and XML, PLY, MetaImage),
//! else by its extension (OBJ, STL, MovieBYU). A directory is a DICOM
//! series. Writers go by the extension alone.

use std::path::Path;

use super::{SNIFF_BYTES, dicom, vtk, vtk_xml};
use crate::foundation::fs::{extension_text, file_name_lower, not_a_directory, open_input};
use crate::{Error, Result};

/// Mesh formats.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum MeshFormat {
    Vtk,
    Vtp,
    Ply,
    Obj,
    Stl,
    Byu,
}

/// Volume formats.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum VolumeFormat {
    Nrrd,
    Nhdr,
    Mha,
    Mhd,
    Nii,
    NiiGz,
    /// VTK legacy STRUCTURED_POINTS.
    Vtk,
    Vti,
    /// A DICOM file or a directory of them.
    Dicom,
}

/// What a file holds.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Format {
    Mesh(MeshFormat),
    Volume(VolumeFormat),
}

impl Format {
    /// The format's name for messages.
    pub(crate) fn name(self) -> &'static str {
        match self {
            Format::Mesh(MeshFormat::Vtk) => "a VTK legacy POLYDATA mesh",
            Format::Mesh(MeshFormat::Vtp) => "a VTK XML PolyData mesh",
            Format::Mesh(MeshFormat::Ply) => "a PLY mesh",
            Format::Mesh(MeshFormat::Obj) => "an OBJ mesh",
            Format::Mesh(MeshFormat::Stl) => "an STL mesh",
            Format::Mesh(MeshFormat::Byu) => "a MovieBYU mesh",
            Format::Volume(VolumeFormat::Nrrd | VolumeFormat::Nhdr) => "an NRRD volume",
            Format::Volume(VolumeFormat::Mha | VolumeFormat::Mhd) => "a MetaImage volume",
            Format::Volume(VolumeFormat::Nii | VolumeFormat::NiiGz) => "a NIfTI volume",
            Format::Volume(VolumeFormat::Vtk) => "a VTK legacy STRUCTURED_POINTS volume",
            Format::Volume(VolumeFormat::Vti) => "a VTK XML ImageData volume",
            Format::Volume(VolumeFormat::Dicom) => "a DICOM volume",
        }
    }
}

const MESH_EXTENSIONS: &str = ".vtk .vtp .ply .obj .stl .byu .g";
const VOLUME_EXTENSIONS: &str = ".nrrd .nhdr .mha .mhd .nii .nii.gz .vtk .vti .dcm";

fn extension(path: &Path) -> (String, String) {
    let name = file_name_lower(path);
    let ext = name.rsplit_once('.').map_or("", |(_, e)| e).to_string();
    (name, ext)
}

/// The mesh format `path`'s extension names (for writing, and for reading
/// formats without a magic).
pub(crate) fn mesh_by_extension(path: &Path) -> Result<MeshFormat> {
    not_a_directory(path, "a mesh file")?;
    let (_, ext) = extension(path);
    Ok(match ext.as_str() {
        "vtk" => MeshFormat::Vtk,
        "vtp" => MeshFormat::Vtp,
        "ply" => MeshFormat::Ply,
        "obj" => MeshFormat::Obj,
        "stl" => MeshFormat::Stl,
        "byu" | "g" => MeshFormat::Byu,
        _ => {
            return Err(Error::Unsupported {
                path: path.into(),
                what: format!("mesh {} (known: {MESH_EXTENSIONS})", extension_text(&ext)),
            });
        }
    })
}

/// The volume format `path`'s extension names.
pub(crate) fn volume_by_extension(path: &Path) -> Result<VolumeFormat> {
    not_a_directory(path, "a volume file")?;
    let (name, ext) = extension(path);
    if name.ends_with(".nii.gz") {
        return Ok(VolumeFormat::NiiGz);
    }
    Ok(match ext.as_str() {
        "nrrd" => VolumeFormat::Nrrd,
        "nhdr" => VolumeFormat::Nhdr,
        "mha" => VolumeFormat::Mha,
        "mhd" => VolumeFormat::Mhd,
        "nii" => VolumeFormat::Nii,
        "vtk" => VolumeFormat::Vtk,
        "vti" => VolumeFormat::Vti,
        "dcm" => VolumeFormat::Dicom,
        _ => {
            return Err(Error::Unsupported {
                path: path.into(),
                what: format!(
                    "volume {} (known: {VOLUME_EXTENSIONS}, or a directory of DICOM files; \
                     headerless raw samples are read through a .nhdr or .mhd header naming them)",
                    extension_text(&ext)
                ),
            });
        }
    })
}

/// Up to [`SNIFF_BYTES`] first bytes of a regular file; `None` for other
/// kinds (a pipe or FIFO must not be read twice, a device may never end).
fn head(path: &Path) -> Result<Option<Vec<u8>>> {
    use std::io::Read;
    // Look before opening: opening a FIFO would wait for, and then cut
    // off, its writer.
    let kind = std::fs::metadata(path).map_err(|e| Error::io(path, e))?;
    if !kind.is_file() {
        return Ok(None);
    }
    let (file, meta) = open_input(path)?;
    if !meta.is_file() {
        return Ok(None);
    }
    let mut head = Vec::new();
    file.take(SNIFF_BYTES as u64)
        .read_to_end(&mut head)
        .map_err(|e| Error::io(path, e))?;
    Ok(Some(head))
}

/// The format `head` begins, where a magic tells.
fn by_content(head: &[u8]) -> Option<Format> {
    use Format::{Mesh, Volume};
    if dicom::is_dicom(head) {
        return Some(Volume(VolumeFormat::Dicom));
    }
    if head.starts_with(b"NRRD000") {
        return Some(Volume(VolumeFormat::Nrrd));
    }
    if head.starts_with(&[0x1f, 0x8b]) {
        return Some(Volume(VolumeFormat::NiiGz));
    }
    let nifti_size = head.get(0..4).is_some_and(|b| {
        let b = [b[0], b[1], b[2], b[3]];
        i32::from_le_bytes(b) == 348 || i32::from_be_bytes(b) == 348
    });
    if nifti_size && matches!(head.get(344..348), Some(b"n+1\0")) {
        return Some(Volume(VolumeFormat::Nii));
    }
    if head.starts_with(b"ply") {
        return Some(Mesh(MeshFormat::Ply));
    }
    match vtk::dataset_kind(head) {
        Some(vtk::LegacyDataset::PolyData) => return Some(Mesh(MeshFormat::Vtk)),
        Some(vtk::LegacyDataset::StructuredPoints) => return Some(Volume(VolumeFormat::Vtk)),
        // Other data sets: the extension decides, the reader says what it found.
        Some(vtk::LegacyDataset::Other) | None => {}
    }
    match vtk_xml::dataset_type(head) {
        Some(vtk_xml::XmlDataset::PolyData) => return Some(Mesh(MeshFormat::Vtp)),
        Some(vtk_xml::XmlDataset::ImageData) => return Some(Volume(VolumeFormat::Vti)),
        Some(vtk_xml::XmlDataset::Other) | None => {}
    }
    if metaimage_header(head) {
        return Some(Volume(VolumeFormat::Mhd));
    }
    None
}

/// A MetaImage header: the first line is `key = value` with one of the
/// keys a MetaImage header starts with.
fn metaimage_header(head: &[u8]) -> bool {
    let line = head.split(|&b| b == b'\n').next().unwrap_or_default();
    let Ok(line) = std::str::from_utf8(line) else {
        return false;
    };
    let Some((key, _)) = line.split_once('=') else {
        return false;
    };
    const KEYS: [&str; 4] = ["objecttype", "ndims", "objectsubtype", "comment"];
    KEYS.contains(&key.trim().to_ascii_lowercase().as_str())
}

/// The format `path`'s content names: a directory is a DICOM series; a
/// regular file's first bytes decide where the format has a magic; `None`
/// otherwise (no magic, or a stream that must not be read twice), and the
/// caller goes by the extension.
pub(crate) fn format_of(path: &Path) -> Result<Option<Format>> {
    if path.is_dir() {
        return Ok(Some(Format::Volume(VolumeFormat::Dicom)));
    }
    Ok(head(path)?.and_then(|head| by_content(&head)))
}
