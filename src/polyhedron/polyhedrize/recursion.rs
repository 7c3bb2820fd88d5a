//! The recursion with swapped roles: takes a digital object and returns the
//! tree of shells ([`polyhedrize()`]), making each component's child
//! shell(s) and merging overlapping siblings level by level.

use crate::foundation::alloc::filled;
use std::collections::VecDeque;

use crate::gpu::Backend;
use crate::hull_scan::VoxelBox;
use crate::polyhedron::balls::maximal_balls;
use crate::polyhedron::{ZkhClass, background_components, faces_to_press};
use crate::volume::analysis::label_6_connected;
use crate::voxel::{DigitalObject, Frame};

use super::pairs::separated;
use super::{
    PolyhedrizeOptions, Polyhedron, Role, Shell, ShellGeometry, ShellKind, ZkhReport,
    try_local_index, voxel_at,
};

/// Polyhedrizes `object` ([module docs](super)). `progress` is called with the
/// number of shells made so far.
///
/// Errors: [`crate::Error::InvalidParameter`] for corner candidates, a flat
/// object (no inside) and hull-scan range limits.
pub fn polyhedrize(
    object: &DigitalObject,
    options: PolyhedrizeOptions,
    backend: Backend<'_>,
    progress: &dyn Fn(usize),
) -> crate::Result<(Polyhedron, Vec<ZkhReport>)> {
    if options.candidates.at_corners() {
        return Err(crate::Error::param(
            "vertices",
            "corners",
            "polyhedrize puts shell vertices at voxel centres; corner candidates are for hulls only",
        ));
    }
    let root = ShellGeometry::of_points(&object.candidates(options.candidates), options.hull)?;
    let mut shells = vec![Shell {
        geometry: root,
        parent: None,
        depth: 0,
        role: Role::Object,
        kind: ShellKind::Hull,
        voxels: object.n_voxels(),
    }];
    let mut queue: VecDeque<u32> = VecDeque::new();
    let mut zkh_reports = Vec::new();
    // Depth 1: the ZKHs with their classes; a flat object (one slice: the
    // 2-D analogue of ch. 9) has no ZKH classes and recurses like any shell.
    let (zkhs, root_hull) = match &shells[0].geometry {
        ShellGeometry::Polytope(h) if !h.is_planar() => {
            (background_components(object, h)?, Some(h.clone()))
        }
        _ => {
            queue.push_back(0);
            (Vec::new(), None)
        }
    };
    let mut merges = 0usize;
    let mut children = Vec::new();
    for z in zkhs {
        let (pressed, mut rim) = match &root_hull {
            Some(h) if options.press_in && z.class != ZkhClass::Cavity => {
                let pressed = faces_to_press(h, &z);
                let rim: Vec<[i64; 3]> = pressed
                    .iter()
                    .flat_map(|&f| &h.faces()[f as usize].vertices)
                    .map(|&v| h.vertices()[v as usize])
                    .collect();
                (pressed, rim)
            }
            _ => (Vec::new(), Vec::new()),
        };
        rim.sort_unstable();
        rim.dedup();
        let kind = ShellKind::Zkh(z.class);
        let (made, genus) = component_children(z.object, kind, 1, options, rim)?;
        zkh_reports.push(ZkhReport {
            class: z.class,
            voxels: z.voxels,
            genus,
            shells: made.len(),
            pressed_faces: pressed.len(),
        });
        children.extend(made);
    }
    if options.disjoint_siblings {
        merges += merge_overlapping(&mut children, options, object.frame())?;
    }
    push_children(&mut shells, &mut queue, 0, children);
    progress(shells.len());
    // Deeper levels: components of the other role inside each shell.
    while let Some(i) = queue.pop_front() {
        let shell = &shells[i as usize];
        let other = shell.role.swapped();
        let (bbox, closed) = shell.geometry.closed_voxels(backend)?;
        let mask: Vec<bool> = closed
            .iter()
            .enumerate()
            .map(|(k, &c)| c && role_of(object, voxel_at(&bbox, k)) == other)
            .collect();
        if !mask.iter().any(|&m| m) {
            continue;
        }
        let labels = label_6_connected(bbox.dims, |k| mask[k])?;
        // Each component's voxels, then a mask over its own box (one pass
        // over the shell's box, not one per component).
        let mut members: Vec<Vec<usize>> = vec![Vec::new(); labels.n_components()];
        for (k, &l) in labels.labels.iter().enumerate() {
            if l > 0 {
                members[l as usize - 1].push(k);
            }
        }
        let depth = shells[i as usize].depth + 1;
        let mut children = Vec::new();
        for voxels in members {
            let at: Vec<[i64; 3]> = voxels.iter().map(|&k| voxel_at(&bbox, k)).collect();
            let set = object_of(&at, object.frame())?;
            let made = component_children(set, ShellKind::Component, depth, options, Vec::new())?;
            children.extend(made.0);
        }
        if options.disjoint_siblings {
            merges += merge_overlapping(&mut children, options, object.frame())?;
        }
        push_children(&mut shells, &mut queue, i, children);
        progress(shells.len());
    }
    Ok((
        Polyhedron {
            shells,
            frame: object.frame(),
            merges,
        },
        zkh_reports,
    ))
}

/// A child shell before it joins the tree.
struct Child {
    /// Its voxel set; `None` for a maximal ball (never merged).
    set: Option<DigitalObject>,
    /// Vertices of pressed faces of the parent among its hull's points
    /// (combinatorial coordinates; empty unless pressed in).
    rim: Vec<[i64; 3]>,
    kind: ShellKind,
    geometry: ShellGeometry,
    voxels: u64,
}

