//! Storage of a [`Polyhedron`]: the compact integer encoding (eq. 8.2 per
//! shell), a binary `.cells` file around it, and a readable JSON form.
//!
//! Compact encoding (`i64`): `[N_shells]`, then per shell `[parent + 1 (0 =
//! root), role (+1 object, −1 background), kind, kind argument, voxels,
//! dimension]` followed by its geometry: a point `x y z`; a segment
//! `x y z x y z`; a polygon or polyhedron as the cell list's compact form
//! ([`crate::hull::CellList::encode_compact`]: `N_V, N_F`, coordinates, then
//! per face `k` and its `k` vertex indices) with the face cycles of
//! background shells reversed (orientation reversal, §4.4.1/§4.4.2).
//!
//! Binary file: the 8 bytes `CHISELPH`, a little-endian `u32` version (1),
//! a `u64` count `n`, then `n` little-endian `i64`. The reader checks the
//! length against `n` before allocating and validates every shell (parents
//! before children, coordinates of points and segments at voxel centres,
//! polytopes convex and of the stated dimension).

use std::path::Path;

use super::ZkhClass;
use super::polyhedrize::{Polyhedron, Role, Shell, ShellGeometry, ShellKind};
use crate::hull::ConvexHull;
use crate::voxel::Frame;

const MAGIC: &[u8; 8] = b"CHISELPH";
const VERSION: u32 = 1;
/// Header bytes: magic, version, count.
const HEADER: usize = 8 + 4 + 8;

fn kind_code(kind: ShellKind) -> (i64, i64) {
    match kind {
        ShellKind::Hull => (0, 0),
        ShellKind::Zkh(ZkhClass::Cavity) => (1, 0),
        ShellKind::Zkh(ZkhClass::Concavity) => (2, 0),
        ShellKind::Zkh(ZkhClass::Tunnel) => (3, 0),
        ShellKind::Zkh(ZkhClass::BranchedTunnel) => (4, 0),
        ShellKind::Component => (5, 0),
        ShellKind::Ball(r2) => (6, i64::from(r2)),
    }
}

fn kind_of(code: i64, arg: i64) -> Option<ShellKind> {
    Some(match code {
        0 => ShellKind::Hull,
        1 => ShellKind::Zkh(ZkhClass::Cavity),
        2 => ShellKind::Zkh(ZkhClass::Concavity),
        3 => ShellKind::Zkh(ZkhClass::Tunnel),
        4 => ShellKind::Zkh(ZkhClass::BranchedTunnel),
        5 => ShellKind::Component,
        6 => ShellKind::Ball(u32::try_from(arg).ok()?),
        _ => return None,
    })
}

/// A cursor over the integers of a compact encoding.
struct Reader<'a> {
    data: &'a [i64],
    pos: usize,
}

impl Reader<'_> {
    fn next(&mut self, what: &str) -> crate::Result<i64> {
        let v = self.data.get(self.pos).copied().ok_or_else(|| {
            crate::Error::data(
                "cell list",
                "integer",
                self.pos,
                format!("the list ends where the {what} was expected"),
            )
        })?;
        self.pos += 1;
        Ok(v)
    }

    fn point(&mut self, what: &str) -> crate::Result<[i64; 3]> {
        Ok([self.next(what)?, self.next(what)?, self.next(what)?])
    }
}

impl Polyhedron {
    /// The compact integer encoding (module docs).
    pub fn encode(&self) -> Vec<i64> {
        let mut out = vec![self.shells.len() as i64];
        for s in &self.shells {
            let (code, arg) = kind_code(s.kind);
            out.extend([
                s.parent.map_or(0, |p| i64::from(p) + 1),
                s.role.sign() as i64,
                code,
                arg,
                s.voxels as i64,
                i64::from(s.geometry.dimension()),
            ]);
            match &s.geometry {
                ShellGeometry::Point(p) => out.extend(p),
                ShellGeometry::Segment(a, b) => {
                    out.extend(a);
                    out.extend(b);
                }
                ShellGeometry::Polytope(h) => {
                    out.extend([h.n_vertices() as i64, h.n_faces() as i64]);
                    for v in h.vertices() {
                        out.extend(v);
                    }
                    for f in h.faces() {
                        out.push(f.vertices.len() as i64);
                        let cycle = f.vertices.iter().map(|&v| i64::from(v));
                        match s.role {
                            Role::Object => out.extend(cycle),
                            Role::Background => out.extend(cycle.rev()),
                        }
                    }
                }
            }
        }
        out
    }

