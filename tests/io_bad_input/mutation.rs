//! Seeded mutations of valid files of every format: every read returns
//! `Ok` or `Err`, never panics.

use std::path::{Path, PathBuf};

use chisel::Volume;
use chisel::io::{read_mesh, read_volume, write_mesh, write_volume};
use chisel::volume::VolumeData;

use crate::mesh::ply_header;
use crate::{common, is_volume, put};

// ---------------------------------------------------------------- mutation loop

/// Valid small files of every format, written by chisel and by hand.
fn valid_files(dir: &Path) -> Vec<PathBuf> {
    let mut m = common::icosphere(0);
    m.scalars.push(chisel::mesh::ScalarField {
        name: "s".into(),
        values: (0..m.n_vertices()).map(|i| i as f32).collect(),
    });
    let mut files = Vec::new();
    for name in ["m.ply", "m.vtk", "m.obj", "m.stl", "m.byu"] {
        let p = dir.join(name);
        write_mesh(&p, &m).unwrap();
        files.push(p);
    }
    files.push(put(
        dir,
        "a.ply",
        format!(
            "{}0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n",
            ply_header("ascii", 3, 1)
        )
        .as_bytes(),
    ));
    files.push(put(
        dir,
        "a.stl",
        b"solid a\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 0 1 0\nendloop\nendfacet\nendsolid a\n",
    ));
    let mut b =
        b"# vtk DataFile Version 3.0\nt\nBINARY\nDATASET POLYDATA\nPOINTS 3 float\n".to_vec();
    for c in [0f32, 0., 0., 1., 0., 0., 0., 1., 0.] {
        b.extend(c.to_be_bytes());
    }
    b.extend(b"\nTRIANGLE_STRIPS 1 4\n");
    for i in [3i32, 0, 1, 2] {
        b.extend(i.to_be_bytes());
    }
    files.push(put(dir, "b.vtk", &b));
    let v = Volume::new(
        [3, 4, 2],
        [1.0, 2.0, 0.5],
        [0.0, -1.0, 2.0],
        VolumeData::I16((0..24).map(|i| i * 300 - 3000).collect()),
    )
    .unwrap();
    for name in ["v.nrrd", "v.mha", "v.nii", "v.nii.gz", "v.mhd"] {
        let p = dir.join(name);
        write_volume(&p, &v).unwrap();
        files.push(p);
    }
    let mut gz =
        b"NRRD0004\ntype: short\ndimension: 3\nsizes: 3 4 2\nendian: big\nencoding: gzip\n\n"
            .to_vec();
    {
        use std::io::Write;
        let mut e = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::fast());
        for i in 0..24i16 {
            e.write_all(&(i * 300).to_be_bytes()).unwrap();
        }
        gz.extend(e.finish().unwrap());
    }
    files.push(put(dir, "g.nrrd", &gz));
    files
}

/// Seeded mutations (truncation, byte flips, digit insertions, repeats) of
/// valid files: every read must return `Ok` or `Err`, never panic.
#[test]
fn mutated_files_never_panic() {
    let dir = tempfile::tempdir().unwrap();
    let files = valid_files(dir.path());
    let mut bits = common::xorshift(0x9E37_79B9_7F4A_7C15);
    let mut next = move |n: usize| (bits() % n.max(1) as u64) as usize;
    let (mut ok, mut err) = (0, 0);
    for path in &files {
        let original = std::fs::read(path).unwrap();
        let name = path.file_name().unwrap().to_string_lossy().into_owned();
        let target = dir.path().join(format!("mut_{name}"));
        // The `.mhd` header keeps pointing at the intact `v.raw`.
        for round in 0..120 {
            let mut b = original.clone();
            match round % 4 {
                0 => b.truncate(next(b.len())),
                1 => {
                    for _ in 0..1 + next(4) {
                        let i = next(b.len());
                        b[i] ^= 1 << next(8);
                    }
                }
                2 => {
                    let i = next(b.len());
                    let digits = [b"9".as_slice(), b"-", b"99999999999", b" ", b"\n", b"nan"];
                    b.splice(i..i, digits[next(digits.len())].iter().copied());
                }
                _ => {
                    let i = next(b.len());
                    let j = (i + next(64)).min(b.len());
                    let chunk = b[i..j].to_vec();
                    b.splice(j..j, chunk);
                }
            }
            std::fs::write(&target, &b).unwrap();
            let r = if is_volume(&target) {
                read_volume(&target).map(|_| ())
            } else {
                read_mesh(&target).map(|_| ())
            };
            match r {
                Ok(()) => ok += 1,
                Err(_) => err += 1,
            }
        }
    }
    // Both outcomes occur: the loop really exercises the error paths.
    assert!(ok > 0 && err > 0, "ok {ok}, err {err}");
}
