//! The large-volume hull scan (SPEC §4.3, seed 003 §4.1–4.2): `chisel scan`,
//! `chisel.scan` and `chisel.batch.scan` in Python. Every structure of the volume gets
//! one report row: its exact convex hull (§4.1, cell list and eq. 8.2
//! storage), the inside / on / outside counts of the hull's voxel bounding
//! box (the per-row interval scan of [`crate::hull_scan`], `hull_rows` on the
//! GPU or its CPU mirror, bit-exact either way) and its ZKHs summarised by
//! class (Def. CO/CA/TU).
//!
//! **Structures.** With a level T (`--level T`): every 6-connected component of the
//! samples `≥ T`, numbered in file order as `chisel hull --component N`
//! numbers them. With labels (`--labels`): every distinct non-zero sample value (NaN
//! samples count as background); the object is *all* voxels of that label,
//! which may form several 6-connected components (counted in the row) —
//! one hull per tissue, so background and other tissues enclosed by it
//! show up as its ZKHs; `--level T` plus `chisel hull --label L
//! --component N` gives the per-component view. Structures with fewer
//! than `--min-voxels` voxels are skipped and counted.
//!
//! **Degenerate structures.** Collinear voxel centres (a single voxel, a
//! straight line of voxels) have no polygon and no polyhedron: their row
//! says `"degenerate": "collinear"` and has no hull, scan or ZKHs. A flat
//! structure gets its polygon hull (two opposite faces plus edge
//! half-spaces) and its scan, but no ZKHs (a flat hull has no inside).
//!
//! **ZKHs.** [`crate::hull_scan::zkh::analyse`], which classifies from the
//! scan's [`Classification`] (so the GPU scan feeds it directly) and finds
//! incident faces only at corners outside the open row intervals. Faces
//! visible from or coplanar with a 0-cell of the ZKH are incident (§4.2.3).
//! The other implementation, [`crate::polyhedron::background_components`]
//! (used by `chisel hull`), rescans every voxel against every face on the
//! CPU and builds each ZKH as a [`DigitalObject`] for the modification
//! steps, which a scan does not need.
//!
//! **Convexity.** Per row, `digital` = object voxels / voxels of the closed
//! hull (inside + on; 1 exactly when S has no ZKH) and `volume` = object
//! voxels / Euclidean hull volume in voxels (above 1 for small objects:
//! the hull passes through the outer voxel centres).
//!
//! **Report.** The selection, backend, adapter and GPU arithmetic, hull
//! options; counts of structures, scanned, degenerate and skipped ones;
//! ZKH totals by class; `rows` (one per scanned structure: id, label,
//! 6-components, object voxels / facets / box, candidates, hull faces /
//! vertices / edges / integers (eq. 8.2 and compact) / volume / area,
//! scan box and inside / on / outside counts, convexity, ZKHs by class
//! with count and voxels); `timings_s` per stage (read, label, adapter,
//! then object, candidates, hull, scan, zkh summed over structures, and
//! total). Reports of the two backends differ only in `backend`,
//! `adapter`, `arithmetic` and `timings_s`.

use std::path::{Path, PathBuf};
use std::time::Instant;

use serde::Serialize;

use crate::foundation::report::Report;
use crate::gpu::{Backend, Gpu};
use crate::hull::{ConvexHull, HullOptions};
use crate::hull_scan::zkh::{ZkhClass, analyse};
use crate::hull_scan::{self, Classification, VoxelBox};
use crate::volume::Volume;
use crate::volume::analysis::label_6_connected;
use crate::voxel::{CandidateKind, DigitalObject, Frame, ObjectFigures};
use crate::{Error, Result};