    /// Rebuilds a polyhedron from [`Polyhedron::encode`] output.
    ///
    /// Errors: [`crate::Error::InvalidData`] naming the shell (or the
    /// integer) and what is wrong for truncated, inconsistent or non-convex
    /// data.
    pub fn decode(data: &[i64], frame: Frame) -> crate::Result<Polyhedron> {
        let mut r = Reader { data, pos: 0 };
        let n = r.next("shell count")?;
        let n = usize::try_from(n)
            .ok()
            .filter(|&n| n <= data.len())
            .ok_or_else(|| {
                crate::Error::data("cell list", "integer", 0, format!("bad shell count {n}"))
            })?;
        let mut shells: Vec<Shell> = Vec::with_capacity(n);
        for i in 0..n {
            let bad = |what: String| crate::Error::data("cell list", "shell", i, what);
            let parent = r.next("parent")?;
            let parent = match parent {
                0 => None,
                p if p >= 1 && ((p - 1) as usize) < i => Some((p - 1) as u32),
                p => return Err(bad(format!("parent {} does not precede it", p - 1))),
            };
            let role = match (r.next("role")?, parent) {
                (1, _) => Role::Object,
                (-1, Some(_)) => Role::Background,
                (r, _) => return Err(bad(format!("role {r} (the root is +1, others ±1)"))),
            };
            let (code, arg) = (r.next("kind")?, r.next("kind argument")?);
            let kind =
                kind_of(code, arg).ok_or_else(|| bad(format!("unknown kind {code}/{arg}")))?;
            let voxels = u64::try_from(r.next("voxel count")?)
                .map_err(|_| bad("negative voxel count".into()))?;
            let dim = r.next("dimension")?;
            let centre = |p: [i64; 3]| {
                if p.iter().all(|c| c.rem_euclid(2) == 1) {
                    Ok(p)
                } else {
                    Err(bad(format!("{p:?} is not a voxel centre")))
                }
            };
            let geometry = match dim {
                0 => ShellGeometry::Point(centre(r.point("point")?)?),
                1 => {
                    let (a, b) = (
                        centre(r.point("segment start")?)?,
                        centre(r.point("segment end")?)?,
                    );
                    if a == b {
                        return Err(bad("segment of length 0".into()));
                    }
                    ShellGeometry::Segment(a, b)
                }
                2 | 3 => {
                    let count = |v: i64, what: &str| {
                        usize::try_from(v)
                            .ok()
                            .filter(|&c| c <= data.len())
                            .ok_or_else(|| bad(format!("bad {what} {v}")))
                    };
                    let n_v = count(r.next("vertex count")?, "vertex count")?;
                    let n_f = count(r.next("face count")?, "face count")?;
                    let mut vertices = Vec::with_capacity(n_v);
                    for _ in 0..n_v {
                        vertices.push(r.point("vertex")?);
                    }
                    let mut cycles = Vec::with_capacity(n_f);
                    for _ in 0..n_f {
                        let k = count(r.next("face size")?, "face size")?;
                        let mut cycle = Vec::with_capacity(k);
                        for _ in 0..k {
                            let v = r.next("face vertex")?;
                            cycle.push(
                                u32::try_from(v).map_err(|_| bad(format!("vertex index {v}")))?,
                            );
                        }
                        if role == Role::Background {
                            cycle.reverse();
                        }
                        cycles.push(cycle);
                    }
                    let hull =
                        ConvexHull::from_faces(vertices, cycles).map_err(|e| bad(e.to_string()))?;
                    let g = ShellGeometry::Polytope(hull);
                    if i64::from(g.dimension()) != dim {
                        return Err(bad(format!(
                            "stated dimension {dim}, found {}",
                            g.dimension()
                        )));
                    }
                    g
                }
                d => return Err(bad(format!("dimension {d}"))),
            };
            let depth = parent.map_or(0, |p| shells[p as usize].depth + 1);
            if let Some(p) = parent
                && shells[p as usize].role == role
            {
                return Err(bad("a child has its parent's role".into()));
            }
            shells.push(Shell {
                geometry,
                parent,
                depth,
                role,
                kind,
                voxels,
            });
        }
        if r.pos != data.len() {
            return Err(crate::Error::data(
                "cell list",
                "integer",
                r.pos,
                format!("{} integers follow the last shell", data.len() - r.pos),
            ));
        }
        Ok(Polyhedron {
            shells,
            frame,
            merges: 0,
        })
    }

