//! A mesh's DMS spline surface end to end (SPEC §2): parametrisation, knot
//! clouds, the basis at the evaluation lattice, the control net and the
//! surface mesh with normals.
//!
//! [`SplineDomain`] is the part that depends only on the mesh's
//! connectivity and parameter points: a relaxation keeps it and, with a
//! control net that is a fixed linear map of the vertices, redraws the
//! smooth skin of every frame with two gathers ([`SplineDomain::skin`]).

use std::time::Instant;

use glam::{DVec2, DVec3, Vec3};
use serde::Serialize;

use super::basis::{BasisRows, dms_basis};
use super::domain::Domain;
use super::fit::{self, ControlMap, FitReport};
use super::lattice::{Lattice, lattice};
use super::surface::gpu::SurfaceBuffers;
use super::surface::{SurfaceInput, SurfacePoints, dms_surface};
use super::{Parametrisation, Projection, knot_clouds, parametrise};
use crate::gpu::{Backend, Gpu, GpuArray};
use crate::mesh::ScalarField;
use crate::{Error, Result, TriMesh};

/// How the control net is made.
#[derive(Debug, Clone, PartialEq)]
pub enum Fit {
    /// Point identification (eq. 2.13).
    Identify,
    /// Blossoms of local quadratic fits ([`ControlMap::quasi`]).
    Quasi,
    /// Least squares with shared controls and a relative fairing weight.
    LeastSquares { fairing: f64 },
}

impl Fit {
    /// `identify`, `quasi` or `lsq`.
    pub fn name(&self) -> &'static str {
        match self {
            Fit::Identify => "identify",
            Fit::Quasi => "quasi",
            Fit::LeastSquares { .. } => "lsq",
        }
    }
}

/// Options of [`spline`].
#[derive(Debug, Clone, PartialEq)]
pub struct SplineOptions {
    pub projection: Projection,
    pub fit: Fit,
    /// Points to fit instead of the mesh (projected by the same map).
    pub data: Option<Vec<Vec3>>,
    /// Points per parameter edge (≥ 2).
    pub n: u32,
}

/// Seconds per phase.
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct SplineTimings {
    pub parametrise: f64,
    pub knots: f64,
    pub basis: f64,
    pub fit: f64,
    pub surface: f64,
}

/// The parameter domain of a mesh with its lattice and basis rows.
#[derive(Debug, Clone)]
pub struct SplineDomain {
    pub param: Parametrisation,
    /// The smallest knot-triple quality (knots module docs).
    pub knot_quality: f64,
    pub domain: Domain,
    pub lattice: Lattice,
    /// The basis at the lattice points, over the shared controls.
    pub basis: BasisRows,
    pub timings: SplineTimings,
}

/// A spline surface and how it was made.
#[derive(Debug, Clone)]
pub struct SplineSurface {
    /// The lattice mesh: positions `F(u)`, the input's winding, scalar
    /// fields `nx ny nz` (unit normals from `F_u × F_v`), `distance`
    /// (`|F(u) − M(u)|`, `M` the input mesh at the same parameter point)
    /// and `curvature` (the largest `|n_a − n_b| / |F_a − F_b|` over the
    /// lattice edges at the point: how fast the normal turns, about the
    /// largest principal curvature; where the surface keeps the input's
    /// facets it peaks along their edges).
    pub mesh: TriMesh,
    /// The controls (`#V + E`: vertices, then edges).
    pub controls: Vec<DVec3>,
    pub fit: FitReport,
}

/// The parameter point of every lattice point (vertex points exactly their
/// vertex's, so the kernel's location-aware zeros apply).
pub fn lattice_params(lattice: &Lattice, uv: &[DVec2], triangles: &[[u32; 3]]) -> Vec<DVec2> {
    let last = lattice.n - 1;
    let s = 1.0 / f64::from(last);
    lattice
        .points
        .iter()
        .map(|p| {
            let [a, b, c] = triangles[p.triangle as usize];
            match (p.i, p.j) {
                (0, 0) => uv[a as usize],
                (i, 0) if i == last => uv[b as usize],
                (0, j) if j == last => uv[c as usize],
                (i, j) => {
                    let [a, b, c] = [a, b, c].map(|v| uv[v as usize]);
                    a + f64::from(i) * s * (b - a) + f64::from(j) * s * (c - a)
                }
            }
        })
        .collect()
}

impl SplineDomain {
    /// Parametrises `mesh`, places the knots and evaluates the basis at the
    /// lattice of accuracy `n` on `backend`.
    pub fn new(
        mesh: &TriMesh,
        projection: &Projection,
        n: u32,
        backend: Backend<'_>,
    ) -> Result<Self> {
        let mut timings = SplineTimings::default();
        let t = Instant::now();
        let param = parametrise(mesh, projection)?;
        timings.parametrise = t.elapsed().as_secs_f64();
        let t = Instant::now();
        let clouds = knot_clouds(&param.uv, &mesh.triangles)?;
        let domain = Domain::new(&mesh.triangles, &clouds);
        timings.knots = t.elapsed().as_secs_f64();
        let t = Instant::now();
        let lattice = lattice(&mesh.triangles, mesh.n_vertices(), n)?;
        let params = lattice_params(&lattice, &param.uv, &mesh.triangles);
        let basis = dms_basis(&domain, &params, backend)?;
        timings.basis = t.elapsed().as_secs_f64();
        Ok(SplineDomain {
            param,
            knot_quality: clouds.min_quality,
            domain,
            lattice,
            basis,
            timings,
        })
    }

