//! `chisel phantom KIND ... -o VOLUME`: the seed's test objects (seed 003
//! Tables 4.1/4.2, 8.6/8.7, §8.1) and the demo's CT-like head as volumes
//! (object voxels 1, background 0; the head in CT numbers).

use std::path::{Path, PathBuf};

use serde::Serialize;

use super::Global;
use super::report::{Report, Show};
use crate::phantom::voxel;
use crate::volume::VolumeStats;

/// The report of `chisel phantom`.
#[derive(Debug, Serialize)]
pub struct PhantomReport<'a> {
    command: &'static str,
    kind: &'a Kind,
    dims: [usize; 3],
    spacing: [f64; 3],
    origin: [f64; 3],
    stats: VolumeStats,
    output: &'a Path,
}

impl Report for PhantomReport<'_> {
    const SCHEMA: &'static str = "chisel.phantom/1";
}

/// The objects (in reports `{"shape": "ball", "r": 4}`).
#[derive(Debug, Clone, clap::Subcommand, serde::Serialize)]
#[serde(tag = "shape", rename_all = "kebab-case")]
pub enum Kind {
    /// Digital ball of combinatorial radius R (radius R/2 voxels), centre at a cell corner.
    Ball {
        /// Combinatorial radius (twice the radius in voxels).
        #[arg(long)]
        r: u32,
    },
    /// Axis-aligned cube of A³ voxels.
    Cube {
        /// Edge length in voxels.
        #[arg(long)]
        a: u32,
    },
    /// Cylinder of height H along z with a central cylindrical tunnel (diameters in voxels).
    CylinderTunnel {
        /// Outer diameter in voxels.
        #[arg(long)]
        outer: u32,
        /// Tunnel diameter in voxels.
        #[arg(long)]
        inner: u32,
        /// Height in voxels.
        #[arg(long, default_value_t = 15)]
        height: u32,
    },
    /// Torus about z (combinatorial major radius R, tube radius r).
    Torus {
        /// Combinatorial radius of the centre circle.
        #[arg(long)]
        major: u32,
        /// Combinatorial radius of the tube.
        #[arg(long)]
        minor: u32,
    },
    /// Ellipsoid (semi-axes A, B, C voxels) with a spherical dent at the +z pole.
    EllipsoidDent {
        /// Semi-axis along x in voxels.
        #[arg(long)]
        a: u32,
        /// Semi-axis along y in voxels.
        #[arg(long)]
        b: u32,
        /// Semi-axis along z in voxels.
        #[arg(long)]
        c: u32,
        /// Radius of the dent in voxels.
        #[arg(long)]
        dent: u32,
    },
    /// Smooth random blob in an N³ grid: twelve integer metaballs from SEED.
    Blob {
        /// Grid size N (N³ voxels).
        #[arg(long)]
        n: u32,
        /// Seed of the metaball placement.
        #[arg(long, default_value_t = 1)]
        seed: u64,
    },
    /// The demo's CT-like head (air 0, soft tissue 1000, bone 2000; mm).
    Head {
        /// Voxel edge in mm.
        #[arg(long, default_value_t = 5.0)]
        voxel: f32,
    },
}

/// Arguments of `chisel phantom`.
#[derive(Debug, clap::Args)]
pub struct Args {
    #[command(subcommand)]
    kind: Kind,
    /// Output volume (nrrd, nhdr, mha, mhd, nii, nii.gz), written atomically.
    #[arg(short, long, global = true)]
    output: Option<PathBuf>,
    /// Print the report on stdout.
    #[arg(long, global = true)]
    json: bool,
}

pub fn run(global: &Global, args: &Args) -> anyhow::Result<()> {
    let Some(output) = &args.output else {
        anyhow::bail!("give the output volume with -o FILE");
    };
    crate::io::check_volume_output(output)?;
    let volume = match args.kind {
        Kind::Ball { r } => voxel::digital_ball(r)?,
        Kind::Cube { a } => voxel::cube(a)?,
        Kind::CylinderTunnel {
            outer,
            inner,
            height,
        } => voxel::cylinder_tunnel(outer, inner, height)?,
        Kind::Torus { major, minor } => voxel::torus(major, minor)?,
        Kind::EllipsoidDent { a, b, c, dent } => voxel::ellipsoid_dent(a, b, c, dent)?,
        Kind::Blob { n, seed } => voxel::blob(n, seed)?,
        Kind::Head { voxel } => crate::tissue::phantom::ct_head_phantom(voxel)?,
    };
    crate::io::write_volume(output, &volume)?;
    let report = PhantomReport {
        command: "phantom",
        kind: &args.kind,
        dims: volume.dims,
        spacing: volume.spacing,
        origin: volume.origin,
        stats: VolumeStats::of(&volume),
        output,
    };
    global.note(format!(
        "{:?}: {:?} samples; wrote {}",
        args.kind,
        volume.dims,
        output.display()
    ));
    super::report::emit(&report, Show::WithJson, args.json, None)
}

impl super::Inputs for Args {
    fn inputs(&self) -> Vec<&std::path::Path> {
        Vec::new()
    }
}
