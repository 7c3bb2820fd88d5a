//! Wavefront OBJ (`.obj`), geometry only.
//!
//! Read: `v x y z [w …]` (extra values such as `w` or vertex colours are
//! ignored) and `f` with `v`, `v/vt`, `v//vn` or `v/vt/vn` corners, 1-based or
//! negative (relative to the vertices defined so far), polygons
//! fan-triangulated. A face may only refer to vertices defined before it.
//! `vt`, `vn`, groups, materials, smoothing groups, lines and other
//! statements are ignored. OBJ has no per-vertex scalars.
//!
//! Write: `v` lines and 1-based `f` triangles.

use std::io::{self, Write};
use std::path::Path;

use glam::Vec3;

use super::text::{Scanner, clip, fan};
use crate::{Result, TriMesh};

/// Reads an OBJ file held in `bytes`.
pub(crate) fn read(path: &Path, bytes: &[u8]) -> Result<TriMesh> {
    let mut sc = Scanner::new(path, bytes);
    let mut mesh = TriMesh::default();
    let mut poly = Vec::new();
    while let Some((at, line)) = sc.line() {
        let mut words = line
            .split(u8::is_ascii_whitespace)
            .filter(|w| !w.is_empty());
        match words.next() {
            Some(b"v") => {
                let mut p = [0f32; 3];
                for c in &mut p {
                    let w = words.next().unwrap_or(b"");
                    *c = std::str::from_utf8(w)
                        .ok()
                        .and_then(|t| t.parse::<f32>().ok())
                        .filter(|v| v.is_finite())
                        .ok_or_else(|| sc.error(at, "a finite vertex coordinate", shown(w)))?;
                }
                mesh.positions.push(Vec3::from_array(p));
            }
            Some(b"f") => {
                let nv = mesh.positions.len() as i64;
                poly.clear();
                for w in words {
                    let head = w.split(|&b| b == b'/').next().unwrap_or(b"");
                    let ix = std::str::from_utf8(head)
                        .ok()
                        .and_then(|t| t.parse::<i64>().ok())
                        .ok_or_else(|| {
                            sc.error(at, "a vertex index (v, v/vt, v//vn or v/vt/vn)", shown(w))
                        })?;
                    let resolved = if ix < 0 { nv + ix } else { ix - 1 };
                    if ix == 0 || resolved < 0 || resolved >= nv {
                        return Err(sc.error(
                            at,
                            format!("a vertex index in 1..={nv} or -{nv}..=-1"),
                            format!("{ix}"),
                        ));
                    }
                    poly.push(resolved as u32);
                }
                if poly.len() < 3 {
                    return Err(sc.error(
                        at,
                        "a face with at least 3 vertices",
                        format!("{} vertices", poly.len()),
                    ));
                }
                fan(&poly, &mut mesh.triangles);
            }
            _ => {}
        }
    }
    Ok(mesh)
}

fn shown(w: &[u8]) -> String {
    if w.is_empty() {
        "nothing".into()
    } else {
        format!("`{}`", clip(&String::from_utf8_lossy(w)))
    }
}

/// Writes `mesh` as OBJ (`v` lines, 1-based `f` triangles; scalars dropped).
pub(crate) fn write(w: &mut dyn Write, mesh: &TriMesh) -> io::Result<()> {
    writeln!(w, "# written by chisel")?;
    for p in &mesh.positions {
        writeln!(w, "v {} {} {}", p.x, p.y, p.z)?;
    }
    for [a, b, c] in &mesh.triangles {
        writeln!(
            w,
            "f {} {} {}",
            u64::from(*a) + 1,
            u64::from(*b) + 1,
            u64::from(*c) + 1
        )?;
    }
    Ok(())
}