    /// The control map of `fit` when it is a fixed linear map of the
    /// vertices (identification, quasi-interpolation), else `None`.
    pub fn control_map(&self, fit: &Fit) -> Option<ControlMap> {
        match fit {
            Fit::Identify => Some(ControlMap::identify(&self.domain)),
            Fit::Quasi => Some(ControlMap::quasi(&self.domain, &self.param.uv)),
            Fit::LeastSquares { .. } => None,
        }
    }

    /// The rows of the lattice over the shared controls.
    pub fn control_rows(&self) -> SurfaceInput {
        SurfaceInput::over_controls(&self.basis, self.domain.n_controls())
    }

    /// The smooth skin of vertex positions `positions` (a relaxation frame)
    /// under a control map given as gather rows
    /// ([`ControlMap::gather_input`]): two gathers, controls then points.
    pub fn skin(
        &self,
        map: &SurfaceInput,
        rows: &SurfaceInput,
        positions: &[[f32; 4]],
        backend: Backend<'_>,
    ) -> Result<SurfacePoints> {
        let controls = dms_surface(map, positions, backend)?;
        dms_surface(rows, &controls.positions, backend)
    }

    /// The output mesh of surface points `s` over `mesh` (the input, for
    /// the distance field).
    pub fn surface_mesh(&self, s: &SurfacePoints, mesh: &TriMesh) -> TriMesh {
        let last = (self.lattice.n - 1) as f32;
        let distance: Vec<f32> = (self.lattice.points.iter().zip(&s.positions))
            .map(|(p, f)| {
                let [a, b, c] =
                    mesh.triangles[p.triangle as usize].map(|v| mesh.positions[v as usize]);
                let m = a + (p.i as f32 / last) * (b - a) + (p.j as f32 / last) * (c - a);
                Vec3::new(f[0], f[1], f[2]).distance(m)
            })
            .collect();
        let field = |name: &str, k: usize| ScalarField {
            name: name.into(),
            values: s.normals.iter().map(|q| q[k]).collect(),
        };
        let mut curvature = vec![0.0f32; s.positions.len()];
        let v3 = |q: &[f32; 4]| Vec3::new(q[0], q[1], q[2]);
        for t in &self.lattice.triangles {
            for k in 0..3 {
                let (a, b) = (t[k] as usize, t[(k + 1) % 3] as usize);
                let d = v3(&s.positions[a]).distance(v3(&s.positions[b]));
                if d > 0.0 {
                    let c = v3(&s.normals[a]).distance(v3(&s.normals[b])) / d;
                    curvature[a] = curvature[a].max(c);
                    curvature[b] = curvature[b].max(c);
                }
            }
        }
        TriMesh {
            positions: s
                .positions
                .iter()
                .map(|p| Vec3::new(p[0], p[1], p[2]))
                .collect(),
            triangles: self.lattice.triangles.clone(),
            scalars: vec![
                field("nx", 0),
                field("ny", 1),
                field("nz", 2),
                ScalarField {
                    name: "distance".into(),
                    values: distance,
                },
                ScalarField {
                    name: "curvature".into(),
                    values: curvature,
                },
            ],
        }
    }

    /// The control net as a mesh: the six controls of every triangle as
    /// four triangles, the input's winding.
    pub fn control_mesh(&self, controls: &[DVec3]) -> TriMesh {
        let d = &self.domain;
        TriMesh {
            positions: controls.iter().map(|c| c.as_vec3()).collect(),
            triangles: (0..d.triangles.len() as u32)
                .flat_map(|t| {
                    // BETAS order: 200 110 101 020 011 002.
                    let c = |b: usize| d.control(t, b);
                    [
                        [c(0), c(1), c(2)],
                        [c(1), c(3), c(4)],
                        [c(2), c(4), c(5)],
                        [c(1), c(4), c(2)],
                    ]
                })
                .collect(),
            scalars: Vec::new(),
        }
    }
}

