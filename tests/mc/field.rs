//! The CPU's sample access (bit rows, native samples) and the GPU's
//! (sample words decoded as `kernels/shared/mc_grid.wgsl` does) against
//! the `f32` layers of `Field::layer`.

use chisel::mc::IsoSpec;
use chisel::mc::field::{NativeSamples, SampleVisitor, Scalar};
use chisel::mc::grid::{SampleKind, grid_sample, inner_layers, sample_grid, sample_words};
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
/// known at compile time); the GPU reads the samples' words of the layers
/// it needs (`grid_sample`, the mirror of the kernels' decoding, on the
/// words of one layer's window as a slab upload makes them); all must equal
/// the `f32` layers (`Field::layer`), for every sample type, with and
/// without padding, at levels between, on and beyond the integer values,
/// and for labels. 8- and 16-bit and `f32` samples travel in their own
/// type (2 bytes a sample for `i16`).
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
                    let (k0, k1) = inner_layers(&field, z, z + 1);
                    let words = sample_words(&field, k0, k1).unwrap();
                    let grid = sample_grid(&field, k0);
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
                                let g = grid_sample(&grid, &words, x as u32, y as u32, z as u32);
                                for (got, what) in
                                    [(s, "sample"), (n, "native sample"), (g, "GPU word sample")]
                                {
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

/// The words' sizes: 16-bit samples two a word, 8-bit four, 32-bit
/// integers and f64 converted to one f32 a word; a word decoded as the
/// wrong kind gives other samples (the comparison above can fail).
#[test]
fn sample_words_keep_the_native_width() {
    let dims = [7, 3, 2];
    let n: u32 = 42;
    let cases = [
        (
            VolumeData::I16((0..n).map(|i| i as i16 * -700).collect()),
            SampleKind::I16,
            21,
        ),
        (
            VolumeData::U16((0..n).map(|i| i as u16 * 900).collect()),
            SampleKind::U16,
            21,
        ),
        (
            VolumeData::I8((0..n).map(|i| i as i8 - 20).collect()),
            SampleKind::I8,
            11,
        ),
        (
            VolumeData::U8((0..n).map(|i| i as u8 * 5).collect()),
            SampleKind::U8,
            11,
        ),
        (
            VolumeData::F32((0..n).map(|i| i as f32 * 0.25).collect()),
            SampleKind::F32,
            42,
        ),
        (
            VolumeData::I32((0..n).map(|i| i as i32 * 3).collect()),
            SampleKind::F32,
            42,
        ),
        (
            VolumeData::F64((0..n).map(|i| i as f64 * 0.5).collect()),
            SampleKind::F32,
            42,
        ),
    ];
    for (data, kind, n_words) in cases {
        let what = data.scalar_type();
        let vol = Volume::new(dims, [1.0; 3], [0.0; 3], data).unwrap();
        let field = chisel::mc::Field::new(&vol, IsoSpec::Level(10.0), false).unwrap();
        let words = sample_words(&field, 0, 2).unwrap();
        let grid = sample_grid(&field, 0);
        assert_eq!((grid.kind, words.len()), (kind as u32, n_words), "{what:?}");
        let wrong = chisel::mc::grid::SampleGrid {
            // Narrower or same-width kinds, so no index leaves the words.
            kind: match kind {
                SampleKind::F32 => SampleKind::I16,
                SampleKind::I16 | SampleKind::U16 | SampleKind::U8 => SampleKind::I8,
                SampleKind::I8 => SampleKind::U8,
            } as u32,
            ..grid
        };
        let differs = (0..n).any(|i| {
            let (x, y, z) = (i % 7, (i / 7) % 3, i / 21);
            grid_sample(&grid, &words, x, y, z) != grid_sample(&wrong, &words, x, y, z)
        });
        assert!(differs, "{what:?}: a wrong kind must change the samples");
    }
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
