//! Stanford PLY (`.ply`): `ascii`, `binary_little_endian`, `binary_big_endian`.
//!
//! Read: LF or CRLF header, classic (`float`, `uchar`, `int`) and sized
//! (`float32`, `uint8`, `int32`) type names. The `vertex` element needs
//! `x`, `y`, `z`; every other scalar vertex property (e.g. bunny's
//! `confidence` and `intensity`, or `nx`, `red`) becomes a [`ScalarField`] of
//! that name. The `face` element's `vertex_indices` (or `vertex_index`) list
//! is fan-triangulated; other elements and list properties are skipped.
//! Indices are checked against the vertex count the header announces.
//!
//! Write: `binary_little_endian`, `float x y z` plus one `float` property per
//! scalar field, faces as `list uchar uint vertex_indices`.

use std::io::{self, Write};
use std::path::Path;

use glam::Vec3;

use super::text::{Endian, Num, Scanner, clip, fan};
use super::vtk::field_name;
use crate::mesh::ScalarField;
use crate::{Position, Result, TriMesh};

#[derive(Debug, Clone, Copy)]
enum PropKind {
    Scalar(Num),
    List(Num, Num),
}

#[derive(Debug)]
struct Prop {
    name: String,
    kind: PropKind,
}

#[derive(Debug)]
struct Element {
    name: String,
    count: u64,
    at: usize,
    line: Position,
    props: Vec<Prop>,
}

fn ply_type(sc: &Scanner, at: usize, name: &str) -> Result<Num> {
    Ok(match name {
        "char" | "int8" => Num::I8,
        "uchar" | "uint8" => Num::U8,
        "short" | "int16" => Num::I16,
        "ushort" | "uint16" => Num::U16,
        "int" | "int32" => Num::I32,
        "uint" | "uint32" => Num::U32,
        "float" | "float32" => Num::F32,
        "double" | "float64" => Num::F64,
        _ => {
            return Err(sc.error(
                at,
                "a PLY type (char uchar short ushort int uint float double or int8 … float64)",
                format!("`{}`", clip(name)),
            ));
        }
    })
}

/// Checks the first line, `ply`, of `bytes` (the file, or its first bytes
/// before the rest is read); returns the scanner after it.
pub(crate) fn magic<'a>(path: &'a Path, bytes: &'a [u8]) -> Result<Scanner<'a>> {
    let mut sc = Scanner::new(path, bytes);
    let (at, magic) = sc.text_line("`ply`")?;
    if magic.trim() != "ply" {
        return Err(sc.error(at, "`ply`", format!("`{}`", clip(magic.trim()))));
    }
    Ok(sc)
}

/// Reads a PLY file held in `bytes`.
pub(crate) fn read(path: &Path, bytes: &[u8]) -> Result<TriMesh> {
    let mut sc = magic(path, bytes)?;
    let mut format = None;
    let mut elements: Vec<Element> = Vec::new();
    loop {
        let (at, line) = sc.text_line("a header line or `end_header`")?;
        let words: Vec<&str> = line.split_whitespace().collect();
        match words.as_slice() {
            [] | ["comment", ..] | ["obj_info", ..] => {}
            ["format", f, _version] => {
                format = Some(match *f {
                    "ascii" => None,
                    "binary_little_endian" => Some(Endian::Little),
                    "binary_big_endian" => Some(Endian::Big),
                    _ => {
                        return Err(sc.error(
                            at,
                            "ascii, binary_little_endian or binary_big_endian",
                            format!("`{}`", clip(f)),
                        ));
                    }
                });
            }
            ["element", name, count] => {
                let count = count.parse::<u64>().map_err(|_| {
                    sc.error(
                        at,
                        "a non-negative element count",
                        format!("`{}`", clip(count)),
                    )
                })?;
                elements.push(Element {
                    name: (*name).to_string(),
                    count,
                    at,
                    line: sc.position(at),
                    props: Vec::new(),
                });
            }
            ["property", "list", ct, it, name] => {
                let ct = ply_type(&sc, at, ct)?;
                let it = ply_type(&sc, at, it)?;
                if !ct.is_integer() {
                    return Err(sc.error(at, "an integer list count type", "a float type"));
                }
                let el = elements
                    .last_mut()
                    .ok_or_else(|| sc.error(at, "`element` before `property`", "`property`"))?;
                el.props.push(Prop {
                    name: (*name).to_string(),
                    kind: PropKind::List(ct, it),
                });
            }
            ["property", ty, name] => {
                let ty = ply_type(&sc, at, ty)?;
                let el = elements
                    .last_mut()
                    .ok_or_else(|| sc.error(at, "`element` before `property`", "`property`"))?;
                el.props.push(Prop {
                    name: (*name).to_string(),
                    kind: PropKind::Scalar(ty),
                });
            }
            ["end_header"] => break,
            _ => {
                return Err(sc.error(
                    at,
                    "format, element, property, comment or end_header",
                    format!("`{}`", clip(line.trim())),
                ));
            }
        }
    }
    let Some(binary) = format else {
        let header_end = sc.mark();
        return Err(sc.error(header_end, "a `format` line", "none"));
    };
    // Before any `mark`: a text mark skips whitespace, which in a binary
    // payload would eat data bytes (0x09–0x0d, 0x20).
    if binary.is_some() {
        sc.set_binary();
    }
    let nv = elements
        .iter()
        .find(|e| e.name == "vertex")
        .map_or(0, |e| e.count);
    let mut mesh = TriMesh::default();
    for el in &elements {
        read_element(&mut sc, binary, el, nv, &mut mesh)?;
    }
    // Data past the header's elements (for text, more than whitespace): the
    // counts do not describe the file.
    let done = if binary.is_some() {
        sc.rest().is_empty()
    } else {
        sc.at_end()
    };
    if !done {
        let at = sc.mark();
        return Err(sc.error(
            at,
            "the end of the file after the elements the header announces",
            "more data",
        ));
    }
    Ok(mesh)
}

