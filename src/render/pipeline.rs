//! The GPU side of a preview: vertex normals by the `vertex_normals` kernel,
//! then one render pass (`shaders/mesh.wgsl`, `shaders/wireframe.wgsl`) into
//! a 4× multisampled sRGB target with depth, resolved and read back.
//!
//! All views of all panels go into one texture (the view grid), each cell
//! drawn with its own viewport and camera uniform; the normals buffer of
//! each panel is bound straight into the vertex stage (no readback).

use glam::{Mat4, Vec4};
use wgpu::util::DeviceExt;

use super::Image;
use super::camera::ViewCamera;
use super::colormap::linear_stops;
use crate::gpu::{Gpu, GpuArray, Shader, UniformBuffer, preprocess};
use crate::mesh::TriMesh;
use crate::vertex_normals::NormalsInput;
use crate::vertex_normals::gpu::NormalsBuffers;
use crate::{Error, Result};

/// Colour target: 8-bit sRGB (shaders work in linear light, hardware encodes).
const COLOR_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba8UnormSrgb;
const DEPTH_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Depth32Float;
/// MSAA samples; 4 is guaranteed for both formats by WebGPU.
const SAMPLES: u32 = 4;
/// Background colour (white, linear = sRGB here).
pub(crate) const BACKGROUND: [u8; 4] = [255, 255, 255, 255];

/// The `Camera` uniform of `shaders/mesh.wgsl` and `shaders/wireframe.wgsl`.
#[derive(Debug, Clone, Copy, encase::ShaderType)]
struct CameraUniform {
    view_proj: Mat4,
    to_eye: Vec4,
    to_light: Vec4,
    depth_pull: f32,
    use_scalars: u32,
    n_colors: u32,
}

/// One mesh to draw: its triangles and, with a colour map, one coordinate
/// per vertex in [0, 1] (negative where the scalar is not finite).
#[derive(Debug)]
pub(crate) struct PanelGeometry<'a> {
    pub mesh: &'a TriMesh,
    pub color_coords: Option<Vec<f32>>,
}

/// One cell of the grid: which panel, through which camera, where (pixels).
#[derive(Debug)]
pub(crate) struct CellDraw {
    pub panel: usize,
    pub camera: ViewCamera,
    pub x: u32,
    pub y: u32,
}

/// Device buffers of one panel.
struct PanelBuffers {
    normals: NormalsBuffers,
    vertices: GpuArray<[f32; 4]>,
    triangles: wgpu::Buffer,
    n_triangle_indices: u32,
    edges: Option<(wgpu::Buffer, u32)>,
}

/// Sorted unique undirected edges `[lo, hi]` of `triangles`, flattened.
fn unique_edge_indices(triangles: &[[u32; 3]]) -> Vec<u32> {
    let mut edges = super::undirected_edges(triangles);
    edges.dedup();
    edges.into_iter().flatten().collect()
}

fn index_buffer(gpu: &Gpu, label: &str, indices: &[u32]) -> wgpu::Buffer {
    gpu.device
        .create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some(label),
            contents: bytemuck::cast_slice(indices),
            usage: wgpu::BufferUsages::INDEX,
        })
}

fn count_u32(n: usize, what: &str) -> Result<u32> {
    u32::try_from(n).map_err(|_| Error::limit(format!("render: {what}"), n, u32::MAX))
}

impl PanelBuffers {
    fn upload(gpu: &Gpu, panel: &PanelGeometry<'_>, wireframe: bool) -> Result<Self> {
        let mesh = panel.mesh;
        let vertices: Vec<[f32; 4]> = mesh
            .positions
            .iter()
            .enumerate()
            .map(|(i, p)| {
                let t = panel.color_coords.as_ref().map_or(0.0, |c| c[i]);
                [p.x, p.y, p.z, t]
            })
            .collect();
        let tri_indices: Vec<u32> = mesh.triangles.iter().flatten().copied().collect();
        let edges = if wireframe {
            let e = unique_edge_indices(&mesh.triangles);
            Some((
                index_buffer(gpu, "chisel.render.edges", &e),
                count_u32(e.len(), "edge indices")?,
            ))
        } else {
            None
        };
        Ok(PanelBuffers {
            normals: NormalsBuffers::upload(gpu, &NormalsInput::new(mesh))?,
            vertices: GpuArray::from_slice(gpu, "render.vertices", &vertices)?,
            triangles: index_buffer(gpu, "chisel.render.triangles", &tri_indices),
            n_triangle_indices: count_u32(tri_indices.len(), "triangle indices")?,
            edges,
        })
    }
}