/// The spline surface of `mesh` (module docs).
///
/// Errors: those of the parametrisation, the knots and the lattice; data
/// points with given UVs (no map to project them, [`Error::InvalidParameter`]);
/// the least-squares errors ([`fit::least_squares`]).
pub fn spline(
    mesh: &TriMesh,
    opts: &SplineOptions,
    backend: Backend<'_>,
) -> Result<(SplineDomain, SplineSurface)> {
    let mut sd = SplineDomain::new(mesh, &opts.projection, opts.n, backend)?;
    let t = Instant::now();
    // Mesh data lie in the domain by construction; `--data` points are
    // projected, and those outside every parameter triangle left out.
    let (params, points, outside): (Vec<DVec2>, Vec<DVec3>, usize) = match &opts.data {
        None => {
            let (u, x) = fit::mesh_data(&sd.domain, &sd.param.uv, &mesh.positions);
            (u, x, 0)
        }
        Some(pts) => {
            let mut params = Vec::with_capacity(pts.len());
            let mut points = Vec::with_capacity(pts.len());
            for p in pts {
                let u = sd.param.project(*p).ok_or_else(|| {
                    Error::param(
                        "data",
                        format!("{} points", pts.len()),
                        "needs a map to project them: use --param cylinder or planar, not given UVs",
                    )
                })?;
                if sd.domain.locate(u).is_some() {
                    params.push(u);
                    points.push(p.as_dvec3());
                }
            }
            let outside = pts.len() - params.len();
            if params.is_empty() {
                return Err(Error::empty(
                    "spline data: points inside the parameter domain",
                ));
            }
            (params, points, outside)
        }
    };
    let (controls, mut report) = match sd.control_map(&opts.fit) {
        Some(map) => {
            let controls = map.apply(&mesh.positions);
            let r = fit::report(
                &sd.domain,
                opts.fit.name(),
                &params,
                &points,
                &controls,
                backend,
            )?;
            (controls, r)
        }
        None => {
            let Fit::LeastSquares { fairing } = opts.fit else {
                return Err(Error::Internal(
                    "a fit without a control map is least squares".into(),
                ));
            };
            let start = ControlMap::identify(&sd.domain).apply(&mesh.positions);
            fit::least_squares(&sd.domain, &params, &points, fairing, start, backend)?
        }
    };
    sd.timings.fit = t.elapsed().as_secs_f64();
    let t = Instant::now();
    let src: Vec<[f32; 4]> = (controls.iter())
        .map(|c| [c.x as f32, c.y as f32, c.z as f32, 0.0])
        .collect();
    let surface = dms_surface(&sd.control_rows(), &src, backend)?;
    sd.timings.surface = t.elapsed().as_secs_f64();
    report.outside = outside;
    let out = sd.surface_mesh(&surface, mesh);
    Ok((
        sd,
        SplineSurface {
            mesh: out,
            controls,
            fit: report,
        },
    ))
}

/// The smooth skin of a state that lives on the device (a relaxation's
/// `x − x_rest` per node, [`crate::tissue::Simulation::device_state`]):
/// two `dms_surface` gathers recorded into the caller's encoder, the first
/// from the state to the controls (with the rest state's controls as its
/// base, so the controls are absolute), the second from the controls to the
/// lattice points. Nothing is read back.
#[derive(Debug)]
pub struct LiveSkin {
    controls: SurfaceBuffers,
    points: SurfaceBuffers,
}

impl LiveSkin {
    /// The chain for `sd` under the control map `map`; `nodes[v]` is the
    /// state index of mesh vertex `v`, `rest[v]` its rest position.
    ///
    /// Errors: `nodes` or `rest` not one per vertex ([`Error::Mismatch`]),
    /// the buffer errors of the uploads.
    pub fn new(
        gpu: &Gpu,
        sd: &SplineDomain,
        map: &ControlMap,
        nodes: &[u32],
        rest: &[Vec3],
    ) -> Result<LiveSkin> {
        let nv = sd.domain.n_vertices;
        if nodes.len() != nv || rest.len() != nv {
            return Err(Error::mismatch(
                "live skin: node ids and rest positions (one per vertex)",
                nv,
                nodes.len().min(rest.len()),
            ));
        }
        let mut input = map.gather_input(nv);
        input
            .rows
            .targets
            .iter_mut()
            .for_each(|v| *v = nodes[*v as usize]);
        input.n_sources = nodes.iter().map(|&n| n as usize + 1).max().unwrap_or(0);
        input.base = Some(
            (map.apply(rest).iter())
                .map(|c| [c.x as f32, c.y as f32, c.z as f32, 0.0])
                .collect(),
        );
        Ok(LiveSkin {
            controls: SurfaceBuffers::upload(gpu, &input)?,
            points: SurfaceBuffers::upload(gpu, &sd.control_rows())?,
        })
    }

    /// Records both gathers from `state` into `encoder`.
    pub fn record(
        &self,
        gpu: &Gpu,
        encoder: &mut wgpu::CommandEncoder,
        state: &GpuArray<[f32; 4]>,
    ) -> Result<()> {
        self.controls.record(gpu, encoder, state)?;
        self.points.record(gpu, encoder, &self.controls.positions)
    }

    /// The lattice points and unit normals after [`LiveSkin::record`].
    pub fn output(&self) -> (&GpuArray<[f32; 4]>, &GpuArray<[f32; 4]>) {
        (&self.points.positions, &self.points.normals)
    }
}
