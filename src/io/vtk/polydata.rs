//! VTK legacy POLYDATA (`.vtk`), ASCII and BINARY.
//!
//! Read: `POINTS`, `POLYGONS` (fan-triangulated), `TRIANGLE_STRIPS`
//! (alternating winding, so every triangle keeps the strip's orientation),
//! `VERTICES`/`LINES` (skipped), both the classic cell layout and the 5.1
//! `OFFSETS`/`CONNECTIVITY` layout. Attribute sections (`POINT_DATA`,
//! `CELL_DATA`, possibly empty) are parsed; one-component point `SCALARS` and
//! one-component point `FIELD` arrays become [`ScalarField`]s, point
//! `TEXTURE_COORDINATES` the fields `u` and `v` (their first two
//! components); everything else (`NORMALS`, `VECTORS`, colours, cell data)
//! is skipped. BINARY payloads are big-endian, as the VTK file-format spec says.
//!
//! Write: ASCII, `POLYGONS` of triangles, scalars as `POINT_DATA SCALARS
//! <name> float 1` with the default lookup table.

use std::io::{self, Write};
use std::path::Path;

use glam::Vec3;

use super::super::text::{Endian, Num, Scanner, clip, fan};
use super::{
    field_name, header, scalars_header, skip_array_metadata, skip_metadata_lines, vtk_type,
};
use crate::mesh::ScalarField;
use crate::{Result, TriMesh};

/// Which data set the current attribute section belongs to.
#[derive(Debug, Clone, Copy)]
enum Owner {
    None,
    Points(usize),
    Cells(usize),
}

struct Reader<'a> {
    sc: Scanner<'a>,
    binary: Option<Endian>,
    positions: Vec<Vec3>,
    have_points: bool,
    triangles: Vec<[u32; 3]>,
    n_cells: u64,
    scalars: Vec<ScalarField>,
    owner: Owner,
}

/// Reads a VTK legacy POLYDATA file held in `bytes`.
pub(crate) fn read(path: &Path, bytes: &[u8]) -> Result<TriMesh> {
    let (sc, binary) = header(path, bytes, "POLYDATA")?;
    let mut r = Reader {
        sc,
        binary,
        positions: Vec::new(),
        have_points: false,
        triangles: Vec::new(),
        n_cells: 0,
        scalars: Vec::new(),
        owner: Owner::None,
    };
    while !r.sc.at_end() {
        r.section()?;
    }
    Ok(TriMesh {
        positions: r.positions,
        triangles: r.triangles,
        scalars: r.scalars,
    })
}