/// What a scan looks for and how it builds hulls.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ScanOptions {
    /// `Some(T)`: the 6-connected components of the samples `≥ T`;
    /// `None`: the non-zero labels (all voxels of each label).
    pub level: Option<f64>,
    /// Structures with fewer voxels are skipped (and counted).
    pub min_voxels: u64,
    /// Hull vertex candidates (§4.1.2–4.1.3).
    pub candidates: CandidateKind,
    /// Coplanar policy and insertion order (§4.1.6, §4.1.8).
    pub hull: HullOptions,
}

impl Default for ScanOptions {
    /// Labels, every structure, the defaults of `chisel scan`.
    fn default() -> Self {
        ScanOptions {
            level: None,
            min_voxels: 1,
            candidates: CandidateKind::Local26,
            hull: HullOptions::default(),
        }
    }
}

/// Most distinct non-zero values a label scan accepts.
pub const MAX_SCAN_LABELS: usize = 65_536;
/// More labels than this: probably intensities, not labels (`chisel
/// stats` lists at most as many); the command line warns.
pub const MANY_LABELS: usize = crate::volume::analysis::MAX_LABELS;

/// How a scan ran before its structures: the volume's path as the caller
/// names it, the seconds spent reading it, the GPU (`None`: the CPU
/// mirror) and the seconds spent opening it.
#[derive(Debug, Clone, Copy)]
pub struct ScanInput<'a> {
    pub path: &'a Path,
    pub read_s: f64,
    pub gpu: Option<&'a Gpu>,
    pub adapter_s: Option<f64>,
}

/// Scans every structure of `volume` ([module docs](self)); `progress`
/// sees `(done, total)` after each structure and stops the scan by
/// returning an error (which the scan returns).
///
/// Errors: nothing to scan ([`Error::InvalidData`]), a fractional label
/// ([`Error::InvalidData`]), more than [`MAX_SCAN_LABELS`] labels
/// ([`Error::Limit`]), GPU errors; each names the volume (and the
/// structure).
pub fn scan(
    volume: &Volume,
    input: ScanInput<'_>,
    options: &ScanOptions,
    progress: &mut dyn FnMut(usize, usize) -> Result<()>,
) -> Result<ScanReport> {
    let name = input.path.display().to_string();
    let t_total = Instant::now();
    let t = Instant::now();
    let (ids, structures) = match options.level {
        Some(threshold) => components(volume, threshold),
        None => labels(volume),
    }
    .map_err(|e| e.within(&name))?;
    if structures.is_empty() {
        return Err(Error::InvalidData {
            what: name,
            at: crate::Position::Whole,
            problem: match options.level {
                Some(t) => format!("no sample ≥ {t}: nothing to scan"),
                None => "no non-zero label: nothing to scan".to_string(),
            },
        });
    }
    let label_s = t.elapsed().as_secs_f64();
    let backend = input.gpu.map_or(Backend::Cpu, Backend::Gpu);
    let frame = Frame::of(volume);
    let (kept, skipped): (Vec<&Structure>, Vec<&Structure>) = structures
        .iter()
        .partition(|s| s.voxels >= options.min_voxels);
    let mut times = StageTimes::default();
    let mut totals = ZkhTotals::default();
    let mut n_degenerate = 0u64;
    let mut rows = Vec::with_capacity(kept.len());
    let n_kept = kept.len();
    for s in kept {
        let row = scan_structure(s, &ids, volume.dims, frame, options, backend, &mut times)
            .map_err(|e| e.within(format!("{name}: structure {}", s.id)))?;
        totals.merge(&row.zkh);
        n_degenerate += u64::from(row.degenerate);
        rows.push(row.value);
        progress(rows.len(), n_kept)?;
    }
    Ok(ScanReport {
        command: "scan",
        volume: input.path.to_path_buf(),
        dims: volume.dims,
        spacing: volume.spacing,
        selection: match options.level {
            Some(t) => ScanSelection::Level(t),
            None => ScanSelection::Labels(true),
        },
        min_voxels: options.min_voxels,
        backend: backend.name(),
        adapter: input.gpu.map(|g| g.describe()),
        arithmetic: input
            .gpu
            .map(|g| format!("{:?}", hull_scan::gpu::Arithmetic::of(g)).to_lowercase()),
        candidates: options.candidates,
        hull_options: options.hull,
        structures: structures.len(),
        scanned: rows.len(),
        degenerate: n_degenerate,
        skipped: Skipped {
            count: skipped.len(),
            voxels: skipped.iter().map(|s| s.voxels).sum(),
        },
        zkh: totals.figures(),
        rows,
        timings_s: ScanTimings {
            read: input.read_s,
            label: label_s,
            adapter: input.adapter_s,
            object: times.object,
            candidates: times.candidates,
            hull: times.hull,
            scan: times.scan,
            zkh: times.zkh,
            total: input.read_s + input.adapter_s.unwrap_or(0.0) + t_total.elapsed().as_secs_f64(),
        },
    })
}

