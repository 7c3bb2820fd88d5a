//! STL (`.stl`), ASCII and binary.
//!
//! Read: a file is binary when its length is exactly `84 + 50·n` for the
//! facet count `n` at byte 80; otherwise it must be ASCII (`solid …`), and a
//! file that starts with neither is checked as binary against its length:
//! fewer bytes than the count announces, or more, is an error.
//! Facet corners with bit-identical coordinates (`-0` = `+0`) are welded
//! into one vertex, in order of first appearance, so the result is an
//! indexed mesh. Facet normals are ignored (the winding defines the normal).
//! ASCII loops with more than 3 vertices are fan-triangulated.
//!
//! Write: binary, facet normals from the winding (zero for degenerate
//! facets), attribute bytes 0. STL has no per-vertex scalars.

use std::collections::HashMap;
use std::io::{self, Write};
use std::path::Path;

use glam::Vec3;

use super::text::{Endian, Num, Scanner, clip, fan};
use crate::{Error, Position, Result, TriMesh};

/// Welds identical corners into an indexed mesh.
#[derive(Debug, Default)]
struct Welder {
    index: HashMap<[u32; 3], u32>,
    mesh: TriMesh,
}

impl Welder {
    fn corner(&mut self, p: [f32; 3]) -> u32 {
        // `+ 0.0` turns -0.0 into +0.0 so both weld.
        let key = p.map(|c| (c + 0.0).to_bits());
        let next = self.mesh.positions.len() as u32;
        *self.index.entry(key).or_insert_with(|| {
            self.mesh.positions.push(Vec3::from_array(p));
            next
        })
    }
}

/// The size a binary STL's facet count implies, from the file's first
/// bytes (`None` for an ASCII one, which starts with `solid` and is text).
pub(crate) fn implied_len(bytes: &[u8]) -> Option<u64> {
    let starts_solid = bytes
        .iter()
        .position(|b| !b.is_ascii_whitespace())
        .is_some_and(|i| bytes[i..].starts_with(b"solid"));
    if bytes.len() < 84 || (starts_solid && !bytes.contains(&0)) {
        return None;
    }
    let n = u64::from(u32::from_le_bytes([
        bytes[80], bytes[81], bytes[82], bytes[83],
    ]));
    Some(84 + 50 * n)
}

/// Reads an STL file held in `bytes`.
pub(crate) fn read(path: &Path, bytes: &[u8]) -> Result<TriMesh> {
    if bytes.len() >= 84 {
        let n = u64::from(u32::from_le_bytes([
            bytes[80], bytes[81], bytes[82], bytes[83],
        ]));
        let starts_solid = bytes
            .iter()
            .position(|b| !b.is_ascii_whitespace())
            .is_some_and(|i| bytes[i..].starts_with(b"solid"));
        if 84 + 50 * n == bytes.len() as u64 || !starts_solid {
            return read_binary(path, bytes, n);
        }
    }
    read_ascii(path, bytes)
}

fn read_binary(path: &Path, bytes: &[u8], n: u64) -> Result<TriMesh> {
    let mut sc = Scanner::new(path, bytes);
    sc.take(84, "the 84-byte binary STL header")?;
    let n = sc.check_count(80, "facets of 50 bytes", n, 50)?;
    let mut w = Welder::default();
    w.mesh.triangles.reserve(n);
    for _ in 0..n {
        let facet = sc.mark();
        sc.take(12, "a facet normal")?;
        let mut tri = [0u32; 3];
        for corner in &mut tri {
            let mut p = [0f32; 3];
            for c in &mut p {
                let at = sc.mark();
                *c = Num::F32.decode(sc.take(4, "a coordinate")?, Endian::Little) as f32;
                if !c.is_finite() {
                    return Err(Error::format(
                        path,
                        Position::Byte(at as u64),
                        format!("a finite coordinate (facet at byte {facet})"),
                        format!("{c}"),
                    ));
                }
            }
            *corner = w.corner(p);
        }
        sc.take(2, "facet attribute bytes")?;
        w.mesh.triangles.push(tri);
    }
    if !sc.rest().is_empty() {
        return Err(Error::format(
            path,
            Position::Byte(84 + 50 * n as u64),
            format!("the end of the file after the {n} facets the count at byte 80 announces"),
            "more data",
        ));
    }
    Ok(w.mesh)
}

fn read_ascii(path: &Path, bytes: &[u8]) -> Result<TriMesh> {
    let mut sc = Scanner::new(path, bytes);
    let mut w = Welder::default();
    let mut poly = Vec::new();
    sc.keyword("solid")?;
    sc.skip_line();
    loop {
        let (at, kw) = sc.next("`facet` or `endsolid`")?;
        if kw.eq_ignore_ascii_case("endsolid") {
            sc.skip_line();
            if sc.at_end() {
                break;
            }
            sc.keyword("solid")?;
            sc.skip_line();
            continue;
        }
        if !kw.eq_ignore_ascii_case("facet") {
            return Err(sc.error(at, "`facet` or `endsolid`", format!("`{}`", clip(kw))));
        }
        sc.keyword("normal")?;
        for _ in 0..3 {
            sc.parse::<f32>("a normal component")?;
        }
        sc.keyword("outer")?;
        sc.keyword("loop")?;
        poly.clear();
        loop {
            let (vat, kw) = sc.next("`vertex` or `endloop`")?;
            if kw.eq_ignore_ascii_case("endloop") {
                break;
            }
            if !kw.eq_ignore_ascii_case("vertex") {
                return Err(sc.error(vat, "`vertex` or `endloop`", format!("`{}`", clip(kw))));
            }
            let mut p = [0f32; 3];
            for c in &mut p {
                *c = sc.finite_f32("a finite vertex coordinate")?;
            }
            poly.push(w.corner(p));
        }
        if poly.len() < 3 {
            return Err(sc.error(
                at,
                "a facet with at least 3 vertices",
                format!("{}", poly.len()),
            ));
        }
        fan(&poly, &mut w.mesh.triangles);
        sc.keyword("endfacet")?;
    }
    Ok(w.mesh)
}

/// Writes `mesh` as binary STL (scalars dropped).
pub(crate) fn write(w: &mut dyn Write, mesh: &TriMesh) -> io::Result<()> {
    let mut header = [b' '; 80];
    let tag = b"binary STL written by chisel";
    header[..tag.len()].copy_from_slice(tag);
    w.write_all(&header)?;
    let n = u32::try_from(mesh.triangles.len())
        .map_err(|_| io::Error::new(io::ErrorKind::InvalidInput, "more than 2^32 triangles"))?;
    w.write_all(&n.to_le_bytes())?;
    for t in &mesh.triangles {
        let [a, b, c] = t.map(|i| mesh.positions[i as usize]);
        let normal = (b - a).cross(c - a).normalize_or_zero();
        for v in [normal, a, b, c] {
            for x in v.to_array() {
                w.write_all(&x.to_le_bytes())?;
            }
        }
        w.write_all(&[0, 0])?;
    }
    Ok(())
}
