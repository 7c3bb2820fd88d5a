//! `.vtp` PolyData ↔ [`TriMesh`].

use std::io::{self, Write};
use std::path::Path;

use glam::Vec3;

use super::super::text::fan;
use super::{Doc, Elem, escape};
use crate::mesh::ScalarField;
use crate::{Error, Result, TriMesh};

/// What [`read_poly`] made of the cells and arrays it did not keep as they are.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub(crate) struct PolyNotes {
    /// Polygons with more than 3 corners, fan-triangulated.
    pub polygons_split: u64,
    /// The triangles made from them.
    pub triangles_from_polygons: u64,
    /// Triangle strips, unrolled.
    pub strips: u64,
    /// The triangles made from them.
    pub triangles_from_strips: u64,
    /// `Verts` cells read and dropped.
    pub verts: u64,
    /// `Lines` cells read and dropped.
    pub lines: u64,
    /// Arrays read but not kept: `point name (3 components)`, `cell name`,
    /// `field name`, or a one-component point array missing from some piece.
    pub skipped: Vec<String>,
}

impl PolyNotes {
    /// The notes as lines for the user (empty when nothing was changed or
    /// passed over).
    pub(crate) fn notes(&self) -> Vec<String> {
        let mut out = Vec::new();
        if self.polygons_split > 0 {
            out.push(format!(
                "{} polygons of more than 3 corners fan-triangulated into {} triangles",
                self.polygons_split, self.triangles_from_polygons
            ));
        }
        if self.strips > 0 {
            out.push(format!(
                "{} triangle strips unrolled into {} triangles",
                self.strips, self.triangles_from_strips
            ));
        }
        if self.verts + self.lines > 0 {
            out.push(format!(
                "skipped {} vertex and {} line cells (a triangle mesh keeps neither)",
                self.verts, self.lines
            ));
        }
        if !self.skipped.is_empty() {
            out.push(format!("skipped data arrays: {}", self.skipped.join(", ")));
        }
        out
    }
}