/// The report of a scan (`chisel scan --json`).
#[derive(Debug, Serialize)]
pub struct ScanReport {
    pub command: &'static str,
    pub volume: PathBuf,
    pub dims: [usize; 3],
    pub spacing: [f64; 3],
    pub selection: ScanSelection,
    pub min_voxels: u64,
    pub backend: &'static str,
    pub adapter: Option<String>,
    /// `int64` or `i32x2`: how the GPU does the exact arithmetic.
    pub arithmetic: Option<String>,
    pub candidates: CandidateKind,
    pub hull_options: HullOptions,
    pub structures: usize,
    pub scanned: usize,
    pub degenerate: u64,
    pub skipped: Skipped,
    pub zkh: ZkhFigures,
    pub rows: Vec<ScanRow>,
    pub timings_s: ScanTimings,
}

impl Report for ScanReport {
    const SCHEMA: &'static str = "chisel.scan/1";
}

/// `{"level": T}` or `{"labels": true}`.
#[derive(Debug, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum ScanSelection {
    Level(f64),
    Labels(bool),
}

#[derive(Debug, Serialize)]
pub struct Skipped {
    pub count: usize,
    pub voxels: u64,
}

/// Seconds per stage (structures summed).
#[derive(Debug, Serialize)]
pub struct ScanTimings {
    pub read: f64,
    pub label: f64,
    pub adapter: Option<f64>,
    pub object: f64,
    pub candidates: f64,
    pub hull: f64,
    pub scan: f64,
    pub zkh: f64,
    pub total: f64,
}

/// One structure's row.
#[derive(Debug, Serialize)]
pub struct ScanRow {
    pub id: u32,
    pub label: Option<f64>,
    pub components: usize,
    pub object: ObjectFigures,
    pub candidates: usize,
    /// `collinear`: no polygon, no polyhedron (the row ends here).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub degenerate: Option<&'static str>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub hull: Option<HullFigures>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub scan: Option<ScanFigures>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub convexity: Option<Convexity>,
    /// Absent for a degenerate row, `null` for a flat hull (no inside).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub zkh: Option<Option<ZkhFigures>>,
}

/// The hull figures a scan row keeps.
#[derive(Debug, Serialize)]
pub struct HullFigures {
    pub faces: usize,
    pub vertices: usize,
    pub edges: usize,
    integers_eq_8_2: usize,
    pub integers_compact: usize,
    pub volume_voxels: f64,
    pub area_voxels: f64,
    pub volume_world: f64,
    pub area_world: f64,
    pub planar: bool,
}

/// Voxels of the hull's box inside, on and outside the hull.
#[derive(Debug, Serialize)]
pub struct ScanFigures {
    #[serde(rename = "box")]
    pub bbox: VoxelBox,
    pub inside: u64,
    pub on: u64,
    pub outside: u64,
}

/// The object's share of its hull: by voxels and by volume.
#[derive(Debug, Serialize)]
pub struct Convexity {
    pub hull_voxels: u64,
    pub digital: f64,
    pub volume: Option<f64>,
}