/// The child shell(s) of component `set` at `depth`: the hull of its
/// voxels and the pressed face vertices `rim`, or its maximal balls when
/// its genus is > 0 and balls are on (balls are not pressed in). Also
/// returns the genus when it was needed (balls on, or a ZKH of the root).
fn component_children(
    set: DigitalObject,
    kind: ShellKind,
    depth: u32,
    options: PolyhedrizeOptions,
    rim: Vec<[i64; 3]>,
) -> crate::Result<(Vec<Child>, Option<i64>)> {
    let genus = if options.balls || depth == 1 {
        Some(set.topology()?.genus)
    } else {
        None
    };
    if options.balls && genus.is_some_and(|g| g > 0) {
        let (lo, hi) = set.voxel_bbox();
        let dims: [usize; 3] = std::array::from_fn(|a| (hi[a] - lo[a] + 1) as usize);
        let bbox = VoxelBox { origin: lo, dims };
        let mask: Vec<bool> = (0..dims.iter().product())
            .map(|k| set.contains(voxel_at(&bbox, k)))
            .collect();
        let mut out = Vec::new();
        for ball in maximal_balls(dims, &mask) {
            let centres: Vec<[i64; 3]> = ball
                .voxels
                .iter()
                .map(|&k| crate::voxel::voxel_centre(voxel_at(&bbox, k)))
                .collect();
            out.push(Child {
                set: None,
                rim: Vec::new(),
                kind: ShellKind::Ball(ball.r2),
                geometry: ShellGeometry::of_points(&centres, options.hull)?,
                voxels: ball.voxels.len() as u64,
            });
        }
        Ok((out, genus))
    } else {
        let mut points = set.candidates(options.candidates);
        points.extend_from_slice(&rim);
        let geometry = ShellGeometry::of_points(&points, options.hull)?;
        let voxels = set.n_voxels();
        Ok((
            vec![Child {
                set: Some(set),
                rim,
                kind,
                geometry,
                voxels,
            }],
            genus,
        ))
    }
}

/// Merges sibling polyhedra whose interiors overlap into the hull of their
/// union until all are pairwise interior-disjoint (balls stay apart).
/// Lossless and terminating as any child: the union hull still lies in the
/// parent and misses its vertices. Returns the number of merges.
fn merge_overlapping(
    children: &mut Vec<Child>,
    options: PolyhedrizeOptions,
    frame: Frame,
) -> crate::Result<usize> {
    let solid = |c: &Child| c.set.is_some() && c.geometry.dimension() == 3;
    let mut merges = 0;
    // Each child in turn is made disjoint from all others, rescanning after
    // every merge into it; a child that grows later rescans all, so at the
    // end every pair is disjoint.
    let mut i = 0;
    while i < children.len() {
        let mut j = 0;
        while j < children.len() {
            let overlap = j != i
                && solid(&children[i])
                && solid(&children[j])
                && match (
                    children[i].geometry.polytope(),
                    children[j].geometry.polytope(),
                ) {
                    (Some(a), Some(b)) => !separated(a, b),
                    _ => false,
                };
            if !overlap {
                j += 1;
                continue;
            }
            let b = children.remove(j);
            if j < i {
                i -= 1;
            }
            let a = &children[i];
            let mut voxels: Vec<[i64; 3]> = Vec::with_capacity((a.voxels + b.voxels) as usize);
            for set in [&a.set, &b.set].into_iter().flatten() {
                voxels.extend(set.voxels());
            }
            let set = object_of(&voxels, frame)?;
            let kind = if a.kind == b.kind {
                a.kind
            } else {
                ShellKind::Component
            };
            let mut rim = [a.rim.as_slice(), b.rim.as_slice()].concat();
            rim.sort_unstable();
            rim.dedup();
            let mut points = set.candidates(options.candidates);
            points.extend_from_slice(&rim);
            children[i] = Child {
                geometry: ShellGeometry::of_points(&points, options.hull)?,
                voxels: set.n_voxels(),
                kind,
                set: Some(set),
                rim,
            };
            merges += 1;
            j = 0;
        }
        i += 1;
    }
    Ok(merges)
}

/// Appends `children` under `parent` and queues them.
fn push_children(
    shells: &mut Vec<Shell>,
    queue: &mut VecDeque<u32>,
    parent: u32,
    children: Vec<Child>,
) {
    let (role, depth) = {
        let p = &shells[parent as usize];
        (p.role.swapped(), p.depth + 1)
    };
    for c in children {
        queue.push_back(shells.len() as u32);
        shells.push(Shell {
            geometry: c.geometry,
            parent: Some(parent),
            depth,
            role,
            kind: c.kind,
            voxels: c.voxels,
        });
    }
}

/// The voxels as an object of their own box.
fn object_of(voxels: &[[i64; 3]], frame: Frame) -> crate::Result<DigitalObject> {
    let mut lo = [i64::MAX; 3];
    let mut hi = [i64::MIN; 3];
    for v in voxels {
        for a in 0..3 {
            lo[a] = lo[a].min(v[a]);
            hi[a] = hi[a].max(v[a]);
        }
    }
    let sub = VoxelBox {
        origin: lo,
        dims: std::array::from_fn(|a| (hi[a] - lo[a] + 1).max(0) as usize),
    };
    let mut mask = filled("polyhedrize: a sub-box mask", sub.n_voxels()?, false)?;
    for &v in voxels {
        if let Some(i) = try_local_index(&sub, v) {
            mask[i] = true;
        }
    }
    Ok(DigitalObject::from_mask(sub.dims, &mask, frame)?.shifted(lo))
}

fn role_of(object: &DigitalObject, v: [i64; 3]) -> Role {
    if object.contains(v) {
        Role::Object
    } else {
        Role::Background
    }
}