    /// The binary `.cells` bytes (module docs).
    pub fn to_bytes(&self) -> Vec<u8> {
        let data = self.encode();
        let mut out = Vec::with_capacity(HEADER + 8 * data.len());
        out.extend_from_slice(MAGIC);
        out.extend_from_slice(&VERSION.to_le_bytes());
        out.extend_from_slice(&(data.len() as u64).to_le_bytes());
        for v in data {
            out.extend_from_slice(&v.to_le_bytes());
        }
        out
    }

    /// Parses `.cells` bytes; `name` labels errors.
    ///
    /// Errors: [`crate::Error::Format`] for a wrong magic or version or a
    /// length that does not match the count, and everything
    /// [`Polyhedron::decode`] refuses (in the context of `name`).
    pub fn from_bytes(bytes: &[u8], name: &str, frame: Frame) -> crate::Result<Polyhedron> {
        use crate::Position;
        if bytes.len() < HEADER || &bytes[..8] != MAGIC {
            return Err(crate::Error::format(
                name,
                Position::Byte(0),
                "the magic CHISELPH of a chisel cell list",
                format!("{} other bytes", bytes.len().min(8)),
            ));
        }
        let version = u32::from_le_bytes([bytes[8], bytes[9], bytes[10], bytes[11]]);
        if version != VERSION {
            return Err(crate::Error::format(
                name,
                Position::Byte(8),
                format!("version {VERSION}"),
                format!("version {version}"),
            ));
        }
        let mut count = [0u8; 8];
        count.copy_from_slice(&bytes[12..20]);
        let n = u64::from_le_bytes(count);
        let body = (bytes.len() - HEADER) as u64;
        if n.checked_mul(8) != Some(body) {
            return Err(crate::Error::format(
                name,
                Position::Byte(12),
                format!(
                    "{n} integers ({} bytes) as the header announces",
                    n.saturating_mul(8)
                ),
                format!("{body} bytes after the header"),
            ));
        }
        let data: Vec<i64> = bytes[HEADER..]
            .chunks_exact(8)
            .map(|c| {
                let mut b = [0u8; 8];
                b.copy_from_slice(c);
                i64::from_le_bytes(b)
            })
            .collect();
        Polyhedron::decode(&data, frame).map_err(|e| e.within(name))
    }

    /// Writes the `.cells` file atomically.
    pub fn write(&self, path: &Path) -> crate::Result<()> {
        crate::foundation::fs::write_atomic(path, &self.to_bytes())
    }

    /// The readable form: one object per shell (parent, depth, role, kind,
    /// voxels, dimension, vertices, faces as vertex cycles oriented as
    /// stored).
    pub fn to_json(&self) -> serde_json::Value {
        let shells: Vec<serde_json::Value> = self
            .shells
            .iter()
            .map(|s| {
                let (vertices, faces): (Vec<[i64; 3]>, Vec<Vec<u32>>) = match &s.geometry {
                    ShellGeometry::Point(p) => (vec![*p], Vec::new()),
                    ShellGeometry::Segment(a, b) => (vec![*a, *b], Vec::new()),
                    ShellGeometry::Polytope(h) => (
                        h.vertices().to_vec(),
                        h.faces()
                            .iter()
                            .map(|f| match s.role {
                                Role::Object => f.vertices.clone(),
                                Role::Background => f.vertices.iter().rev().copied().collect(),
                            })
                            .collect(),
                    ),
                };
                serde_json::json!({
                    "parent": s.parent,
                    "depth": s.depth,
                    "role": s.role,
                    "kind": s.kind,
                    "voxels": s.voxels,
                    "dimension": s.geometry.dimension(),
                    "vertices": vertices,
                    "faces": faces,
                })
            })
            .collect();
        serde_json::json!({
            "coordinates": "combinatorial (voxel (i,j,k) has centre (2i+1, 2j+1, 2k+1))",
            "frame": { "spacing": self.frame.spacing, "origin": self.frame.origin, "axes": self.frame.axes },
            "shells": shells,
        })
    }
}
