//! VTK legacy `DATASET STRUCTURED_POINTS` (`.vtk`): an axis-aligned image.
//!
//! Read: `DIMENSIONS nx ny nz`, `SPACING` (or the old `ASPECT_RATIO`;
//! 1 when absent), `ORIGIN` (0 when absent), then attribute sections. The
//! first `SCALARS` of `POINT_DATA nx·ny·nz` becomes the volume, keeping
//! its element type (8-, 16-, 32-bit integers, float, double); 64-bit
//! integers and more than one component are an [`Error::Unsupported`]
//! that says so. Every other array (more `SCALARS`, `VECTORS`, `NORMALS`,
//! `TENSORS`, `TEXTURE_COORDINATES`, `COLOR_SCALARS`, lookup tables,
//! `FIELD` arrays, all of `CELL_DATA` and data-set `FIELD` data) is read
//! boundedly, so the whole file is checked, and its name is returned in
//! [`StructuredPoints::skipped`]. BINARY payloads are big-endian. The
//! legacy format stores no orientation and no anatomical frame: the volume
//! has identity axes and no [`Space`](crate::volume::Space).
//!
//! Write: BINARY (big-endian), `SCALARS scalars <type> 1`, for volumes
//! with identity axes only ([`structured_points_can_hold`]).

use std::io::{self, Write};
use std::path::Path;

use super::super::saturating_product;
use super::super::text::{Endian, Num, Scanner, clip};
use super::{
    check_samples_budget, empty_samples, header, legacy_type_name, push_binary, push_text,
    scalars_header, skip_array_metadata, skip_metadata_lines, vtk_type,
};
use crate::volume::{IDENTITY_AXES, VolumeData};
use crate::{Error, Result, Volume};

/// A volume read from a legacy STRUCTURED_POINTS file.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct StructuredPoints {
    /// The first point `SCALARS` array, as a volume.
    pub volume: Volume,
    /// The arrays read but not kept, as `point SCALARS name`, `cell FIELD
    /// name`, ... in file order, so the caller can say what was dropped.
    pub skipped: Vec<String>,
}

/// Which data set the current attribute section belongs to.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Owner {
    None,
    Points(u64),
    Cells(u64),
}

impl Owner {
    fn label(self) -> &'static str {
        match self {
            Owner::None => "data-set",
            Owner::Points(_) => "point",
            Owner::Cells(_) => "cell",
        }
    }
}

struct Reader<'a> {
    path: &'a Path,
    sc: Scanner<'a>,
    binary: Option<Endian>,
    dims: Option<[usize; 3]>,
    owner: Owner,
    volume: Option<VolumeData>,
    skipped: Vec<String>,
}