/// Reads a `.vtp` file held in `bytes`: all pieces concatenated.
pub(crate) fn read_poly(path: &Path, bytes: &[u8]) -> Result<(TriMesh, PolyNotes)> {
    let doc = Doc::parse(path, bytes, "PolyData")?;
    let pd = doc.one(&doc.root, "PolyData")?;
    let mut notes = PolyNotes::default();
    let note = |notes: &mut PolyNotes, s: String| {
        if !notes.skipped.contains(&s) {
            notes.skipped.push(s);
        }
    };
    doc.skip_field_data(pd, |s| note(&mut notes, s))?;
    let pieces: Vec<&Elem> = pd.children_named("Piece").collect();
    let mut positions: Vec<Vec3> = Vec::new();
    let mut triangles: Vec<[u32; 3]> = Vec::new();
    // One-component point arrays per piece, by name.
    let mut fields: Vec<Vec<(String, Vec<f32>)>> = Vec::new();
    for piece in &pieces {
        let np = doc.count(piece, "NumberOfPoints")?;
        let base = positions.len() as u64;
        if base.saturating_add(np) > u64::from(u32::MAX) {
            return Err(doc.error(
                piece.at,
                "at most 4294967295 points in all pieces (32-bit indices)",
                format!("NumberOfPoints {np} after {base} points"),
            ));
        }
        if let Some(points) = piece.child("Points") {
            let el = points
                .child("DataArray")
                .ok_or_else(|| doc.error(points.at, "a <DataArray> inside <Points>", "none"))?;
            let a = doc.array(el)?;
            if a.comps != 3 {
                return Err(doc.error(
                    el.at,
                    "Points with NumberOfComponents=\"3\"",
                    format!("{} components", a.comps),
                ));
            }
            let xyz = doc.f64s(&a, np * 3)?;
            positions
                .try_reserve_exact(np as usize)
                .map_err(|_| Error::HostMemory {
                    what: format!("{}: points", path.display()),
                    bytes: np * 12,
                })?;
            for (i, p) in xyz.chunks_exact(3).enumerate() {
                let v = Vec3::new(p[0] as f32, p[1] as f32, p[2] as f32);
                if !v.is_finite() {
                    return Err(doc.error(
                        el.at,
                        format!("finite coordinates for point {i} of the piece"),
                        format!("{p:?}"),
                    ));
                }
                positions.push(v);
            }
        } else if np > 0 {
            return Err(doc.error(
                piece.at,
                format!("<Points> for NumberOfPoints=\"{np}\""),
                "none",
            ));
        }
        let ncells = [
            doc.count(piece, "NumberOfVerts")?,
            doc.count(piece, "NumberOfLines")?,
            doc.count(piece, "NumberOfStrips")?,
            doc.count(piece, "NumberOfPolys")?,
        ];
        for (kind, &n) in ["Verts", "Lines", "Strips", "Polys"].iter().zip(&ncells) {
            let (offsets, conn) = cell_list(&doc, piece, kind, n, np)?;
            for w in offsets.windows(2) {
                let poly: Vec<u32> = conn[w[0]..w[1]].iter().map(|&i| i + base as u32).collect();
                match *kind {
                    "Verts" => notes.verts += 1,
                    "Lines" => notes.lines += 1,
                    _ if poly.len() < 3 => {
                        return Err(doc.error(
                            piece.at,
                            format!("{kind} cells with at least 3 points"),
                            format!("a cell of {} points", poly.len()),
                        ));
                    }
                    "Strips" => {
                        notes.strips += 1;
                        notes.triangles_from_strips += poly.len() as u64 - 2;
                        for i in 0..poly.len() - 2 {
                            triangles.push(if i % 2 == 0 {
                                [poly[i], poly[i + 1], poly[i + 2]]
                            } else {
                                [poly[i + 1], poly[i], poly[i + 2]]
                            });
                        }
                    }
                    _ => {
                        if poly.len() > 3 {
                            notes.polygons_split += 1;
                            notes.triangles_from_polygons += poly.len() as u64 - 2;
                        }
                        fan(&poly, &mut triangles);
                    }
                }
            }
        }
        let mut piece_fields = Vec::new();
        if let Some(pdata) = piece.child("PointData") {
            for el in pdata.children_named("DataArray") {
                let a = doc.array(el)?;
                if a.comps == 1 && a.num.is_some() {
                    let values = doc.f64s(&a, np)?;
                    piece_fields.push((a.name.clone(), values.iter().map(|&v| v as f32).collect()));
                } else {
                    doc.skip(&a, Some(np.saturating_mul(a.comps)))?;
                    note(
                        &mut notes,
                        format!("point {} ({} components)", a.name, a.comps),
                    );
                }
            }
        }
        fields.push(piece_fields);
        if let Some(cdata) = piece.child("CellData") {
            let total: u64 = ncells.iter().sum();
            for el in cdata.children_named("DataArray") {
                let a = doc.array(el)?;
                doc.skip(&a, Some(total.saturating_mul(a.comps)))?;
                note(&mut notes, format!("cell {}", a.name));
            }
        }
    }
    doc.check_appended_tail()?;
    // A field is kept when every piece has it.
    let mut scalars = Vec::new();
    if let Some(first) = fields.first() {
        for (name, _) in first {
            let mut values = Vec::new();
            let mut everywhere = true;
            for piece in &fields {
                match piece.iter().find(|(n, _)| n == name) {
                    Some((_, v)) => values.extend_from_slice(v),
                    None => everywhere = false,
                }
            }
            if everywhere {
                if !scalars.iter().any(|s: &ScalarField| &s.name == name) {
                    scalars.push(ScalarField {
                        name: name.clone(),
                        values,
                    });
                }
            } else {
                note(&mut notes, format!("point {name} (not in every piece)"));
            }
        }
    }
    Ok((
        TriMesh {
            positions,
            triangles,
            scalars,
        },
        notes,
    ))
}

/// The cells of kind `kind` (`Polys`, ...): `n + 1` non-decreasing
/// offsets starting at 0 (VTK stores the `n` ends), and the
/// `connectivity`, as many point indices (each below `np`) as the last
/// offset says.
fn cell_list(
    doc: &Doc,
    piece: &Elem,
    kind: &str,
    n: u64,
    np: u64,
) -> Result<(Vec<usize>, Vec<u32>)> {
    let Some(el) = piece.child(kind) else {
        if n > 0 {
            return Err(doc.error(
                piece.at,
                format!("<{kind}> for NumberOf{kind}=\"{n}\""),
                "none",
            ));
        }
        return Ok((vec![0], Vec::new()));
    };
    let a = named(doc, el, "offsets")?;
    let values = doc.f64s(&a, n)?;
    let mut offsets = Vec::new();
    offsets
        .try_reserve_exact(values.len() + 1)
        .map_err(|_| Error::HostMemory {
            what: format!("{}: offsets", doc.path.display()),
            bytes: n.saturating_mul(8),
        })?;
    offsets.push(0usize);
    for v in values {
        let prev = *offsets.last().unwrap_or(&0);
        if v.fract() != 0.0 || v < prev as f64 || v > 9.0e15 {
            return Err(doc.error(
                a.el.at,
                format!("non-decreasing integer offsets in <{kind}>"),
                format!("{v} after {prev}"),
            ));
        }
        offsets.push(v as usize);
    }
    let len = *offsets.last().unwrap_or(&0) as u64;
    let a = named(doc, el, "connectivity")?;
    let values = doc.f64s(&a, len)?;
    let mut conn = Vec::new();
    conn.try_reserve_exact(values.len())
        .map_err(|_| Error::HostMemory {
            what: format!("{}: connectivity", doc.path.display()),
            bytes: len * 4,
        })?;
    for (k, v) in values.into_iter().enumerate() {
        if v.fract() != 0.0 || v < 0.0 || v >= np as f64 {
            return Err(doc.error(
                a.el.at,
                format!("point indices in 0..{np} in the connectivity of <{kind}>"),
                format!("{v} at entry {k}"),
            ));
        }
        conn.push(v as u32);
    }
    Ok((offsets, conn))
}

