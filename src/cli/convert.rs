//! `chisel convert IN -o OUT`: mesh ↔ mesh or volume ↔ volume (the input
//! told by its content, the output by its extension).

use std::path::PathBuf;

use super::Global;

/// Arguments of `chisel convert`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Input mesh or volume.
    input: PathBuf,
    /// Output file; its extension picks the format (written atomically).
    #[arg(short, long)]
    output: PathBuf,
    /// Meshes: also write a shaded preview PNG of the result.
    #[arg(long)]
    preview: Option<PathBuf>,
    /// Meshes: keep only the K-th connected component (0 = the most
    /// triangles; ties by first triangle).
    #[arg(long, value_name = "K")]
    component: Option<usize>,
    /// Meshes: move every vertex by `x,y,z`.
    #[arg(long, value_delimiter = ',', allow_hyphen_values = true)]
    translate: Option<Vec<f32>>,
}

/// `--component` and `--translate` applied to `m`.
fn select_and_move(args: &Args, mut m: crate::TriMesh) -> anyhow::Result<crate::TriMesh> {
    if let Some(k) = args.component {
        let (labels, n) = crate::foundation::vertex_components(m.positions.len(), &m.triangles);
        let mut parts = crate::mesh::split_by_label(&m, &labels);
        anyhow::ensure!(
            k < n,
            "{}: --component {k}, but the mesh has {n} component(s)",
            args.input.display()
        );
        // Stable: equal sizes keep the order of their first triangles.
        parts.sort_by_key(|p| std::cmp::Reverse(p.triangles.len()));
        m = parts.swap_remove(k);
    }
    if let Some(t) = super::vec3_arg("translate", args.translate.as_deref())? {
        for p in &mut m.positions {
            *p += t;
        }
    }
    Ok(m)
}

/// An output-path check of one kind (mesh or volume).
type CheckOutput = fn(&std::path::Path) -> crate::Result<()>;

pub fn run(global: &Global, args: &Args) -> anyhow::Result<()> {
    // Output names are checked before the input is looked at.
    if let Some(path) = &args.preview {
        crate::foundation::fs::check_png_output(path)?;
    }
    let input_is_volume = crate::io::is_volume(&args.input)?;
    // `.vtk` holds either kind: the input's.
    let output_is_volume = if crate::foundation::fs::file_name_lower(&args.output).ends_with(".vtk")
    {
        input_is_volume
    } else {
        crate::io::names_volume(&args.output)
    };
    match (input_is_volume, output_is_volume) {
        (true, true) => {
            anyhow::ensure!(
                args.component.is_none() && args.translate.is_none(),
                "--component and --translate work on meshes"
            );
            anyhow::ensure!(
                args.preview.is_none(),
                "--preview draws meshes; use `chisel mc --preview` for a volume's surface"
            );
            let v = global.read_volume(&args.input)?;
            crate::io::write_volume(&args.output, &v)?;
            global.note(format!(
                "wrote {} ({}×{}×{} {})",
                args.output.display(),
                v.dims[0],
                v.dims[1],
                v.dims[2],
                v.data.scalar_type().name()
            ));
        }
        (false, false) => {
            crate::io::check_mesh_output(&args.output)?;
            if let Some(path) = &args.preview {
                crate::foundation::fs::check_png_output(path)?;
            }
            let m = select_and_move(args, crate::io::read_mesh(&args.input)?)?;
            if !m.scalars.is_empty() && !crate::io::mesh_format_carries_scalars(&args.output) {
                global.note(format!(
                    "note: {} cannot store per-vertex scalars; dropped: {}",
                    args.output.display(),
                    m.scalars
                        .iter()
                        .map(|s| s.name.as_str())
                        .collect::<Vec<_>>()
                        .join(", ")
                ));
            }
            crate::io::write_mesh(&args.output, &m)?;
            if let Some(path) = &args.preview {
                let opts = crate::render::RenderOptions {
                    views: vec![crate::render::View::Front, crate::render::View::Iso],
                    title: Some(super::file_name(&args.output)),
                    ..Default::default()
                };
                crate::render::render_png(&global.gpu()?, &m, &opts, path)?;
            }
            global.note(format!(
                "wrote {} ({} vertices, {} triangles)",
                args.output.display(),
                m.n_vertices(),
                m.n_triangles()
            ));
        }
        (input_is_volume, _) => {
            // An output name of neither kind gets the input kind's formats.
            let (same_kind, other_kind): (CheckOutput, CheckOutput) = if input_is_volume {
                (crate::io::check_volume_output, crate::io::check_mesh_output)
            } else {
                (crate::io::check_mesh_output, crate::io::check_volume_output)
            };
            if other_kind(&args.output).is_err() {
                same_kind(&args.output)?;
            }
            anyhow::bail!(
                "cannot convert a {} into a {} ({} → {}){}",
                if input_is_volume { "volume" } else { "mesh" },
                if input_is_volume { "mesh" } else { "volume" },
                args.input.display(),
                args.output.display(),
                if input_is_volume {
                    "; `chisel mc` makes surfaces of volumes"
                } else {
                    ""
                }
            )
        }
    }
    Ok(())
}

impl super::Inputs for Args {
    fn inputs(&self) -> Vec<&std::path::Path> {
        vec![self.input.as_path()]
    }
}