/// Reads a VTK legacy STRUCTURED_POINTS file held in `bytes`.
pub(crate) fn read_structured_points(path: &Path, bytes: &[u8]) -> Result<StructuredPoints> {
    let (sc, binary) = header(path, bytes, "STRUCTURED_POINTS")?;
    let mut r = Reader {
        path,
        sc,
        binary,
        dims: None,
        owner: Owner::None,
        volume: None,
        skipped: Vec::new(),
    };
    let mut spacing = [1.0; 3];
    let mut origin = [0.0; 3];
    let mut geometry_done = false;
    let mut spacing_at = 0;
    while !r.sc.at_end() {
        let (at, kw) = r.sc.next("a section keyword")?;
        let upper = kw.to_ascii_uppercase();
        match upper.as_str() {
            "DIMENSIONS" | "SPACING" | "ASPECT_RATIO" | "ORIGIN" if geometry_done => {
                return Err(r.sc.error(
                    at,
                    "the geometry (DIMENSIONS, SPACING, ORIGIN) before the attribute data",
                    format!("`{kw}` after POINT_DATA or CELL_DATA"),
                ));
            }
            "DIMENSIONS" => {
                let mut d = [0usize; 3];
                for x in &mut d {
                    let (dat, n) = r.sc.count("a dimension")?;
                    *x = usize::try_from(n)
                        .ok()
                        .filter(|&n| n >= 1)
                        .ok_or_else(|| r.sc.error(dat, "a dimension ≥ 1", format!("{n}")))?;
                }
                if d.iter()
                    .try_fold(1u64, |a, &x| a.checked_mul(x as u64))
                    .is_none()
                {
                    return Err(r.sc.error(
                        at,
                        "DIMENSIONS whose point count fits 64 bits",
                        format!("{} × {} × {}", d[0], d[1], d[2]),
                    ));
                }
                r.dims = Some(d);
            }
            "SPACING" | "ASPECT_RATIO" => {
                spacing_at = at;
                for s in &mut spacing {
                    *s = r.finite(&format!("a {kw} value"))?;
                }
            }
            "ORIGIN" => {
                for o in &mut origin {
                    *o = r.finite("an ORIGIN coordinate")?;
                }
            }
            "POINT_DATA" | "CELL_DATA" => {
                let dims = r.dims.ok_or_else(|| {
                    r.sc.error(
                        at,
                        "DIMENSIONS before the attribute data",
                        format!("`{kw}`"),
                    )
                })?;
                geometry_done = true;
                let (cat, n) = r.sc.count("a count")?;
                let want = if upper == "POINT_DATA" {
                    saturating_product(dims.iter().map(|&d| d as u64))
                } else {
                    saturating_product(dims.iter().map(|&d| d.saturating_sub(1).max(1) as u64))
                };
                if n != want {
                    let what = if upper == "POINT_DATA" {
                        "points (nx·ny·nz)"
                    } else {
                        "cells"
                    };
                    return Err(r.sc.error(
                        cat,
                        format!("{kw} {want} (the number of {what})"),
                        format!("{kw} {n}"),
                    ));
                }
                r.owner = if upper == "POINT_DATA" {
                    Owner::Points(n)
                } else {
                    Owner::Cells(n)
                };
            }
            _ => r.attribute(at, kw)?,
        }
    }
    let dims = r
        .dims
        .ok_or_else(|| r.sc.error(r.sc.pos(), "DIMENSIONS nx ny nz", "end of file"))?;
    let Some(data) = r.volume else {
        return Err(r.sc.error(
            r.sc.pos(),
            "a POINT_DATA SCALARS array (the volume's samples)",
            if r.skipped.is_empty() {
                "none".to_string()
            } else {
                format!("only {}", r.skipped.join(", "))
            },
        ));
    };
    if spacing.iter().any(|&s| s <= 0.0) {
        return Err(r
            .sc
            .error(spacing_at, "a positive spacing", format!("{spacing:?}")));
    }
    let volume = Volume::new(dims, spacing, origin, data)?.with_frame(IDENTITY_AXES, None)?;
    Ok(StructuredPoints {
        volume,
        skipped: r.skipped,
    })
}

