//! View directions, the auto-facing rule and orthographic view cameras.
//!
//! Conventions (documented for users in [`super`]): +y is up; `front` looks
//! from +z toward −z; `right` = up × front (+x). [`Facing::Auto`] keeps +y up
//! but turns the frame about it so that `front` faces the bulging side of an
//! open surface such as a face scan (see [`open_surface_facing`]).

use glam::camera::rh::{proj::directx, view::look_at_mat4};
use glam::{DVec3, Mat4, Vec3};

use super::{Facing, View, undirected_edges};
use crate::TriMesh;

/// Ortho half-extent over the bounding-sphere radius (the framing margin).
const MARGIN: f32 = 1.08;

/// World axes of the views. `front` points from the object toward the
/// camera of [`View::Front`]; `up` is image-up in the four side views.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Frame {
    pub up: Vec3,
    pub front: Vec3,
    pub right: Vec3,
}

impl Frame {
    /// The fixed axes: up +y, front +z, right +x.
    pub fn axes() -> Self {
        Frame {
            up: Vec3::Y,
            front: Vec3::Z,
            right: Vec3::X,
        }
    }

    /// `up` and `front` made orthonormal (front loses its part along up);
    /// the fixed axes when either is zero or they are parallel.
    pub fn anatomical(up: Vec3, front: Vec3) -> Self {
        let up = up.normalize_or_zero();
        let front = (front - front.dot(up) * up).normalize_or_zero();
        if up == Vec3::ZERO || front == Vec3::ZERO {
            return Frame::axes();
        }
        Frame {
            up,
            front,
            right: up.cross(front),
        }
    }

    /// The frame for `meshes` under `facing`; [`Facing::Auto`] asks the
    /// first mesh (the "before" of a panel row) for its facing.
    pub fn for_meshes(meshes: &[&TriMesh], facing: Facing) -> Self {
        match facing {
            Facing::Axes => Frame::axes(),
            Facing::Anatomical { up, front } => Frame::anatomical(up, front),
            Facing::Auto => {
                meshes
                    .first()
                    .and_then(|m| open_surface_facing(m))
                    .map_or(Frame::axes(), |front| Frame {
                        up: Vec3::Y,
                        front,
                        right: Vec3::Y.cross(front),
                    })
            }
        }
    }

    /// `(to_eye, image_up)` of `view`: unit world direction from the object
    /// toward the camera, and the world direction that is up in the image.
    pub fn view_axes(&self, view: View) -> (Vec3, Vec3) {
        match view {
            View::Front => (self.front, self.up),
            View::Back => (-self.front, self.up),
            View::Right => (self.right, self.up),
            View::Left => (-self.right, self.up),
            View::Top => (self.up, -self.front),
            View::Bottom => (-self.up, self.front),
            View::Iso => ((self.front + self.right + self.up).normalize(), self.up),
        }
    }
}

/// The horizontal (⊥ +y) direction an open surface faces, or `None` when
/// the mesh is closed or nearly so, or faces straight up or down.
///
/// The vector area V = ½ Σ (b − a) × (c − a) of a closed surface is zero;
/// for a cap (a face scan, a bowl) it points along the cap's axis, its sign
/// set by the winding. The sign is fixed without trusting the winding: the
/// cap bulges toward the side where its area centroid lies beyond its
/// boundary loop's centroid. Used only when |V| ≥ ¼ of the total area.
pub(crate) fn open_surface_facing(mesh: &TriMesh) -> Option<Vec3> {
    let p = |i: u32| mesh.positions[i as usize].as_dvec3();
    let mut vector_area = DVec3::ZERO;
    let mut area = 0.0;
    let mut weighted_centroid = DVec3::ZERO;
    for &[a, b, c] in &mesh.triangles {
        let (a, b, c) = (p(a), p(b), p(c));
        let cross = (b - a).cross(c - a);
        let twice = cross.length();
        vector_area += 0.5 * cross;
        area += 0.5 * twice;
        weighted_centroid += (a + b + c) / 3.0 * (0.5 * twice);
    }
    if area.is_nan() || area <= 0.0 || vector_area.length() < 0.25 * area {
        return None;
    }
    let edges = undirected_edges(&mesh.triangles);
    let mut boundary_len = 0.0;
    let mut boundary_centroid = DVec3::ZERO;
    let mut k = 0;
    while k < edges.len() {
        let run = edges[k..].iter().take_while(|e| **e == edges[k]).count();
        if run == 1 {
            let (a, b) = (p(edges[k][0]), p(edges[k][1]));
            let len = (b - a).length();
            boundary_len += len;
            boundary_centroid += 0.5 * (a + b) * len;
        }
        k += run;
    }
    if boundary_len.is_nan() || boundary_len <= 0.0 {
        return None;
    }
    let bulge = weighted_centroid / area - boundary_centroid / boundary_len;
    let mut d = vector_area.normalize();
    if d.dot(bulge) < 0.0 {
        d = -d;
    }
    let horizontal = DVec3::new(d.x, 0.0, d.z);
    (horizontal.length() >= 0.3).then(|| horizontal.normalize().as_vec3())
}