/// The bind group layout shared by both shaders (mesh.wgsl's bindings;
/// wireframe.wgsl uses 0–1).
fn bind_group_layout(gpu: &Gpu) -> wgpu::BindGroupLayout {
    let storage = |binding, visibility| wgpu::BindGroupLayoutEntry {
        binding,
        visibility,
        ty: wgpu::BindingType::Buffer {
            ty: wgpu::BufferBindingType::Storage { read_only: true },
            has_dynamic_offset: false,
            min_binding_size: None,
        },
        count: None,
    };
    gpu.device
        .create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("chisel.render.bind_group_layout"),
            entries: &[
                wgpu::BindGroupLayoutEntry {
                    binding: 0,
                    visibility: wgpu::ShaderStages::VERTEX_FRAGMENT,
                    ty: wgpu::BindingType::Buffer {
                        ty: wgpu::BufferBindingType::Uniform,
                        has_dynamic_offset: false,
                        min_binding_size: None,
                    },
                    count: None,
                },
                storage(1, wgpu::ShaderStages::VERTEX),
                storage(2, wgpu::ShaderStages::VERTEX),
                storage(3, wgpu::ShaderStages::FRAGMENT),
            ],
        })
}

/// Builds the render pipeline of `shader` inside validation scopes; a bad
/// shader comes back as [`Error::Kernel`].
fn render_pipeline(
    gpu: &Gpu,
    shader: Shader,
    layout: &wgpu::PipelineLayout,
    topology: wgpu::PrimitiveTopology,
    depth_compare: wgpu::CompareFunction,
) -> Result<wgpu::RenderPipeline> {
    let source = preprocess(shader.source()).map_err(|message| Error::Kernel {
        name: shader.name().into(),
        message,
    })?;
    let label = shader.label();
    gpu.scoped(&label, || {
        let module = gpu
            .device
            .create_shader_module(wgpu::ShaderModuleDescriptor {
                label: Some(&label),
                source: wgpu::ShaderSource::Wgsl(source.into()),
            });
        gpu.device
            .create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                label: Some(&label),
                layout: Some(layout),
                vertex: wgpu::VertexState {
                    module: &module,
                    entry_point: Some("vs_main"),
                    compilation_options: Default::default(),
                    buffers: &[],
                },
                primitive: wgpu::PrimitiveState {
                    topology,
                    cull_mode: None,
                    front_face: wgpu::FrontFace::Ccw,
                    ..Default::default()
                },
                depth_stencil: Some(wgpu::DepthStencilState {
                    format: DEPTH_FORMAT,
                    depth_write_enabled: Some(true),
                    depth_compare: Some(depth_compare),
                    stencil: Default::default(),
                    bias: Default::default(),
                }),
                multisample: wgpu::MultisampleState {
                    count: SAMPLES,
                    ..Default::default()
                },
                fragment: Some(wgpu::FragmentState {
                    module: &module,
                    entry_point: Some("fs_main"),
                    compilation_options: Default::default(),
                    targets: &[Some(wgpu::ColorTargetState {
                        format: COLOR_FORMAT,
                        blend: None,
                        write_mask: wgpu::ColorWrites::ALL,
                    })],
                }),
                multiview_mask: None,
                cache: None,
            })
    })
    .map_err(|e| match e {
        Error::Validation { message, .. } => Error::Kernel {
            name: shader.name().into(),
            message,
        },
        other => other,
    })
}

fn attachment(
    gpu: &Gpu,
    label: &str,
    w: u32,
    h: u32,
    format: wgpu::TextureFormat,
    samples: u32,
    usage: wgpu::TextureUsages,
) -> wgpu::TextureView {
    gpu.device
        .create_texture(&wgpu::TextureDescriptor {
            label: Some(label),
            size: wgpu::Extent3d {
                width: w,
                height: h,
                depth_or_array_layers: 1,
            },
            mip_level_count: 1,
            sample_count: samples,
            dimension: wgpu::TextureDimension::D2,
            format,
            usage,
            view_formats: &[],
        })
        .create_view(&Default::default())
}