impl Reader<'_> {
    fn finite(&mut self, expected: &str) -> Result<f64> {
        let (at, tok) = self.sc.next(expected)?;
        tok.parse::<f64>()
            .ok()
            .filter(|v| v.is_finite())
            .ok_or_else(|| self.sc.error(at, expected, format!("`{}`", clip(tok))))
    }

    /// After a header line: in binary mode the payload starts after its `\n`.
    fn end_header_line(&mut self) {
        if self.binary.is_some() {
            self.sc.skip_line();
            self.sc.payload_follows();
        }
    }

    fn min_bytes(&self, num: Num) -> u64 {
        self.binary.map_or(1, |_| num.size() as u64)
    }

    /// Reads (and checks) `count` values of `num` without keeping them.
    fn skip_values(&mut self, at: usize, what: &str, num: Num, count: u64) -> Result<()> {
        let count = self.sc.check_count(at, what, count, self.min_bytes(num))?;
        match self.binary {
            Some(_) => {
                self.sc.take(count * num.size(), what)?;
            }
            None => {
                for _ in 0..count {
                    self.sc.value(num, None, what)?;
                }
            }
        }
        Ok(())
    }

    fn tuples(&self, at: usize, kw: &str) -> Result<u64> {
        match self.owner {
            Owner::Points(n) | Owner::Cells(n) => Ok(n),
            Owner::None => Err(self.sc.error(
                at,
                "POINT_DATA or CELL_DATA before attribute data",
                format!("`{kw}` outside a data section"),
            )),
        }
    }

    fn note(&mut self, kind: &str, name: &str) {
        let owner = self.owner.label();
        self.skipped.push(format!("{owner} {kind} {name}"));
    }

    fn attribute(&mut self, at: usize, kw: &str) -> Result<()> {
        let upper = kw.to_ascii_uppercase();
        match upper.as_str() {
            "SCALARS" => self.scalars(at),
            "VECTORS" | "NORMALS" | "TENSORS" | "TENSORS6" | "GLOBAL_IDS" | "PEDIGREE_IDS" => {
                let per = match upper.as_str() {
                    "TENSORS" => 9,
                    "TENSORS6" => 6,
                    "GLOBAL_IDS" | "PEDIGREE_IDS" => 1,
                    _ => 3,
                };
                let n = self.tuples(at, kw)?;
                let (_, name) = self.sc.next("a name")?;
                let (tat, ty) = self.sc.next("a data type")?;
                let num = vtk_type(&self.sc, tat, ty)?;
                self.end_header_line();
                self.note(&upper, name);
                self.skip_values(at, &format!("{kw} values"), num, n.saturating_mul(per))
            }
            "TEXTURE_COORDINATES" => {
                let n = self.tuples(at, kw)?;
                let (_, name) = self.sc.next("a name")?;
                let (_, dim) = self.sc.count("a dimension 1..3")?;
                let (tat, ty) = self.sc.next("a data type")?;
                let num = vtk_type(&self.sc, tat, ty)?;
                self.end_header_line();
                self.note(&upper, name);
                self.skip_values(at, "texture coordinates", num, n.saturating_mul(dim))
            }
            "COLOR_SCALARS" => {
                let n = self.tuples(at, kw)?;
                let (_, name) = self.sc.next("a name")?;
                let (_, per) = self.sc.count("a number of colour components")?;
                self.end_header_line();
                self.note(&upper, name);
                self.colours(at, per.saturating_mul(n))
            }
            "LOOKUP_TABLE" => {
                let (_, name) = self.sc.next("a name")?;
                let (_, size) = self.sc.count("a table size")?;
                self.end_header_line();
                self.note(&upper, name);
                self.colours(at, size.saturating_mul(4))
            }
            "FIELD" => self.field(),
            "METADATA" => {
                self.sc.skip_line();
                skip_metadata_lines(&mut self.sc);
                Ok(())
            }
            _ => Err(self.sc.error(
                at,
                "a STRUCTURED_POINTS section (DIMENSIONS, SPACING, ORIGIN, POINT_DATA, \
                 SCALARS, ...)",
                format!("`{}`", clip(kw)),
            )),
        }
    }

    fn colours(&mut self, at: usize, count: u64) -> Result<()> {
        let num = self.binary.map_or(Num::F32, |_| Num::U8);
        self.skip_values(at, "colour values", num, count)
    }

    fn scalars(&mut self, at: usize) -> Result<()> {
        let n = self.tuples(at, "SCALARS")?;
        let (name, ty, num, comps) = scalars_header(&mut self.sc, self.binary.is_some())?;
        let first_point_scalars = matches!(self.owner, Owner::Points(_)) && self.volume.is_none();
        if !first_point_scalars {
            self.note("SCALARS", name);
            return self.skip_values(at, "scalar values", num, n.saturating_mul(comps));
        }
        if comps != 1 {
            return Err(Error::Unsupported {
                path: self.path.into(),
                what: format!(
                    "STRUCTURED_POINTS scalars `{}` with {comps} components per point at {} \
                     (chisel volumes hold one)",
                    clip(name),
                    self.sc.position(at)
                ),
            });
        }
        let what = format!("SCALARS `{}` ({ty})", clip(name));
        let count = self.sc.check_count(at, &what, n, self.min_bytes(num))?;
        check_samples_budget(self.path, self.sc.position(at), &what, n, num.size())?;
        let mut data = empty_samples(self.path, num, count, &what)?;
        match self.binary {
            Some(endian) => {
                let bytes = self.sc.take(count * num.size(), &what)?;
                push_binary(&mut data, bytes, endian);
            }
            None => {
                let expected = format!("a `{ty}` sample");
                for _ in 0..count {
                    let (vat, tok) = self.sc.next(&expected)?;
                    if !push_text(&mut data, tok) {
                        return Err(self.sc.error(vat, expected, format!("`{}`", clip(tok))));
                    }
                }
            }
        }
        self.volume = Some(data);
        Ok(())
    }

    fn field(&mut self) -> Result<()> {
        self.sc.next("a field name")?;
        let (_, arrays) = self.sc.count("a number of arrays")?;
        for _ in 0..arrays {
            let (aat, name) = self.sc.next("an array name")?;
            let (_, comps) = self.sc.count("a number of components")?;
            let (_, tuples) = self.sc.count("a number of tuples")?;
            let (tat, ty) = self.sc.next("a data type")?;
            let num = vtk_type(&self.sc, tat, ty)?;
            self.end_header_line();
            self.note("FIELD", name);
            self.skip_values(aat, "field values", num, comps.saturating_mul(tuples))?;
            if self.binary.is_none() {
                skip_array_metadata(&mut self.sc)?;
            }
        }
        Ok(())
    }
}