/// ZKH totals per class.
#[derive(Debug, Serialize)]
pub struct ZkhFigures {
    pub count: u64,
    pub voxels: u64,
    pub largest: u64,
    pub cavities: ClassFigures,
    pub concavities: ClassFigures,
    pub tunnels: ClassFigures,
    pub branched_tunnels: ClassFigures,
}

#[derive(Debug, Serialize)]
pub struct ClassFigures {
    pub count: u64,
    pub voxels: u64,
}

/// One structure: its id in the per-voxel id map, the label value it
/// stands for (`--labels`), its voxels and inclusive voxel bounding box.
#[derive(Debug, Clone)]
struct Structure {
    id: u32,
    label: Option<f64>,
    voxels: u64,
    lo: [usize; 3],
    hi: [usize; 3],
}

/// Seconds per stage, summed over structures.
#[derive(Debug, Default)]
struct StageTimes {
    object: f64,
    candidates: f64,
    hull: f64,
    scan: f64,
    zkh: f64,
}

/// Per-class ZKH totals of one structure or of the whole scan.
#[derive(Debug, Default, Clone, Copy)]
struct ZkhTotals {
    /// `[cavity, concavity, tunnel, branched tunnel]` counts.
    count: [u64; 4],
    /// Their voxels.
    voxels: [u64; 4],
    largest: u64,
}

impl ZkhTotals {
    fn add(&mut self, class: ZkhClass, size: u64) {
        let k = match class {
            ZkhClass::Cavity => 0,
            ZkhClass::Concavity => 1,
            ZkhClass::UnbranchedTunnel => 2,
            ZkhClass::BranchedTunnel => 3,
        };
        self.count[k] += 1;
        self.voxels[k] += size;
        self.largest = self.largest.max(size);
    }

    fn merge(&mut self, o: &ZkhTotals) {
        for k in 0..4 {
            self.count[k] += o.count[k];
            self.voxels[k] += o.voxels[k];
        }
        self.largest = self.largest.max(o.largest);
    }

    fn figures(&self) -> ZkhFigures {
        let class = |k: usize| ClassFigures {
            count: self.count[k],
            voxels: self.voxels[k],
        };
        ZkhFigures {
            count: self.count.iter().sum(),
            voxels: self.voxels.iter().sum(),
            largest: self.largest,
            cavities: class(0),
            concavities: class(1),
            tunnels: class(2),
            branched_tunnels: class(3),
        }
    }
}

/// The 6-connected components of the samples `≥ threshold`: the per-voxel
/// component number (0 = not selected) and one [`Structure`] per component
/// in file order.
fn components(volume: &Volume, threshold: f64) -> Result<(Vec<u32>, Vec<Structure>)> {
    let lab = label_6_connected(volume.dims, |i| volume.data.get_f64(i) >= threshold)?;
    let structures = boxes(&lab.labels, volume.dims, lab.n_components())
        .into_iter()
        .enumerate()
        .map(|(c, (lo, hi, voxels))| Structure {
            id: c as u32 + 1,
            label: None,
            voxels,
            lo,
            hi,
        })
        .collect();
    Ok((lab.labels, structures))
}

