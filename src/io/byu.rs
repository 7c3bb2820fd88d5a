//! MovieBYU (`.byu`, `.g`), the mesh format of seed 000 (Bartz 1995, App. C:
//! `mobis` reads triangulations "im MovieByu-Format").
//!
//! Layout (free-format whitespace-separated numbers):
//! 1. `nparts nvertices npolygons nedges` (`nedges` = length of the
//!    connectivity list; read, checked to be non-negative, used as a hint);
//! 2. `nparts` pairs `first last` of 1-based polygon numbers per part;
//! 3. `3·nvertices` coordinates;
//! 4. the connectivity list: 1-based vertex numbers, the last one of each
//!    polygon negated. Polygons are fan-triangulated.
//!
//! Anything after the last polygon (e.g. scalar or displacement blocks of
//! the separate MOVIE.BYU files) is ignored. Write: one part, triangles.

use std::io::{self, Write};
use std::path::Path;

use glam::Vec3;

use super::text::{Num, Scanner, fan};
use crate::{Result, TriMesh};

/// Reads a MovieBYU geometry file held in `bytes`.
pub(crate) fn read(path: &Path, bytes: &[u8]) -> Result<TriMesh> {
    let mut sc = Scanner::new(path, bytes);
    let (pat, parts) = sc.count("the number of parts")?;
    let (vat, nv) = sc.count("the number of vertices")?;
    let (fat, npoly) = sc.count("the number of polygons")?;
    sc.count("the number of connectivity entries")?;
    let parts = sc.check_count(pat, "part ranges", parts, 4)?;
    for _ in 0..parts {
        let at = sc.mark();
        // `first last` with `last = first - 1` is an empty part.
        let first = sc.index(Num::I64, None, "a part's first polygon")?;
        let last = sc.index(Num::I64, None, "a part's last polygon")?;
        if first < 1 || last < first - 1 || last as u64 > npoly {
            return Err(sc.error(
                at,
                format!("a polygon range within 1..={npoly}"),
                format!("{first} {last}"),
            ));
        }
    }
    let nv = sc.check_count(vat, "vertex coordinates", nv.saturating_mul(3), 2)? / 3;
    let mut positions = Vec::with_capacity(nv);
    for _ in 0..nv {
        let mut p = [0f32; 3];
        for c in &mut p {
            *c = sc.finite_f32("a finite vertex coordinate")?;
        }
        positions.push(Vec3::from_array(p));
    }
    let npoly = sc.check_count(fat, "polygons of at least 3 entries", npoly, 6)?;
    let mut triangles = Vec::with_capacity(npoly);
    let mut poly = Vec::new();
    for _ in 0..npoly {
        poly.clear();
        let start = sc.mark();
        loop {
            let at = sc.mark();
            let ix = sc.index(
                Num::I64,
                None,
                "a vertex number (negative to end a polygon)",
            )?;
            if ix == 0 || ix.unsigned_abs() > nv as u64 {
                return Err(sc.error(
                    at,
                    format!("a vertex number in 1..={nv} or its negative"),
                    format!("{ix}"),
                ));
            }
            poly.push((ix.unsigned_abs() - 1) as u32);
            if ix < 0 {
                break;
            }
        }
        if poly.len() < 3 {
            return Err(sc.error(
                start,
                "a polygon with at least 3 vertices",
                format!("{} vertices", poly.len()),
            ));
        }
        fan(&poly, &mut triangles);
    }
    Ok(TriMesh {
        positions,
        triangles,
        scalars: Vec::new(),
    })
}

/// Writes `mesh` as a one-part MovieBYU file (scalars dropped).
pub(crate) fn write(w: &mut dyn Write, mesh: &TriMesh) -> io::Result<()> {
    let nt = mesh.triangles.len();
    writeln!(w, "1 {} {nt} {}", mesh.positions.len(), 3 * nt)?;
    writeln!(w, "1 {nt}")?;
    for p in &mesh.positions {
        writeln!(w, "{} {} {}", p.x, p.y, p.z)?;
    }
    for [a, b, c] in &mesh.triangles {
        let [a, b, c] = [a, b, c].map(|&i| i64::from(i) + 1);
        writeln!(w, "{a} {b} {}", -c)?;
    }
    Ok(())
}
