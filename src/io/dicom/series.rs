//! DICOM series: the image files of a directory grouped by
//! SeriesInstanceUID, their frames ordered along the slice normal and
//! checked to form one regular grid.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use serde::Serialize;

use super::{Frame, Header, SPACE, Samples, header, open, stored_values};
use crate::volume::Volume;
use crate::{Error, Position, Result};

/// One series of a DICOM directory, as `chisel stats DIR` lists it.
#[derive(Debug, Clone, Serialize)]
pub struct SeriesInfo {
    /// SeriesInstanceUID (empty when the files have none).
    pub uid: String,
    pub description: Option<String>,
    pub modality: Option<String>,
    /// Image files of the series.
    pub files: usize,
    /// Frames (slices) over all its files.
    pub frames: usize,
    /// Rows and columns of its first file.
    pub rows: u32,
    pub columns: u32,
    /// Transfer syntax UID of its first file.
    pub transfer_syntax: String,
}

/// One image file of a series: its header and, once read, its stored values.
pub(crate) struct File {
    pub path: PathBuf,
    pub header: Header,
    pub values: Option<Vec<Vec<f64>>>,
}

/// Directory levels searched below the named one.
const MAX_DEPTH: usize = 4;

/// The regular files under `dir` (sorted, so errors name the same file
/// on every run), at most [`MAX_DEPTH`] levels down; directory symlinks
/// are not followed.
fn files_under(dir: &Path) -> Result<Vec<PathBuf>> {
    let mut out = Vec::new();
    let mut stack = vec![(dir.to_path_buf(), 0)];
    while let Some((d, depth)) = stack.pop() {
        let entries = std::fs::read_dir(&d).map_err(|e| Error::io(&d, e))?;
        for entry in entries {
            let entry = entry.map_err(|e| Error::io(&d, e))?;
            let kind = entry.file_type().map_err(|e| Error::io(entry.path(), e))?;
            if kind.is_dir() {
                if depth < MAX_DEPTH {
                    stack.push((entry.path(), depth + 1));
                }
            } else if std::fs::metadata(entry.path()).is_ok_and(|m| m.is_file()) {
                out.push(entry.path());
            }
        }
    }
    out.sort();
    Ok(out)
}

/// The first bytes of `path` say DICOM.
fn looks_dicom(path: &Path) -> bool {
    use std::io::Read;
    let mut head = [0u8; 132];
    let Ok(mut f) = std::fs::File::open(path) else {
        return false;
    };
    let mut n = 0;
    while n < head.len() {
        match f.read(&mut head[n..]) {
            Ok(0) | Err(_) => break,
            Ok(k) => n += k,
        }
    }
    super::is_dicom(&head[..n])
}

/// The image files under `dir`, by series (headers only; other files and
/// DICOM files without an image are passed over).
fn scan(dir: &Path) -> Result<BTreeMap<String, Vec<File>>> {
    let mut series: BTreeMap<String, Vec<File>> = BTreeMap::new();
    for path in files_under(dir)? {
        if !looks_dicom(&path) {
            continue;
        }
        let obj = open(&path, true)?;
        if let Some(header) = header(&path, &obj)? {
            series
                .entry(header.series_uid.clone().unwrap_or_default())
                .or_default()
                .push(File {
                    path,
                    header,
                    values: None,
                });
        }
    }
    if series.is_empty() {
        return Err(Error::format(
            dir,
            Position::Whole,
            "a directory with DICOM image files",
            "none",
        ));
    }
    Ok(series)
}

fn info(uid: &str, files: &[File]) -> SeriesInfo {
    let first = &files[0].header;
    SeriesInfo {
        uid: uid.to_string(),
        description: first.description.clone(),
        modality: first.modality.clone(),
        files: files.len(),
        frames: files.iter().map(|f| f.header.frames.len()).sum(),
        rows: first.rows,
        columns: first.columns,
        transfer_syntax: first.transfer_syntax.clone(),
    }
}

/// The series of the DICOM image files under `dir`, by UID.
pub(crate) fn list_series(dir: &Path) -> Result<Vec<SeriesInfo>> {
    Ok(scan(dir)?
        .iter()
        .map(|(uid, files)| info(uid, files))
        .collect())
}

/// Reads the series under `dir` (the only one, or the one whose
/// SeriesInstanceUID is `series`) as a volume.
pub(crate) fn read_dir(dir: &Path, series: Option<&str>) -> Result<Volume> {
    let mut all = scan(dir)?;
    let uid = match series {
        Some(uid) => uid.to_string(),
        None if all.len() == 1 => all.keys().next().cloned().unwrap_or_default(),
        None => {
            let list: Vec<String> = all
                .iter()
                .map(|(uid, files)| {
                    let i = info(uid, files);
                    format!(
                        "{uid} ({} files, {}×{}{})",
                        i.files,
                        i.columns,
                        i.rows,
                        i.description
                            .map(|d| format!(", \"{d}\""))
                            .unwrap_or_default()
                    )
                })
                .collect();
            return Err(Error::Unsupported {
                path: dir.into(),
                what: format!(
                    "a directory with {} DICOM series without choosing one (--series UID): {}",
                    all.len(),
                    list.join("; ")
                ),
            });
        }
    };
    let files = all.remove(&uid).ok_or_else(|| Error::Unsupported {
        path: dir.into(),
        what: format!(
            "DICOM series {uid}: not in this directory (it holds {})",
            all.keys().cloned().collect::<Vec<_>>().join(", ")
        ),
    })?;
    assemble(files)
}

