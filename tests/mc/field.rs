//! The CPU's sample access (bit rows, native samples) against the `f32`
//! layers the GPU uploads.

use chisel::mc::IsoSpec;
use chisel::mc::field::{NativeSamples, SampleVisitor, Scalar};
use chisel::volume::{Volume, VolumeData};

use crate::common;

/// Every sample of the padded grid read through `NativeSamples` (x
/// fastest, then y, then z).
struct AllSamples([usize; 3]);

impl SampleVisitor for AllSamples {
    type Output = Vec<f32>;

    fn visit<T: Scalar>(self, samples: NativeSamples<'_, '_, T>) -> Vec<f32> {
        let [nx, ny, nz] = self.0;
        let mut out = Vec::with_capacity(nx * ny * nz);
        for z in 0..nz {
            for y in 0..ny {
                for x in 0..nx {
                    out.push(samples.sample(x, y, z));
                }
            }
        }
        out
    }
}

/// The CPU reads inside flags as bit rows in the native type and samples
/// only at crossings (`Field::sample`, and `NativeSamples` with the type
/// known at compile time); all must equal the `f32` layers the GPU uploads
/// (`Field::layer`), for every sample type, with and without padding, at
/// levels between, on and beyond the integer values, and for labels.
#[test]
fn field_rows_and_samples_match_layers() {
    let dims = [70, 5, 4];
    let n: usize = dims.iter().product();
    let mut next = common::xorshift(77);
    let raw: Vec<i64> = (0..n).map(|_| (next() % 9) as i64 - 4).collect();
    let volumes = [
        VolumeData::U8(raw.iter().map(|&v| (v + 4) as u8).collect()),
        VolumeData::I8(raw.iter().map(|&v| v as i8).collect()),
        VolumeData::U16(raw.iter().map(|&v| (v + 4) as u16 * 1000).collect()),
        VolumeData::I16(raw.iter().map(|&v| v as i16 * 1000).collect()),
        VolumeData::U32(raw.iter().map(|&v| (v + 4) as u32 * 100_000_007).collect()),
        VolumeData::I32(raw.iter().map(|&v| v as i32 * 100_000_007).collect()),
        VolumeData::F32(raw.iter().map(|&v| v as f32 * 0.3).collect()),
        VolumeData::F64(raw.iter().map(|&v| v as f64 * 0.3 + 1e-9).collect()),
    ];
    let isos = [
        IsoSpec::Level(0.0),
        IsoSpec::Level(0.5),
        IsoSpec::Level(-1.0),
        IsoSpec::Level(2.0),
        IsoSpec::Level(1000.0),
        IsoSpec::Level(-3999.5),
        IsoSpec::Level(1e6),
        IsoSpec::Level(1e30),
        IsoSpec::Level(-1e30),
        IsoSpec::Level(300_000_021.0),
        IsoSpec::Level(0.6),
        IsoSpec::Label(0.0),
        IsoSpec::Label(2.0),
        IsoSpec::Label(-2.0),
        IsoSpec::Label(2000.0),
        IsoSpec::Label(0.5),
        IsoSpec::Label(1e12),
    ];
    let mut checked_inside = 0usize;
    for data in volumes {
        let vol = Volume::new(dims, [1.0; 3], [0.0; 3], data).unwrap();
        for iso in isos {
            for close in [false, true] {
                let field = chisel::mc::Field::new(&vol, iso, close).unwrap();
                let [nx, ny, nz] = field.dims;
                let native = field.visit_samples(AllSamples(field.dims));
                let mut layer = vec![0f32; nx * ny];
                let mut row = vec![0u64; field.row_words()];
                for z in 0..nz {
                    field.layer(z, &mut layer);
                    for y in 0..ny {
                        field.inside_row(y, z, &mut row);
                        for x in 0..field.row_words() * 64 {
                            let bit = row[x / 64] >> (x % 64) & 1 == 1;
                            let want = x < nx && layer[x + nx * y] >= field.level;
                            assert_eq!(
                                bit,
                                want,
                                "{:?} {iso:?} close {close}: inside ({x}, {y}, {z})",
                                vol.data.scalar_type()
                            );
                            checked_inside += usize::from(want);
                            if x < nx {
                                let want = layer[x + nx * y].to_bits();
                                let s = field.sample(x, y, z);
                                let n = native[x + nx * (y + ny * z)];
                                for (got, what) in [(s, "sample"), (n, "native sample")] {
                                    assert_eq!(
                                        got.to_bits(),
                                        want,
                                        "{:?} {iso:?} close {close}: {what} ({x}, {y}, {z})",
                                        vol.data.scalar_type()
                                    );
                                }
                            }
                        }
                    }
                }
            }
        }
    }
    assert!(
        checked_inside > 0,
        "no inside sample: the test proves nothing"
    );
}

/// A view of borrowed samples (a caller's buffer, read in place) gives the
/// surface of the owning volume, and is checked as `Volume::new` checks.
#[test]
fn a_borrowed_view_gives_the_owned_volumes_surface() {
    use chisel::Backend;
    use chisel::mc::McOptions;
    use chisel::volume::{IDENTITY_AXES, Samples, VolumeView};
    let n = 16usize;
    let ball: Vec<u8> = (0..n * n * n)
        .map(|i| {
            let (x, y, z) = (i % n, (i / n) % n, i / (n * n));
            let d2 = [x, y, z]
                .iter()
                .map(|&c| (c as f64 - 7.5).powi(2))
                .sum::<f64>();
            u8::from(d2 <= 25.0) * 200
        })
        .collect();
    let vol = Volume::new(
        [n; 3],
        [0.5, 0.75, 1.0],
        [1.0, 2.0, 3.0],
        VolumeData::U8(ball),
    )
    .unwrap();
    let iso = IsoSpec::Level(100.0);
    let owned = chisel::mc::marching_cubes(&vol, iso, &McOptions::default(), Backend::Cpu).unwrap();
    let VolumeData::U8(samples) = &vol.data else {
        unreachable!("made as u8 above");
    };
    let view = VolumeView::new(
        vol.dims,
        vol.spacing,
        vol.origin,
        IDENTITY_AXES,
        None,
        Samples::U8(samples),
    )
    .unwrap();
    let borrowed =
        chisel::mc::marching_cubes(view, iso, &McOptions::default(), Backend::Cpu).unwrap();
    assert_eq!(borrowed.mesh, owned.mesh);
    assert!(!owned.mesh.triangles.is_empty());
    // Negative controls: a sample short, a zero spacing.
    let short = Samples::U8(&samples[1..]);
    assert!(
        VolumeView::new(
            vol.dims,
            vol.spacing,
            vol.origin,
            IDENTITY_AXES,
            None,
            short
        )
        .is_err()
    );
    let flat = [vol.spacing[0], 0.0, vol.spacing[2]];
    assert!(
        VolumeView::new(
            vol.dims,
            flat,
            vol.origin,
            IDENTITY_AXES,
            None,
            Samples::U8(samples)
        )
        .is_err()
    );
}