/// Renders `cells` (each `cell_w`×`cell_h` at its offset) of `panels` into
/// a `grid_w`×`grid_h` image on a white background.
pub(crate) fn render_grid(
    gpu: &Gpu,
    panels: &[PanelGeometry<'_>],
    cells: &[CellDraw],
    (cell_w, cell_h): (u32, u32),
    (grid_w, grid_h): (u32, u32),
    wireframe: bool,
) -> Result<Image> {
    let max_dim = gpu.device.limits().max_texture_dimension_2d;
    if grid_w > max_dim || grid_h > max_dim {
        return Err(Error::limit(
            format!(
                "render: pixels across the {grid_w}×{grid_h} view grid (this adapter's \
                 texture limit; use fewer views or smaller views)"
            ),
            grid_w.max(grid_h),
            max_dim,
        ));
    }
    let padded_row = (4 * grid_w).next_multiple_of(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT);
    let readback = gpu.scoped("chisel.render", || -> Result<wgpu::Buffer> {
        let layout = bind_group_layout(gpu);
        let pipeline_layout = gpu
            .device
            .create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                label: Some("chisel.render.pipeline_layout"),
                bind_group_layouts: &[Some(&layout)],
                immediate_size: 0,
            });
        let mesh_pipeline = render_pipeline(
            gpu,
            Shader::Mesh,
            &pipeline_layout,
            wgpu::PrimitiveTopology::TriangleList,
            wgpu::CompareFunction::Less,
        )?;
        let wire_pipeline = if wireframe {
            Some(render_pipeline(
                gpu,
                Shader::Wireframe,
                &pipeline_layout,
                wgpu::PrimitiveTopology::LineList,
                wgpu::CompareFunction::LessEqual,
            )?)
        } else {
            None
        };
        let stops = linear_stops();
        let colormap = GpuArray::from_slice(gpu, "render.colormap", &stops)?;
        let n_colors = count_u32(stops.len(), "colour stops")?;
        let buffers = panels
            .iter()
            .map(|p| PanelBuffers::upload(gpu, p, wireframe))
            .collect::<Result<Vec<_>>>()?;
        let mut encoder = gpu.encoder("render");
        for b in &buffers {
            b.normals.record(gpu, &mut encoder)?;
        }
        let mut binds = Vec::with_capacity(cells.len());
        for cell in cells {
            let panel = &panels[cell.panel];
            let cam = &cell.camera;
            let uniform = UniformBuffer::new(
                gpu,
                "render.camera",
                &CameraUniform {
                    view_proj: cam.view_proj,
                    to_eye: cam.to_eye.extend(0.0),
                    to_light: cam.to_light.extend(0.0),
                    depth_pull: cam.depth_pull,
                    use_scalars: u32::from(panel.color_coords.is_some()),
                    n_colors,
                },
            )?;
            let b = &buffers[cell.panel];
            let group = gpu.device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("chisel.render.bind_group"),
                layout: &layout,
                entries: &[
                    wgpu::BindGroupEntry {
                        binding: 0,
                        resource: uniform.binding(),
                    },
                    wgpu::BindGroupEntry {
                        binding: 1,
                        resource: b.vertices.binding(),
                    },
                    wgpu::BindGroupEntry {
                        binding: 2,
                        resource: b.normals.normals.binding(),
                    },
                    wgpu::BindGroupEntry {
                        binding: 3,
                        resource: colormap.binding(),
                    },
                ],
            });
            binds.push((group, uniform));
        }
        let target = wgpu::TextureUsages::RENDER_ATTACHMENT;
        let msaa = attachment(
            gpu,
            "chisel.render.msaa",
            grid_w,
            grid_h,
            COLOR_FORMAT,
            SAMPLES,
            target,
        );
        let depth = attachment(
            gpu,
            "chisel.render.depth",
            grid_w,
            grid_h,
            DEPTH_FORMAT,
            SAMPLES,
            target,
        );
        let resolved_texture = gpu.device.create_texture(&wgpu::TextureDescriptor {
            label: Some("chisel.render.resolved"),
            size: wgpu::Extent3d {
                width: grid_w,
                height: grid_h,
                depth_or_array_layers: 1,
            },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: COLOR_FORMAT,
            usage: target | wgpu::TextureUsages::COPY_SRC,
            view_formats: &[],
        });
        let resolved = resolved_texture.create_view(&Default::default());
        {
            let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("chisel.render.pass"),
                color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                    view: &msaa,
                    depth_slice: None,
                    resolve_target: Some(&resolved),
                    ops: wgpu::Operations {
                        load: wgpu::LoadOp::Clear(wgpu::Color::WHITE),
                        store: wgpu::StoreOp::Discard,
                    },
                })],
                depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                    view: &depth,
                    depth_ops: Some(wgpu::Operations {
                        load: wgpu::LoadOp::Clear(1.0),
                        store: wgpu::StoreOp::Discard,
                    }),
                    stencil_ops: None,
                }),
                timestamp_writes: None,
                occlusion_query_set: None,
                multiview_mask: None,
            });
            for (cell, (group, _)) in cells.iter().zip(&binds) {
                let b = &buffers[cell.panel];
                pass.set_viewport(
                    cell.x as f32,
                    cell.y as f32,
                    cell_w as f32,
                    cell_h as f32,
                    0.0,
                    1.0,
                );
                pass.set_scissor_rect(cell.x, cell.y, cell_w, cell_h);
                pass.set_bind_group(0, group, &[]);
                pass.set_pipeline(&mesh_pipeline);
                pass.set_index_buffer(b.triangles.slice(..), wgpu::IndexFormat::Uint32);
                pass.draw_indexed(0..b.n_triangle_indices, 0, 0..1);
                if let (Some(wire), Some((edges, n))) = (&wire_pipeline, &b.edges) {
                    pass.set_pipeline(wire);
                    pass.set_index_buffer(edges.slice(..), wgpu::IndexFormat::Uint32);
                    pass.draw_indexed(0..*n, 0, 0..1);
                }
            }
        }
        let readback = gpu.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("chisel.render.readback"),
            size: u64::from(padded_row) * u64::from(grid_h),
            usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        encoder.copy_texture_to_buffer(
            wgpu::TexelCopyTextureInfo {
                texture: &resolved_texture,
                mip_level: 0,
                origin: wgpu::Origin3d::ZERO,
                aspect: wgpu::TextureAspect::All,
            },
            wgpu::TexelCopyBufferInfo {
                buffer: &readback,
                layout: wgpu::TexelCopyBufferLayout {
                    offset: 0,
                    bytes_per_row: Some(padded_row),
                    rows_per_image: Some(grid_h),
                },
            },
            wgpu::Extent3d {
                width: grid_w,
                height: grid_h,
                depth_or_array_layers: 1,
            },
        );
        gpu.submit_and_wait(encoder)?;
        Ok(readback)
    })??;
    let padded = map_read(gpu, &readback)?;
    let row = 4 * grid_w as usize;
    let mut rgba = Vec::with_capacity(row * grid_h as usize);
    for chunk in padded.chunks_exact(padded_row as usize) {
        rgba.extend_from_slice(&chunk[..row]);
    }
    Ok(Image {
        width: grid_w,
        height: grid_h,
        rgba,
    })
}

/// Maps `buffer` (already written by a finished submission) and copies it out.
fn map_read(gpu: &Gpu, buffer: &wgpu::Buffer) -> Result<Vec<u8>> {
    let err = |message: String| Error::Readback {
        label: "chisel.render.readback".into(),
        message,
    };
    let (tx, rx) = std::sync::mpsc::channel();
    buffer.map_async(wgpu::MapMode::Read, .., move |r| {
        let _ = tx.send(r);
    });
    gpu.device
        .poll(wgpu::PollType::Wait {
            submission_index: None,
            timeout: None,
        })
        .map_err(|e| err(e.to_string()))?;
    gpu.check_errors()?;
    rx.recv()
        .map_err(|_| err("map callback never ran".into()))?
        .map_err(|e| err(e.to_string()))?;
    let out = buffer
        .get_mapped_range(..)
        .map_err(|e| err(e.to_string()))?
        .to_vec();
    buffer.unmap();
    Ok(out)
}
