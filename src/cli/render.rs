//! `chisel render IN -o OUT.png`: a shaded preview of a mesh.

use std::path::PathBuf;

use super::{Global, ViewAxes};
use crate::render::{RenderOptions, View};

/// Arguments of `chisel render`.
#[derive(Debug, clap::Args)]
#[command(allow_negative_numbers = true)]
pub struct Args {
    /// Mesh to draw.
    input: PathBuf,
    /// Output PNG (written atomically).
    #[arg(short, long)]
    output: PathBuf,
    /// Colour the surface by this per-vertex scalar field (with a legend).
    #[arg(long)]
    scalars: Option<String>,
    /// Views, in order: front, back, left, right (= side), top, bottom, iso.
    #[arg(long, value_delimiter = ',', default_value = "front,side,top,iso")]
    views: Vec<View>,
    /// Draw the triangle edges over the shading.
    #[arg(long)]
    wireframe: bool,
    /// Pixel size of each view (128 to 4096: smaller views have no room
    /// for their labels and the legend).
    #[arg(long, default_value_t = 512, value_parser = clap::value_parser!(u32).range(128..=4096))]
    size: u32,
    #[command(flatten)]
    view: ViewAxes,
}

pub fn run(global: &Global, args: &Args) -> anyhow::Result<()> {
    crate::foundation::fs::check_png_output(&args.output)?;
    let facing = args.view.facing()?;
    let mesh = crate::io::read_surface(&args.input)?;
    let gpu = global.gpu()?;
    let opts = RenderOptions {
        width: args.size,
        height: args.size,
        views: args.views.clone(),
        wireframe: args.wireframe,
        scalars: args.scalars.clone(),
        title: Some(super::file_name(&args.input)),
        facing,
        ..Default::default()
    };
    crate::render::render_png(&gpu, &mesh, &opts, &args.output)?;
    global.note(format!("wrote {}", args.output.display()));
    Ok(())
}

impl super::Inputs for Args {
    fn inputs(&self) -> Vec<&std::path::Path> {
        vec![self.input.as_path()]
    }
}