/// The `<DataArray Name="name">` inside `el`.
fn named<'e>(doc: &Doc, el: &'e Elem, name: &str) -> Result<super::array::Array<'e>> {
    let child = el
        .children_named("DataArray")
        .find(|c| c.attr("Name") == Some(name))
        .ok_or_else(|| {
            doc.error(
                el.at,
                format!("a <DataArray Name=\"{name}\"> inside <{}>", el.name),
                "none",
            )
        })?;
    doc.array(child)
}

/// Writes `mesh` as a `.vtp` file: little-endian, `header_type="UInt64"`,
/// appended raw `Points` (`Float32`), `Polys` (`Int64` connectivity and
/// offsets) and one `Float32` point array per scalar field.
pub(crate) fn write_poly(w: &mut dyn Write, mesh: &TriMesh) -> io::Result<()> {
    let nv = mesh.positions.len();
    let nt = mesh.triangles.len();
    let mut offset = 0u64;
    let mut next = |bytes: u64| {
        let at = offset;
        offset += 8 + bytes;
        at
    };
    writeln!(w, "<?xml version=\"1.0\"?>")?;
    writeln!(
        w,
        "<VTKFile type=\"PolyData\" version=\"1.0\" byte_order=\"LittleEndian\" header_type=\"UInt64\">"
    )?;
    writeln!(w, "  <PolyData>")?;
    writeln!(
        w,
        "    <Piece NumberOfPoints=\"{nv}\" NumberOfVerts=\"0\" NumberOfLines=\"0\" NumberOfStrips=\"0\" NumberOfPolys=\"{nt}\">"
    )?;
    writeln!(w, "      <PointData>")?;
    for s in &mesh.scalars {
        let name = if s.name.is_empty() { "scalar" } else { &s.name };
        writeln!(
            w,
            "        <DataArray type=\"Float32\" Name=\"{}\" format=\"appended\" offset=\"{}\"/>",
            escape(name),
            next(4 * nv as u64)
        )?;
    }
    writeln!(w, "      </PointData>\n      <CellData>\n      </CellData>")?;
    writeln!(
        w,
        "      <Points>\n        <DataArray type=\"Float32\" Name=\"Points\" NumberOfComponents=\"3\" format=\"appended\" offset=\"{}\"/>\n      </Points>",
        next(12 * nv as u64)
    )?;
    writeln!(w, "      <Polys>")?;
    writeln!(
        w,
        "        <DataArray type=\"Int64\" Name=\"connectivity\" format=\"appended\" offset=\"{}\"/>",
        next(24 * nt as u64)
    )?;
    writeln!(
        w,
        "        <DataArray type=\"Int64\" Name=\"offsets\" format=\"appended\" offset=\"{}\"/>",
        next(8 * nt as u64)
    )?;
    writeln!(w, "      </Polys>\n    </Piece>\n  </PolyData>")?;
    write!(w, "  <AppendedData encoding=\"raw\">\n   _")?;
    let block = |w: &mut dyn Write, bytes: Vec<u8>| -> io::Result<()> {
        w.write_all(&(bytes.len() as u64).to_le_bytes())?;
        w.write_all(&bytes)
    };
    for s in &mesh.scalars {
        block(w, s.values.iter().flat_map(|v| v.to_le_bytes()).collect())?;
    }
    block(
        w,
        mesh.positions
            .iter()
            .flat_map(|p| p.to_array())
            .flat_map(|c| c.to_le_bytes())
            .collect(),
    )?;
    block(
        w,
        mesh.triangles
            .iter()
            .flatten()
            .flat_map(|&i| i64::from(i).to_le_bytes())
            .collect(),
    )?;
    block(
        w,
        (1..=nt as i64)
            .flat_map(|k| (3 * k).to_le_bytes())
            .collect(),
    )?;
    writeln!(w, "\n  </AppendedData>\n</VTKFile>")
}