/// Whether [`write_structured_points`] can store `v` without losing its
/// frame: the legacy format has no orientation, so only volumes whose
/// axes are the world axes ([`IDENTITY_AXES`]) qualify. (The anatomical
/// frame, `v.space`, is not stored either; world coordinates are written
/// as they are.)
pub(crate) fn structured_points_can_hold(v: &Volume) -> bool {
    v.axes == IDENTITY_AXES
}

/// Writes `v` as a BINARY (big-endian) VTK legacy STRUCTURED_POINTS file.
///
/// Errors: [`io::ErrorKind::InvalidInput`] when `v` has rotated or flipped
/// axes ([`structured_points_can_hold`] is false); nothing is written then.
pub(crate) fn write_structured_points(w: &mut dyn Write, v: &Volume) -> io::Result<()> {
    if !structured_points_can_hold(v) {
        return Err(io::Error::new(
            io::ErrorKind::InvalidInput,
            format!(
                "VTK legacy STRUCTURED_POINTS stores no orientation; the volume's axes {:?} \
                 are not the world axes (write .vti, .nrrd, .mha or .nii instead)",
                v.axes
            ),
        ));
    }
    let [nx, ny, nz] = v.dims;
    let [sx, sy, sz] = v.spacing;
    let [ox, oy, oz] = v.origin;
    writeln!(w, "# vtk DataFile Version 3.0")?;
    writeln!(w, "chisel volume")?;
    writeln!(w, "BINARY")?;
    writeln!(w, "DATASET STRUCTURED_POINTS")?;
    writeln!(w, "DIMENSIONS {nx} {ny} {nz}")?;
    writeln!(w, "SPACING {sx:?} {sy:?} {sz:?}")?;
    writeln!(w, "ORIGIN {ox:?} {oy:?} {oz:?}")?;
    writeln!(w, "POINT_DATA {}", v.len())?;
    writeln!(w, "SCALARS scalars {} 1", legacy_type_name(&v.data))?;
    writeln!(w, "LOOKUP_TABLE default")?;
    write_be(w, &v.data)?;
    writeln!(w)
}