/// What to do with each property of an element.
#[derive(Debug, Clone, Copy)]
enum Role {
    Coord(usize),
    Scalar(usize),
    Corners,
    Skip,
}

fn read_element(
    sc: &mut Scanner,
    binary: Option<Endian>,
    el: &Element,
    nv: u64,
    mesh: &mut TriMesh,
) -> Result<()> {
    let min_row: u64 = el
        .props
        .iter()
        .map(|p| match (binary, p.kind) {
            (None, _) => 2,
            (Some(_), PropKind::Scalar(t) | PropKind::List(t, _)) => t.size() as u64,
        })
        .sum();
    let what = format!("`{}` elements", el.name);
    let count = sc.check_count_at(el.line.clone(), &what, el.count, min_row.max(1))?;
    let is_vertex = el.name == "vertex";
    let is_face = el.name == "face";
    let mut roles = Vec::with_capacity(el.props.len());
    let mut fields = Vec::new();
    let mut coords = [false; 3];
    for p in &el.props {
        let role = match (p.kind, p.name.as_str()) {
            (PropKind::Scalar(_), n @ ("x" | "y" | "z")) if is_vertex => {
                let axis = usize::from(n.as_bytes()[0] - b'x');
                coords[axis] = true;
                Role::Coord(axis)
            }
            (PropKind::Scalar(_), n) if is_vertex => {
                fields.push(ScalarField {
                    name: n.to_string(),
                    values: Vec::with_capacity(count),
                });
                Role::Scalar(fields.len() - 1)
            }
            (PropKind::List(..), "vertex_indices" | "vertex_index") if is_face => Role::Corners,
            _ => Role::Skip,
        };
        roles.push(role);
    }
    if is_vertex && coords.contains(&false) {
        return Err(sc.error(el.at, "vertex properties x, y and z", "some missing"));
    }
    if is_face && !roles.iter().any(|r| matches!(r, Role::Corners)) {
        return Err(sc.error(el.at, "a face list property `vertex_indices`", "none"));
    }
    if is_vertex {
        mesh.positions.reserve(count);
    }
    let mut poly = Vec::new();
    for _ in 0..count {
        let mut p = [0f32; 3];
        for (prop, role) in el.props.iter().zip(&roles) {
            match prop.kind {
                PropKind::Scalar(t) => {
                    let at = sc.mark();
                    let v = sc.value(t, binary, &format!("property `{}`", prop.name))?;
                    match *role {
                        Role::Coord(axis) => {
                            let c = v as f32;
                            if !c.is_finite() {
                                return Err(sc.error(at, "a finite coordinate", format!("{v}")));
                            }
                            p[axis] = c;
                        }
                        Role::Scalar(i) => fields[i].values.push(v as f32),
                        Role::Corners | Role::Skip => {}
                    }
                }
                PropKind::List(ct, it) => {
                    let at = sc.mark();
                    let k = sc.index(ct, binary, "a list length")?;
                    let min = if binary.is_some() {
                        it.size() as u64
                    } else {
                        2
                    };
                    let k = u64::try_from(k)
                        .map_err(|_| sc.error(at, "a non-negative list length", format!("{k}")))?;
                    let k = sc.check_count(at, "list entries", k, min)?;
                    let corners = matches!(role, Role::Corners);
                    if corners && k < 3 {
                        return Err(sc.error(
                            at,
                            "a face with at least 3 vertices",
                            format!("{k}"),
                        ));
                    }
                    poly.clear();
                    for _ in 0..k {
                        let vat = sc.mark();
                        if corners {
                            let ix = sc.index(it, binary, "a vertex index")?;
                            if ix < 0 || ix as u64 >= nv {
                                return Err(sc.error(
                                    vat,
                                    format!("a vertex index in 0..{nv}"),
                                    format!("{ix}"),
                                ));
                            }
                            poly.push(ix as u32);
                        } else {
                            sc.value(it, binary, "a list entry")?;
                        }
                    }
                    if corners {
                        fan(&poly, &mut mesh.triangles);
                    }
                }
            }
        }
        if is_vertex {
            mesh.positions.push(Vec3::from_array(p));
        }
    }
    mesh.scalars.extend(fields);
    Ok(())
}

/// Writes `mesh` as binary little-endian PLY, scalars as float properties.
pub(crate) fn write(w: &mut dyn Write, mesh: &TriMesh) -> io::Result<()> {
    writeln!(w, "ply")?;
    writeln!(w, "format binary_little_endian 1.0")?;
    writeln!(w, "comment written by chisel")?;
    writeln!(w, "element vertex {}", mesh.positions.len())?;
    for axis in ["x", "y", "z"] {
        writeln!(w, "property float {axis}")?;
    }
    for s in &mesh.scalars {
        writeln!(w, "property float {}", field_name(&s.name))?;
    }
    writeln!(w, "element face {}", mesh.triangles.len())?;
    writeln!(w, "property list uchar uint vertex_indices")?;
    writeln!(w, "end_header")?;
    for (i, p) in mesh.positions.iter().enumerate() {
        for c in p.to_array() {
            w.write_all(&c.to_le_bytes())?;
        }
        for s in &mesh.scalars {
            w.write_all(&s.values[i].to_le_bytes())?;
        }
    }
    for t in &mesh.triangles {
        w.write_all(&[3])?;
        for &ix in t {
            w.write_all(&ix.to_le_bytes())?;
        }
    }
    Ok(())
}