/// Bounding sphere of the vertices the triangles use: centre at the box
/// centre, radius the largest distance to it (at least a tiny positive
/// value, so a degenerate mesh still frames). `None` without triangles.
pub(crate) fn bounding_sphere(meshes: &[&TriMesh]) -> Option<(Vec3, f32)> {
    let used = || {
        meshes.iter().flat_map(|m| {
            m.triangles
                .iter()
                .flatten()
                .map(|&i| m.positions[i as usize])
        })
    };
    let first = used().next()?;
    let (lo, hi) = used().fold((first, first), |(lo, hi), q| (lo.min(q), hi.max(q)));
    let center = 0.5 * (lo + hi);
    let radius = used().map(|q| q.distance(center)).fold(0.0f32, f32::max);
    let floor = f32::EPSILON * center.abs().max_element().max(1.0);
    Some((center, radius.max(floor)))
}

/// One view's camera, ready for the shader's `Camera` uniform.
#[derive(Debug, Clone, Copy)]
pub(crate) struct ViewCamera {
    /// World → clip, orthographic, depth in [0, 1].
    pub view_proj: Mat4,
    /// Unit world vector toward the camera.
    pub to_eye: Vec3,
    /// Unit world vector toward the key light (above-left of the camera).
    pub to_light: Vec3,
    /// NDC depth by which wireframe lines are pulled forward (≈ 3 pixels).
    pub depth_pull: f32,
}