/// The distinct non-zero, non-NaN sample values in ascending order: the
/// per-voxel index into them (1-based; 0 = background) and one
/// [`Structure`] per value.
///
/// Errors: [`Error::InvalidData`] for a fractional value,
/// [`Error::Limit`] past [`MAX_SCAN_LABELS`] values.
fn labels(volume: &Volume) -> Result<(Vec<u32>, Vec<Structure>)> {
    let n = volume.data.len();
    let is_label = |v: f64| v != 0.0 && !v.is_nan();
    let mut values: Vec<f64> = Vec::new();
    let mut last = f64::NAN;
    for i in 0..n {
        let v = volume.data.get_f64(i);
        if is_label(v) && v != last {
            last = v;
            if let Err(at) = values.binary_search_by(|x| x.total_cmp(&v)) {
                if v.fract() != 0.0 {
                    return Err(Error::data(
                        "label volume",
                        "sample",
                        i,
                        format!(
                            "--labels takes whole-number labels, found the value {v}: an \
                             intensity volume? (use --level)"
                        ),
                    ));
                }
                if values.len() == MAX_SCAN_LABELS {
                    return Err(Error::limit(
                        "distinct non-zero values of a label volume (use --level for \
                         an intensity volume)",
                        MAX_SCAN_LABELS + 1,
                        MAX_SCAN_LABELS,
                    ));
                }
                values.insert(at, v);
            }
        }
    }
    let mut ids = vec![0u32; n];
    let (mut last, mut last_id) = (f64::NAN, 0u32);
    for (i, id) in ids.iter_mut().enumerate() {
        let v = volume.data.get_f64(i);
        if !is_label(v) {
            continue;
        }
        if v != last {
            last = v;
            last_id = values
                .binary_search_by(|x| x.total_cmp(&v))
                .map_or(0, |k| k as u32 + 1);
        }
        *id = last_id;
    }
    let structures = boxes(&ids, volume.dims, values.len())
        .into_iter()
        .zip(values)
        .enumerate()
        .map(|(k, ((lo, hi, voxels), value))| Structure {
            id: k as u32 + 1,
            label: Some(value),
            voxels,
            lo,
            hi,
        })
        .collect();
    Ok((ids, structures))
}

/// Per id `1..=n`: inclusive voxel bounding box and voxel count.
fn boxes(ids: &[u32], dims: [usize; 3], n: usize) -> Vec<([usize; 3], [usize; 3], u64)> {
    let mut out = vec![([usize::MAX; 3], [0usize; 3], 0u64); n];
    let [nx, ny, _] = dims;
    for (i, &id) in ids.iter().enumerate() {
        if id == 0 {
            continue;
        }
        let p = [i % nx, (i / nx) % ny, i / (nx * ny)];
        let (lo, hi, count) = &mut out[id as usize - 1];
        for a in 0..3 {
            lo[a] = lo[a].min(p[a]);
            hi[a] = hi[a].max(p[a]);
        }
        *count += 1;
    }
    out
}

/// One report row and what the totals need.
struct Row {
    value: ScanRow,
    zkh: ZkhTotals,
    degenerate: bool,
}

/// Flags `ids == id` over the box `lo ..= hi` (x fastest).
fn flags(ids: &[u32], dims: [usize; 3], id: u32, lo: [usize; 3], hi: [usize; 3]) -> Vec<bool> {
    let [nx, ny, _] = dims;
    let mut out = Vec::with_capacity((0..3).map(|a| hi[a] - lo[a] + 1).product());
    for z in lo[2]..=hi[2] {
        for y in lo[1]..=hi[1] {
            let row = nx * (y + ny * z);
            out.extend(ids[row + lo[0]..=row + hi[0]].iter().map(|&v| v == id));
        }
    }
    out
}