/// Writes the samples big-endian, in blocks.
pub(crate) fn write_be(w: &mut dyn Write, data: &VolumeData) -> io::Result<()> {
    macro_rules! put {
        ($v:expr) => {{
            let mut buf = Vec::with_capacity(1 << 16);
            for chunk in $v.chunks(1 << 13) {
                buf.clear();
                for x in chunk {
                    buf.extend_from_slice(&x.to_be_bytes());
                }
                w.write_all(&buf)?;
            }
            Ok(())
        }};
    }
    match data {
        VolumeData::U8(v) => w.write_all(v),
        VolumeData::I8(v) => put!(v),
        VolumeData::U16(v) => put!(v),
        VolumeData::I16(v) => put!(v),
        VolumeData::U32(v) => put!(v),
        VolumeData::I32(v) => put!(v),
        VolumeData::F32(v) => put!(v),
        VolumeData::F64(v) => put!(v),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::volume::Space;
    use std::path::PathBuf;

    fn data(name: &str) -> (PathBuf, Vec<u8>) {
        let path = Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("tests/data/vtk")
            .join(name);
        let bytes = std::fs::read(&path).unwrap();
        (path, bytes)
    }

    fn expected(name: &str) -> serde_json::Value {
        let (_, bytes) = data("expected.json");
        let all: serde_json::Value = serde_json::from_slice(&bytes).unwrap();
        all["files"][name].clone()
    }

    fn floats(v: &serde_json::Value) -> Vec<f64> {
        v.as_array()
            .unwrap()
            .iter()
            .map(|x| x.as_f64().unwrap())
            .collect()
    }

    fn close(a: f64, b: f64) -> bool {
        (a - b).abs() <= 1e-12 * a.abs().max(b.abs()).max(1.0)
    }

    #[test]
    fn reads_every_vtk_reference_file() {
        for name in [
            "sp_ascii.vtk",
            "sp_binary.vtk",
            "sp_f64_extra_ascii.vtk",
            "sp_f64_extra_binary.vtk",
        ] {
            let (path, bytes) = data(name);
            let e = expected(name);
            assert_eq!(
                super::super::dataset_kind(&bytes),
                Some(super::super::LegacyDataset::StructuredPoints)
            );
            let sp = read_structured_points(&path, &bytes).unwrap_or_else(|e| panic!("{e}"));
            let v = &sp.volume;
            let dims: Vec<usize> = e["dims"]
                .as_array()
                .unwrap()
                .iter()
                .map(|d| d.as_u64().unwrap() as usize)
                .collect();
            assert_eq!(v.dims.to_vec(), dims, "{name}");
            assert_eq!(v.spacing.to_vec(), floats(&e["spacing"]), "{name}");
            assert_eq!(v.origin.to_vec(), floats(&e["origin"]), "{name}");
            assert_eq!(v.axes, IDENTITY_AXES);
            let want = floats(&e["values"]);
            assert_eq!(v.len(), want.len());
            for (i, w) in want.iter().enumerate() {
                assert!(close(v.data.get_f64(i), *w), "{name} sample {i}");
            }
            let sum: f64 = (0..v.len()).map(|i| v.data.get_f64(i)).sum();
            assert!(close(sum, e["sum"].as_f64().unwrap()), "{name}");
            let ty = e["type"].as_str().unwrap();
            assert_eq!(legacy_type_name(&v.data), ty, "{name}");
            if name.contains("extra") {
                assert_eq!(
                    sp.skipped,
                    [
                        "cell FIELD cellid",
                        "point FIELD doubled",
                        "point FIELD gradient"
                    ],
                    "{name}"
                );
            } else {
                assert!(sp.skipped.is_empty());
            }
        }
    }

    fn round_trip(v: &Volume) -> Volume {
        let mut out = Vec::new();
        write_structured_points(&mut out, v).unwrap();
        read_structured_points(Path::new("mem.vtk"), &out)
            .unwrap()
            .volume
    }

    #[test]
    fn round_trips_every_sample_type() {
        let n = 2 * 3 * 4;
        let datas = [
            VolumeData::U8((0..n).map(|i| i as u8 * 9).collect()),
            VolumeData::I8((0..n).map(|i| i as i8 - 12).collect()),
            VolumeData::U16((0..n).map(|i| i as u16 * 2000).collect()),
            VolumeData::I16((0..n).map(|i| i as i16 * -1000).collect()),
            VolumeData::U32((0..n).map(|i| i as u32 * 100_000_000).collect()),
            VolumeData::I32((0..n).map(|i| i * -80_000_000).collect()),
            VolumeData::F32((0..n).map(|i| i as f32 * 0.1 - 1.0).collect()),
            VolumeData::F64((0..n).map(|i| (i as f64).sqrt() * 1e-7).collect()),
        ];
        for d in datas {
            let v = Volume::new(
                [2, 3, 4],
                [0.1, 0.2, 0.30000000000000004],
                [-1.5, 1e-9, 7.0],
                d,
            )
            .unwrap();
            assert_eq!(round_trip(&v), v);
        }
    }

    #[test]
    fn refuses_a_rotated_volume() {
        let v = Volume::new([1, 1, 1], [1.0; 3], [0.0; 3], VolumeData::U8(vec![1]))
            .unwrap()
            .with_frame([[0.0, 1.0, 0.0], [-1.0, 0.0, 0.0], [0.0, 0.0, 1.0]], None)
            .unwrap();
        assert!(!structured_points_can_hold(&v));
        let e = write_structured_points(&mut Vec::new(), &v).unwrap_err();
        assert_eq!(e.kind(), io::ErrorKind::InvalidInput);
        // A named frame alone does not stop the writer (world coordinates kept).
        let v = Volume::new([1, 1, 1], [1.0; 3], [0.0; 3], VolumeData::U8(vec![1]))
            .unwrap()
            .with_frame(IDENTITY_AXES, Some(Space::Lps))
            .unwrap();
        assert!(structured_points_can_hold(&v));
    }

    fn err(text: &[u8]) -> String {
        read_structured_points(Path::new("bad.vtk"), text)
            .unwrap_err()
            .to_string()
    }

    const HEAD: &str = "# vtk DataFile Version 3.0\nt\nASCII\nDATASET STRUCTURED_POINTS\n";

    #[test]
    fn negative_controls_name_what_was_expected() {
        let e = err(format!("{HEAD}DIMENSIONS 2 1 1\nPOINT_DATA 3\n").as_bytes());
        assert!(e.contains("line 6") && e.contains("POINT_DATA 2"), "{e}");
        let e = err(format!(
            "{HEAD}DIMENSIONS 2 1 1\nPOINT_DATA 2\nSCALARS s unsigned_char\n1 256\n"
        )
        .as_bytes());
        assert!(
            e.contains("line 8") && e.contains("`unsigned_char` sample"),
            "{e}"
        );
        let e =
            err(format!("{HEAD}DIMENSIONS 2 1 1\nPOINT_DATA 2\nSCALARS s long\n1 2\n").as_bytes());
        assert!(e.contains("64-bit"), "{e}");
        let e =
            err(format!("{HEAD}DIMENSIONS 2 1 1\nPOINT_DATA 2\nSCALARS s float 3\n").as_bytes());
        assert!(e.contains("3 components"), "{e}");
        let e = err(format!(
            "{HEAD}DIMENSIONS 2 1 1\nPOINT_DATA 2\nSCALARS s float\n1 2\nGARBAGE\n"
        )
        .as_bytes());
        assert!(e.contains("line 9") && e.contains("`GARBAGE`"), "{e}");
        let e = err(format!(
            "{HEAD}DIMENSIONS 2 1 1\nSPACING 1 0 1\nPOINT_DATA 2\nSCALARS s float\n1 2\n"
        )
        .as_bytes());
        assert!(e.contains("positive spacing"), "{e}");
        let e = err(
            format!("{HEAD}DIMENSIONS 2 1 1\nPOINT_DATA 2\nVECTORS v float\n1 2 3\n").as_bytes(),
        );
        assert!(e.contains("VECTORS values"), "{e}");
        // A binary payload shorter than announced.
        let (path, bytes) = data("sp_binary.vtk");
        let e = read_structured_points(&path, &bytes[..bytes.len() - 10]).unwrap_err();
        assert!(
            e.to_string()
                .contains("SCALARS `density` (short) needs 120 bytes"),
            "{e}"
        );
        // Trailing garbage after a binary payload: named by its byte offset.
        let mut b = bytes.clone();
        b.extend_from_slice(b"junk\n");
        let e = read_structured_points(&path, &b).unwrap_err().to_string();
        assert!(
            e.contains(&format!("byte {}", bytes.len())) && e.contains("`junk`"),
            "{e}"
        );
        // A huge announced size: refused before allocating.
        let e = err(format!(
            "{HEAD}DIMENSIONS 100000 100000 100000\nPOINT_DATA 1000000000000000\nSCALARS s float\n"
        )
        .as_bytes());
        assert!(e.contains("needs"), "{e}");
    }
}