/// The orthographic camera of `view` framing the sphere `(center, radius)`
/// in a `width`×`height` viewport: the sphere, plus a margin, fits the
/// shorter side; the eye sits 2 radii out, depth spans 0.5–3.5 radii.
pub(crate) fn view_camera(
    frame: &Frame,
    (center, radius): (Vec3, f32),
    view: View,
    width: u32,
    height: u32,
) -> ViewCamera {
    let (to_eye, image_up) = frame.view_axes(view);
    let aspect = width as f32 / height as f32;
    let (half_w, half_h) = if aspect >= 1.0 {
        (MARGIN * radius * aspect, MARGIN * radius)
    } else {
        (MARGIN * radius, MARGIN * radius / aspect)
    };
    let eye = center + 2.0 * radius * to_eye;
    let view_m = look_at_mat4(eye, center, image_up);
    // wgpu NDC: y up, depth in [0, 1] (glam's `directx` convention).
    let proj = directx::orthographic(-half_w, half_w, -half_h, half_h, 0.5 * radius, 3.5 * radius);
    let image_right = (-to_eye).cross(image_up);
    let to_light = (to_eye + 0.45 * image_up - 0.3 * image_right).normalize();
    let pixel = 2.0 * half_h / height as f32;
    ViewCamera {
        view_proj: proj * view_m,
        to_eye,
        to_light,
        depth_pull: pixel / radius,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A spherical cap of half-angle 70° around `axis` (unit sphere), as a
    /// polar grid; `outward` picks the winding.
    fn cap(axis: Vec3, outward: bool) -> TriMesh {
        let (n_r, n_a) = (8u32, 24u32);
        let (u, v) = axis.any_orthonormal_pair();
        let mut pos = vec![axis];
        for i in 1..=n_r {
            let theta = 70f32.to_radians() * i as f32 / n_r as f32;
            for j in 0..n_a {
                let phi = std::f32::consts::TAU * j as f32 / n_a as f32;
                pos.push(theta.cos() * axis + theta.sin() * (phi.cos() * u + phi.sin() * v));
            }
        }
        let ring = |i: u32, j: u32| 1 + (i - 1) * n_a + j % n_a;
        let mut tris = Vec::new();
        for j in 0..n_a {
            tris.push([0, ring(1, j), ring(1, j + 1)]);
        }
        for i in 1..n_r {
            for j in 0..n_a {
                let (a, b, c, d) = (
                    ring(i, j),
                    ring(i, j + 1),
                    ring(i + 1, j),
                    ring(i + 1, j + 1),
                );
                tris.push([a, c, d]);
                tris.push([a, d, b]);
            }
        }
        let mut m = TriMesh::new(pos, tris).unwrap();
        if !outward {
            m.flip_winding();
        }
        m
    }

    #[test]
    fn open_cap_faces_its_bulge_whatever_the_winding() {
        let axis = Vec3::new(0.8, 0.1, -0.6).normalize();
        let want = Vec3::new(0.8, 0.0, -0.6).normalize();
        for outward in [true, false] {
            let got = open_surface_facing(&cap(axis, outward)).expect("open cap");
            assert!(got.distance(want) < 1e-4, "outward={outward}: {got}");
        }
    }

    #[test]
    fn anatomical_frame_follows_the_given_axes() {
        // headsq: slice 1 is the top (up −z), row 0 anterior (front −y).
        let f = Frame::anatomical(Vec3::new(0.0, 0.0, -2.0), Vec3::new(0.0, -1.0, 0.3));
        assert_eq!(f.up, Vec3::NEG_Z);
        assert!(f.front.distance(Vec3::NEG_Y) < 1e-6);
        assert!(f.right.distance(Vec3::NEG_Z.cross(Vec3::NEG_Y)) < 1e-6);
        let m = cap(Vec3::X, true);
        let g = Frame::for_meshes(
            &[&m],
            Facing::Anatomical {
                up: Vec3::NEG_Z,
                front: Vec3::NEG_Y,
            },
        );
        assert_eq!(g, f);
        assert_eq!(Frame::anatomical(Vec3::Y, Vec3::Y * 3.0), Frame::axes());
        assert_eq!(Frame::anatomical(Vec3::ZERO, Vec3::X), Frame::axes());
    }

    #[test]
    fn cap_facing_up_keeps_the_axes() {
        assert_eq!(open_surface_facing(&cap(Vec3::Y, true)), None);
        let m = cap(Vec3::Y, false);
        assert_eq!(Frame::for_meshes(&[&m], Facing::Auto), Frame::axes());
    }

    #[test]
    fn views_are_orthonormal_and_distinct() {
        let f = Frame::for_meshes(&[&cap(Vec3::X, true)], Facing::Auto);
        assert!(f.front.distance(Vec3::X) < 1e-5);
        assert!(f.right.distance(-Vec3::Z) < 1e-5);
        let dirs: Vec<Vec3> = View::ALL.iter().map(|&v| f.view_axes(v).0).collect();
        for (i, a) in dirs.iter().enumerate() {
            assert!((a.length() - 1.0).abs() < 1e-5);
            for b in &dirs[i + 1..] {
                assert!(a.distance(*b) > 0.5);
            }
        }
    }

    #[test]
    fn camera_maps_the_sphere_inside_clip_space() {
        let (c, r) = (Vec3::new(1.0, 2.0, 3.0), 2.0);
        for &view in View::ALL {
            let cam = view_camera(&Frame::axes(), (c, r), view, 300, 200);
            let near = cam.view_proj.project_point3(c + r * cam.to_eye);
            let far = cam.view_proj.project_point3(c - r * cam.to_eye);
            let mid = cam.view_proj.project_point3(c);
            assert!(mid.truncate().length() < 1e-5, "{view:?}: centre at {mid}");
            assert!(near.z > 0.0 && near.z < mid.z && mid.z < far.z && far.z < 1.0);
            // Image-up is the view's up made perpendicular to the view direction.
            let (e, up) = Frame::axes().view_axes(view);
            let up = (up - up.dot(e) * e).normalize();
            let top = cam.view_proj.project_point3(c + r * up);
            assert!(
                (top.y - 1.0 / MARGIN).abs() < 1e-4,
                "{view:?}: top at {top}"
            );
        }
    }
}