/// Whether all `points` lie on one line (no polygon, no polyhedron).
fn collinear(points: &[[i64; 3]]) -> bool {
    let sub = |a: [i64; 3], b: [i64; 3]| [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
    let Some(&a) = points.first() else {
        return true;
    };
    let Some(&b) = points.iter().find(|&&p| p != a) else {
        return true;
    };
    let u = sub(b, a);
    points.iter().all(|&p| {
        let v = sub(p, a);
        u[1] * v[2] == u[2] * v[1] && u[2] * v[0] == u[0] * v[2] && u[0] * v[1] == u[1] * v[0]
    })
}

/// Hull, inside-hull scan and ZKH summary of one structure.
fn scan_structure(
    s: &Structure,
    ids: &[u32],
    dims: [usize; 3],
    frame: Frame,
    options: &ScanOptions,
    backend: Backend<'_>,
    times: &mut StageTimes,
) -> Result<Row> {
    let t = Instant::now();
    let lo = s.lo.map(|c| c as i64);
    let box_dims: [usize; 3] = std::array::from_fn(|a| s.hi[a] - s.lo[a] + 1);
    let object_flags = flags(ids, dims, s.id, s.lo, s.hi);
    let object = DigitalObject::from_mask(box_dims, &object_flags, frame)?.shifted(lo);
    let n_components = if s.label.is_some() {
        label_6_connected(box_dims, |i| object_flags[i])?.n_components()
    } else {
        1
    };
    times.object += t.elapsed().as_secs_f64();

    let t = Instant::now();
    let candidates = object.candidates(options.candidates);
    let mut row = ScanRow {
        id: s.id,
        label: s.label,
        components: n_components,
        object: object.figures(),
        candidates: candidates.len(),
        degenerate: None,
        hull: None,
        scan: None,
        convexity: None,
        zkh: None,
    };
    times.candidates += t.elapsed().as_secs_f64();
    if collinear(&candidates) {
        row.degenerate = Some("collinear");
        return Ok(Row {
            value: row,
            zkh: ZkhTotals::default(),
            degenerate: true,
        });
    }

    let t = Instant::now();
    let hull = ConvexHull::build(&candidates, options.hull)?;
    let summary = hull.summary(&frame);
    row.hull = Some(HullFigures {
        faces: summary.faces,
        vertices: summary.vertices,
        edges: summary.edges,
        integers_eq_8_2: summary.integers_eq_8_2,
        integers_compact: summary.integers_compact,
        volume_voxels: summary.volume_voxels,
        area_voxels: summary.area_voxels,
        volume_world: summary.volume_world,
        area_world: summary.area_world,
        planar: summary.planar,
    });
    let faces: Vec<hull_scan::HalfSpace> = hull.half_spaces().into_iter().map(Into::into).collect();
    times.hull += t.elapsed().as_secs_f64();

    let t = Instant::now();
    let (hlo, hhi) = hull.voxel_bbox();
    let bbox = VoxelBox {
        origin: hlo,
        dims: std::array::from_fn(|a| (hhi[a] - hlo[a] + 1).max(0) as usize),
    };
    let classification: Classification = hull.row_spans(&bbox, backend)?.to_classification()?;
    let [outside, on, inside] = classification.counts();
    row.scan = Some(ScanFigures {
        bbox,
        inside,
        on,
        outside,
    });
    let closed = inside + on;
    row.convexity = Some(Convexity {
        hull_voxels: closed,
        digital: object.n_voxels() as f64 / closed as f64,
        volume: (summary.volume_voxels > 0.0)
            .then(|| object.n_voxels() as f64 / summary.volume_voxels),
    });
    times.scan += t.elapsed().as_secs_f64();

    let mut zkh = ZkhTotals::default();
    if !hull.is_planar() {
        let t = Instant::now();
        // Extreme voxels are hull vertices (or own its corner vertices), so
        // the hull's voxel box is the structure's box.
        if hlo != lo || hhi != s.hi.map(|c| c as i64) {
            return Err(Error::Internal(format!(
                "hull box {hlo:?}..={hhi:?} differs from the structure box {:?}..={:?}",
                s.lo, s.hi
            )));
        }
        let mut adjacency = vec![Vec::new(); faces.len()];
        for e in hull.cell_list().edges {
            adjacency[e.left as usize].push(e.right as usize);
            adjacency[e.right as usize].push(e.left as usize);
        }
        let analysis = analyse(&object_flags, &classification, &faces, &adjacency)?;
        for c in &analysis.components {
            zkh.add(c.class, c.size);
        }
        times.zkh += t.elapsed().as_secs_f64();
    }
    row.zkh = Some((!hull.is_planar()).then(|| zkh.figures()));
    Ok(Row {
        value: row,
        zkh,
        degenerate: false,
    })
}