/// A frame of a file: the file's index, the frame's index in it.
#[derive(Debug, Clone, Copy)]
struct Slot {
    file: usize,
    frame: usize,
    /// Position along the slice normal.
    depth: f64,
}

fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

fn unit(path: &Path, v: [f64; 3]) -> Result<[f64; 3]> {
    let len = dot(v, v).sqrt();
    if !(len > 0.5 && len < 1.5) {
        return Err(Error::format(
            path,
            Position::Field("ImageOrientationPatient".into()),
            "unit row and column directions",
            format!("a direction of length {len}"),
        ));
    }
    Ok(v.map(|c| c / len))
}

/// Tolerance for "the same" geometry between frames, in mm (and, for
/// directions, in cosines; relative for pixel spacings): values written as
/// decimal strings by scanners carry about six significant digits.
const SAME: f64 = 1e-3;

/// How far, in voxels, a frame may lie from the grid the series makes.
const GRID_TOLERANCE: f64 = 0.1;

/// The volume of `files` (one series): every frame the same size,
/// orientation and pixel spacing; ordered by position along the normal;
/// equally spaced; without gantry tilt.
pub(crate) fn assemble(mut files: Vec<File>) -> Result<Volume> {
    let first = &files[0];
    let path0 = first.path.clone();
    let (rows, columns) = (first.header.rows, first.header.columns);
    let frame0: &Frame = &first.header.frames[0];
    let field = |p: &Path, name: &str, expected: String, found: String| {
        Error::format(p, Position::Field(name.into()), expected, found)
    };
    let orientation = frame0.orientation.unwrap_or([1.0, 0.0, 0.0, 0.0, 1.0, 0.0]);
    let pixel = frame0.pixel_spacing.unwrap_or([1.0, 1.0]);
    let row = unit(&path0, [orientation[0], orientation[1], orientation[2]])?;
    let col = unit(&path0, [orientation[3], orientation[4], orientation[5]])?;
    let normal = [
        row[1] * col[2] - row[2] * col[1],
        row[2] * col[0] - row[0] * col[2],
        row[0] * col[1] - row[1] * col[0],
    ];
    let mut slots = Vec::new();
    for (i, f) in files.iter().enumerate() {
        let h = &f.header;
        if (h.rows, h.columns) != (rows, columns) {
            return Err(field(
                &f.path,
                "Rows",
                format!("{columns}×{rows} like {}", path0.display()),
                format!("{}×{}", h.columns, h.rows),
            ));
        }
        for (k, fr) in h.frames.iter().enumerate() {
            let o = fr.orientation.unwrap_or(orientation);
            if o.iter()
                .zip(&orientation)
                .any(|(a, b)| (a - b).abs() > SAME)
            {
                return Err(field(
                    &f.path,
                    "ImageOrientationPatient",
                    format!("{orientation:?} like {}", path0.display()),
                    format!("{o:?} (frame {k})"),
                ));
            }
            let s = fr.pixel_spacing.unwrap_or(pixel);
            if s.iter().zip(&pixel).any(|(a, b)| (a - b).abs() > SAME * b) {
                return Err(field(
                    &f.path,
                    "PixelSpacing",
                    format!("{pixel:?} like {}", path0.display()),
                    format!("{s:?} (frame {k})"),
                ));
            }
            let depth = fr.position.map_or(0.0, |p| dot(p, normal));
            slots.push(Slot {
                file: i,
                frame: k,
                depth,
            });
        }
    }
    let n = slots.len();
    let positioned = files
        .iter()
        .all(|f| f.header.frames.iter().all(|fr| fr.position.is_some()));
    if n > 1 && !positioned {
        let f = files
            .iter()
            .find(|f| f.header.frames.iter().any(|fr| fr.position.is_none()))
            .map_or(path0.clone(), |f| f.path.clone());
        return Err(field(
            &f,
            "ImagePositionPatient",
            "a position for every frame of a series".into(),
            "none".into(),
        ));
    }
    slots.sort_by(|a, b| a.depth.total_cmp(&b.depth));
    let position = |s: &Slot| {
        files[s.file].header.frames[s.frame]
            .position
            .unwrap_or([0.0; 3])
    };
    let name = |s: &Slot| {
        let f = &files[s.file];
        if f.header.frames.len() > 1 {
            format!("{} frame {}", f.path.display(), s.frame)
        } else {
            f.path.display().to_string()
        }
    };
    let step = if n > 1 {
        let gaps: Vec<f64> = slots.windows(2).map(|w| w[1].depth - w[0].depth).collect();
        if let Some(i) = gaps.iter().position(|&g| g <= SAME) {
            return Err(Error::Unsupported {
                path: files[slots[i + 1].file].path.clone(),
                what: format!(
                    "two DICOM frames at one position ({} and {}, {:.4} mm apart along the \
                     normal): several acquisitions in one series; split them first",
                    name(&slots[i]),
                    name(&slots[i + 1]),
                    gaps[i]
                ),
            });
        }
        let step = (slots[n - 1].depth - slots[0].depth) / (n - 1) as f64;
        // The grid may miss the frames by a tenth of a voxel at most:
        // along the normal (uneven spacing, a missing slice) and across it
        // (gantry tilt, a sheared stack).
        let p0 = position(&slots[0]);
        let along_tolerance = GRID_TOLERANCE * step;
        let across_tolerance = GRID_TOLERANCE * pixel[0].min(pixel[1]);
        for (k, s) in slots.iter().enumerate() {
            let off = sub(position(s), p0);
            let along = dot(off, normal);
            if (along - k as f64 * step).abs() > along_tolerance {
                let mut sorted = gaps.clone();
                sorted.sort_by(f64::total_cmp);
                let median = sorted[sorted.len() / 2];
                // The gap farthest from the median names the odd slice.
                let odd = (0..gaps.len())
                    .max_by(|&a, &b| {
                        (gaps[a] - median)
                            .abs()
                            .total_cmp(&(gaps[b] - median).abs())
                    })
                    .unwrap_or(0);
                return Err(Error::Unsupported {
                    path: files[slots[odd + 1].file].path.clone(),
                    what: format!(
                        "non-uniform DICOM slice spacing: {:.4} mm between {} and {} where the \
                         other slices are {median:.4} mm apart (a missing slice or a varying \
                         spacing); resample the series to equal spacing first",
                        gaps[odd],
                        name(&slots[odd]),
                        name(&slots[odd + 1]),
                    ),
                });
            }
            let across = sub(off, normal.map(|c| c * along));
            let shift = dot(across, across).sqrt();
            if shift > across_tolerance {
                return Err(Error::Unsupported {
                    path: files[s.file].path.clone(),
                    what: format!(
                        "gantry tilt or a sheared stack: {} lies {shift:.4} mm across the \
                         slice normal from {} (a volume's grid is not sheared); resample the \
                         series onto an orthogonal grid first",
                        name(s),
                        name(&slots[0]),
                    ),
                });
            }
        }
        step
    } else {
        files[0].header.slice_step.unwrap_or(1.0)
    };
    let (nx, ny) = (columns as usize, rows as usize);
    let per_frame = nx.checked_mul(ny).ok_or_else(|| {
        field(
            &path0,
            "Rows",
            "a frame size that fits memory".into(),
            format!("{columns}×{rows}"),
        )
    })?;
    let total = per_frame.checked_mul(n).ok_or_else(|| {
        field(
            &path0,
            "Rows",
            "a volume size that fits memory".into(),
            format!("{n} frames"),
        )
    })?;
    let integral = files.iter().all(|f| {
        f.header
            .frames
            .iter()
            .all(|fr| fr.slope.fract() == 0.0 && fr.intercept.fract() == 0.0)
    });
    let origin = position(&slots[0]);
    let mut samples = Samples::with_capacity(&path0, total, integral)?;
    // Frames in slice order; each file's pixel data decoded once, when its
    // first frame comes, and dropped after its last.
    let mut left: Vec<usize> = files.iter().map(|f| f.header.frames.len()).collect();
    for s in &slots {
        let f = &mut files[s.file];
        if f.values.is_none() {
            let obj = open(&f.path, false)?;
            f.values = Some(stored_values(&f.path, &obj)?);
        }
        let values = f.values.as_ref().expect("just read");
        let stored = values
            .get(s.frame)
            .filter(|v| v.len() == per_frame)
            .ok_or_else(|| {
                field(
                    &f.path,
                    "PixelData",
                    format!("{} frames of {per_frame} samples", f.header.frames.len()),
                    format!(
                        "{} frames{}",
                        values.len(),
                        values
                            .get(s.frame)
                            .map(|v| format!(", frame {} of {} samples", s.frame, v.len()))
                            .unwrap_or_default()
                    ),
                )
            })?;
        samples.push(&f.path, stored, &f.header.frames[s.frame])?;
        left[s.file] -= 1;
        if left[s.file] == 0 {
            f.values = None;
        }
    }
    let data = samples.finish(&path0)?;
    Volume::new([nx, ny, n], [pixel[1], pixel[0], step], origin, data)?
        .with_frame([row, col, normal], Some(SPACE))
        .map_err(|e| {
            field(
                &path0,
                "ImageOrientationPatient",
                "orthonormal row and column directions".into(),
                e.to_string(),
            )
        })
}