impl Reader<'_> {
    /// After a header line: in binary mode the payload starts after its `\n`
    /// (and from there on no whitespace may be skipped).
    fn end_header_line(&mut self) {
        if self.binary.is_some() {
            self.sc.skip_line();
            self.sc.payload_follows();
        }
    }

    /// Smallest number of bytes one value of `num` occupies in the file.
    fn min_bytes(&self, num: Num) -> u64 {
        match self.binary {
            Some(_) => num.size() as u64,
            None => 1,
        }
    }

    /// Reads `count` values of `num`, handing each to `f`; sizes checked first.
    fn values(
        &mut self,
        at: usize,
        what: &str,
        num: Num,
        count: u64,
        mut f: impl FnMut(f64),
    ) -> Result<()> {
        let min = self.min_bytes(num);
        let count = self.sc.check_count(at, what, count, min)?;
        for _ in 0..count {
            f(self.sc.value(num, self.binary, what)?);
        }
        Ok(())
    }

    fn section(&mut self) -> Result<()> {
        let (at, kw) = self.sc.next("a section keyword")?;
        match kw.to_ascii_uppercase().as_str() {
            "POINTS" => self.points(at),
            "POLYGONS" => self.cells(at, CellKind::Polygons),
            "TRIANGLE_STRIPS" => self.cells(at, CellKind::Strips),
            "VERTICES" | "LINES" => self.cells(at, CellKind::Skip),
            "POINT_DATA" => {
                let (cat, n) = self.sc.count("a point count")?;
                if n != self.positions.len() as u64 {
                    return Err(self.sc.error(
                        cat,
                        format!("POINT_DATA {} (the POINTS count)", self.positions.len()),
                        format!("POINT_DATA {n}"),
                    ));
                }
                self.owner = Owner::Points(self.positions.len());
                Ok(())
            }
            "CELL_DATA" => {
                let (cat, n) = self.sc.count("a cell count")?;
                if n != self.n_cells {
                    return Err(self.sc.error(
                        cat,
                        format!("CELL_DATA {} (the number of cells)", self.n_cells),
                        format!("CELL_DATA {n}"),
                    ));
                }
                self.owner = Owner::Cells(self.n_cells as usize);
                Ok(())
            }
            "SCALARS" => self.scalars_section(at),
            "COLOR_SCALARS" => {
                let n = self.owner_count(at)?;
                self.sc.next("a name")?;
                let (_, per) = self.sc.count("a number of colour components")?;
                self.end_header_line();
                self.colours(at, per.saturating_mul(n as u64))
            }
            "LOOKUP_TABLE" => {
                self.sc.next("a name")?;
                let (_, size) = self.sc.count("a table size")?;
                self.end_header_line();
                self.colours(at, size.saturating_mul(4))
            }
            "VECTORS" | "NORMALS" | "TENSORS" | "TENSORS6" => {
                let per = match kw.to_ascii_uppercase().as_str() {
                    "TENSORS" => 9,
                    "TENSORS6" => 6,
                    _ => 3,
                };
                let n = self.owner_count(at)?;
                self.sc.next("a name")?;
                let (tat, ty) = self.sc.next("a data type")?;
                let num = vtk_type(&self.sc, tat, ty)?;
                self.end_header_line();
                self.values(at, kw, num, (n as u64).saturating_mul(per), |_| ())
            }
            "TEXTURE_COORDINATES" => {
                let n = self.owner_count(at)?;
                self.sc.next("a name")?;
                let (_, dim) = self.sc.count("a dimension 1..3")?;
                let (tat, ty) = self.sc.next("a data type")?;
                let num = vtk_type(&self.sc, tat, ty)?;
                self.end_header_line();
                // Point texture coordinates of 2 or 3 components keep their
                // first two as the fields `u` and `v` (the DMS room's
                // `--param uv`).
                let keep = matches!(self.owner, Owner::Points(_)) && dim >= 2;
                let mut uv: [Vec<f32>; 2] = [Vec::new(), Vec::new()];
                let mut k = 0u64;
                self.values(
                    at,
                    "texture coordinates",
                    num,
                    (n as u64).saturating_mul(dim),
                    |x| {
                        if keep && k % dim < 2 {
                            uv[(k % dim) as usize].push(x as f32);
                        }
                        k += 1;
                    },
                )?;
                if keep {
                    let [u, v] = uv;
                    self.scalars.push(ScalarField {
                        name: "u".into(),
                        values: u,
                    });
                    self.scalars.push(ScalarField {
                        name: "v".into(),
                        values: v,
                    });
                }
                Ok(())
            }
            "FIELD" => self.field(at),
            "METADATA" => {
                self.sc.skip_line();
                skip_metadata_lines(&mut self.sc);
                Ok(())
            }
            _ => Err(self.sc.error(
                at,
                "a POLYDATA section (POINTS, POLYGONS, TRIANGLE_STRIPS, POINT_DATA, ...)",
                format!("`{}`", clip(kw)),
            )),
        }
    }

    fn owner_count(&self, at: usize) -> Result<usize> {
        match self.owner {
            Owner::Points(n) | Owner::Cells(n) => Ok(n),
            Owner::None => Err(self.sc.error(
                at,
                "POINT_DATA or CELL_DATA before attribute data",
                "an attribute outside a data section",
            )),
        }
    }

    fn points(&mut self, at: usize) -> Result<()> {
        if self.have_points {
            return Err(self.sc.error(at, "one POINTS section", "a second POINTS"));
        }
        let (_, n) = self.sc.count("a point count")?;
        let (tat, ty) = self.sc.next("a data type")?;
        let num = vtk_type(&self.sc, tat, ty)?;
        self.end_header_line();
        let min = self.min_bytes(num);
        let n = self
            .sc
            .check_count(at, "point coordinates", n.saturating_mul(3), min)?
            / 3;
        let mut positions = Vec::with_capacity(n);
        for _ in 0..n {
            let mut p = [0f32; 3];
            for c in &mut p {
                let vat = self.sc.mark();
                let v = self.sc.value(num, self.binary, "a point coordinate")? as f32;
                if !v.is_finite() {
                    return Err(self
                        .sc
                        .error(vat, "a finite point coordinate", format!("{v}")));
                }
                *c = v;
            }
            positions.push(Vec3::from_array(p));
        }
        self.positions = positions;
        self.have_points = true;
        Ok(())
    }

    fn cells(&mut self, at: usize, kind: CellKind) -> Result<()> {
        let (_, n) = self.sc.count("a cell count")?;
        let (_, size) = self.sc.count("a cell list size")?;
        if kind != CellKind::Skip && !self.have_points {
            return Err(self
                .sc
                .error(at, "POINTS before the cells", "cells before POINTS"));
        }
        self.end_header_line();
        let offsets_follow = match self.binary {
            Some(_) => self.sc.rest().starts_with(b"OFFSETS"),
            None => self
                .sc
                .peek()
                .is_some_and(|t| t.eq_ignore_ascii_case(b"OFFSETS")),
        };
        let mut corners = Vec::new();
        let mut polygons: Vec<(usize, std::ops::Range<usize>)> = Vec::new();
        if offsets_follow {
            // VTK 5.1: `n` offsets (cells + 1), then `size` connectivity entries.
            self.sc.keyword("OFFSETS")?;
            let (tat, ty) = self.sc.next("an offset type")?;
            let num = vtk_type(&self.sc, tat, ty)?;
            self.end_header_line();
            let mut offsets = Vec::new();
            let oat = self.sc.mark();
            let min = self.min_bytes(num);
            let count = self.sc.check_count(oat, "cell offsets", n, min)?;
            offsets.reserve(count);
            for _ in 0..count {
                let vat = self.sc.mark();
                let o = self.sc.index(num, self.binary, "a cell offset")?;
                let prev = offsets.last().copied().unwrap_or(0);
                if o < prev || o as u64 > size || (offsets.is_empty() && o != 0) {
                    return Err(self.sc.error(
                        vat,
                        format!("non-decreasing offsets from 0 up to {size}"),
                        format!("{o}"),
                    ));
                }
                offsets.push(o);
            }
            if offsets.last().is_some_and(|&o| o as u64 != size) {
                return Err(self.sc.error(
                    oat,
                    format!("a last offset equal to the connectivity size {size}"),
                    format!("{:?}", offsets.last()),
                ));
            }
            self.sc.keyword("CONNECTIVITY")?;
            let (tat, ty) = self.sc.next("a connectivity type")?;
            let num = vtk_type(&self.sc, tat, ty)?;
            self.end_header_line();
            let cat = self.sc.mark();
            let min = self.min_bytes(num);
            let count = self
                .sc
                .check_count(cat, "connectivity entries", size, min)?;
            corners.reserve(count);
            for _ in 0..count {
                let vat = self.sc.mark();
                corners.push((vat, self.sc.index(num, self.binary, "a point index")?));
            }
            for w in offsets.windows(2) {
                polygons.push((cat, w[0] as usize..w[1] as usize));
            }
            self.n_cells += offsets.len().saturating_sub(1) as u64;
        } else {
            let min = self.min_bytes(Num::I32);
            let count = self.sc.check_count(at, "cell list entries", size, min)?;
            let cells = self.sc.check_count(at, "cells", n, min)?;
            corners.reserve(count);
            for _ in 0..cells {
                let cat = self.sc.mark();
                let k = self.sc.index(Num::I32, self.binary, "a cell size")?;
                let end = corners.len() as u64 + 1 + k.max(0) as u64;
                if k < 0 || end > size {
                    return Err(self.sc.error(
                        cat,
                        format!("a cell size that fits the list size {size}"),
                        format!("{k}"),
                    ));
                }
                // The count entry itself occupies one slot of `size`.
                corners.push((cat, -1));
                let first = corners.len();
                for _ in 0..k {
                    let vat = self.sc.mark();
                    corners.push((vat, self.sc.index(Num::I32, self.binary, "a point index")?));
                }
                polygons.push((cat, first..corners.len()));
            }
            if corners.len() as u64 != size {
                return Err(self.sc.error(
                    at,
                    format!("cells filling the list size {size}"),
                    format!("{} entries", corners.len()),
                ));
            }
            self.n_cells += n;
        }
        if kind == CellKind::Skip {
            return Ok(());
        }
        let nv = self.positions.len();
        let mut poly = Vec::new();
        for (cat, range) in polygons {
            poly.clear();
            for &(vat, ix) in &corners[range] {
                if ix < 0 || ix as usize >= nv {
                    return Err(self.sc.error(
                        vat,
                        format!("a point index in 0..{nv}"),
                        format!("{ix}"),
                    ));
                }
                poly.push(ix as u32);
            }
            if poly.len() < 3 {
                return Err(self.sc.error(
                    cat,
                    "a polygon or strip with at least 3 points",
                    format!("{} points", poly.len()),
                ));
            }
            match kind {
                CellKind::Polygons => fan(&poly, &mut self.triangles),
                CellKind::Strips => {
                    for i in 0..poly.len() - 2 {
                        let t = if i % 2 == 0 {
                            [poly[i], poly[i + 1], poly[i + 2]]
                        } else {
                            [poly[i + 1], poly[i], poly[i + 2]]
                        };
                        self.triangles.push(t);
                    }
                }
                CellKind::Skip => {}
            }
        }
        Ok(())
    }

    fn scalars_section(&mut self, at: usize) -> Result<()> {
        let n = self.owner_count(at)?;
        let (name, _, num, comps) = scalars_header(&mut self.sc, self.binary.is_some())?;
        let name = name.to_string();
        let count = (n as u64).saturating_mul(comps);
        let keep = matches!(self.owner, Owner::Points(_)) && comps == 1;
        let mut values = Vec::new();
        self.values(at, "scalar values", num, count, |v| {
            if keep {
                values.push(v as f32);
            }
        })?;
        if keep {
            self.scalars.push(ScalarField { name, values });
        }
        Ok(())
    }

    fn colours(&mut self, at: usize, count: u64) -> Result<()> {
        let num = match self.binary {
            Some(_) => Num::U8,
            None => Num::F32,
        };
        self.values(at, "colour values", num, count, |_| ())
    }

    fn field(&mut self, at: usize) -> Result<()> {
        self.owner_count(at)?;
        self.sc.next("a field name")?;
        let (_, arrays) = self.sc.count("a number of arrays")?;
        for _ in 0..arrays {
            let (aat, name) = self.sc.next("an array name")?;
            let name = name.to_string();
            let (_, comps) = self.sc.count("a number of components")?;
            let (_, tuples) = self.sc.count("a number of tuples")?;
            let (tat, ty) = self.sc.next("a data type")?;
            let num = vtk_type(&self.sc, tat, ty)?;
            self.end_header_line();
            let keep = matches!(self.owner, Owner::Points(n) if n as u64 == tuples) && comps == 1;
            let mut values = Vec::new();
            self.values(
                aat,
                "field values",
                num,
                comps.saturating_mul(tuples),
                |v| {
                    if keep {
                        values.push(v as f32);
                    }
                },
            )?;
            if keep {
                self.scalars.push(ScalarField { name, values });
            }
            if self.binary.is_none() {
                skip_array_metadata(&mut self.sc)?;
            }
        }
        Ok(())
    }
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum CellKind {
    Polygons,
    Strips,
    Skip,
}

/// Writes `mesh` as an ASCII VTK legacy POLYDATA file.
pub(crate) fn write(w: &mut dyn Write, mesh: &TriMesh) -> io::Result<()> {
    writeln!(w, "# vtk DataFile Version 3.0")?;
    writeln!(w, "chisel mesh")?;
    writeln!(w, "ASCII")?;
    writeln!(w, "DATASET POLYDATA")?;
    writeln!(w, "POINTS {} float", mesh.positions.len())?;
    for p in &mesh.positions {
        writeln!(w, "{} {} {}", p.x, p.y, p.z)?;
    }
    let nt = mesh.triangles.len();
    writeln!(w, "POLYGONS {nt} {}", 4 * nt)?;
    for [a, b, c] in &mesh.triangles {
        writeln!(w, "3 {a} {b} {c}")?;
    }
    if !mesh.scalars.is_empty() {
        writeln!(w, "POINT_DATA {}", mesh.positions.len())?;
        for s in &mesh.scalars {
            writeln!(w, "SCALARS {} float 1", field_name(&s.name))?;
            writeln!(w, "LOOKUP_TABLE default")?;
            for v in &s.values {
                writeln!(w, "{v}")?;
            }
        }
    }
    Ok(())
}
