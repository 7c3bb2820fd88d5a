//! Shared by every bench binary.

/// Smoke mode: `CHISEL_BENCH_QUICK=1`, or the binary runs under
/// `cargo test` (criterion's test mode runs each benchmark once, without
/// `--bench`), so the test suite never builds the full-size problems.
pub fn quick() -> bool {
    std::env::var("CHISEL_BENCH_QUICK").is_ok_and(|v| v == "1" || v == "true")
        || !std::env::args().any(|a| a == "--bench")
}

/// A benchmark group with the house timing: 10 samples after 300 ms of
/// warm-up over 2 s (smoke mode: 20 ms, 60 ms).
#[allow(dead_code, reason = "not every bench binary measures in groups")]
pub fn group<'a>(
    c: &'a mut criterion::Criterion,
    name: &str,
) -> criterion::BenchmarkGroup<'a, criterion::measurement::WallTime> {
    use std::time::Duration;
    let mut g = c.benchmark_group(name);
    if quick() {
        g.sample_size(10)
            .warm_up_time(Duration::from_millis(20))
            .measurement_time(Duration::from_millis(60));
    } else {
        g.sample_size(10)
            .warm_up_time(Duration::from_millis(300))
            .measurement_time(Duration::from_secs(2));
    }
    g
}

/// The GPU the benches run on (the adapter printed), or `None` with a note
/// when there is none: the GPU rows are then left out.
#[allow(dead_code, reason = "not every bench binary runs GPU rows")]
pub fn gpu() -> Option<chisel::gpu::Gpu> {
    match chisel::gpu::Gpu::new() {
        Ok(g) => {
            eprintln!("adapter: {}", g.describe());
            Some(g)
        }
        Err(e) => {
            eprintln!("no adapter, GPU benches skipped: {e}");
            None
        }
    }
}

/// A CT-like head phantom (i16, "Hounsfield-ish" 0..2000): soft tissue
/// ellipsoid ~1000, a bone shell ~1600 with a jaw, air 0, some texture.
#[allow(dead_code, reason = "marching-cubes benches only")]
pub fn head_phantom(n: usize) -> chisel::Volume {
    let c = (n as f32 - 1.0) / 2.0;
    let s = 2.0 / n as f32;
    let mut data = Vec::with_capacity(n * n * n);
    for z in 0..n {
        for y in 0..n {
            for x in 0..n {
                let p = [(x as f32 - c) * s, (y as f32 - c) * s, (z as f32 - c) * s];
                let head = (p[0] / 0.8).powi(2) + (p[1] / 0.9).powi(2) + (p[2] / 0.95).powi(2);
                let skull = (p[0] / 0.7).powi(2) + (p[1] / 0.8).powi(2) + (p[2] / 0.85).powi(2);
                let jaw = (p[0] / 0.5).powi(2)
                    + ((p[1] + 0.35) / 0.35).powi(2)
                    + ((p[2] + 0.6) / 0.15).powi(2);
                let texture = 40.0
                    * ((x as f32 * 0.31).sin() + (y as f32 * 0.17).cos() + (z as f32 * 0.23).sin());
                let mut v = 0.0;
                if head < 1.0 {
                    v = 1000.0 + texture;
                }
                if (0.82..1.0).contains(&skull) || (jaw < 1.0 && jaw > 0.5) {
                    v = 1600.0 + texture;
                }
                data.push(v as i16);
            }
        }
    }
    chisel::Volume::new(
        [n; 3],
        [1.0; 3],
        [0.0; 3],
        chisel::volume::VolumeData::I16(data),
    )
    .expect("phantom dims")
}

/// A smooth field of 12 Gaussian blobs on an `n³` grid over the unit cube
/// (`f32`, iso level 0.5 cuts them into a few merged bodies): the kind of
/// volume a fitted implicit model or a smoothed probability map gives.
/// Centres in [0.2, 0.8]³ and widths in [0.06, 0.14] from a fixed
/// SplitMix64 sequence, so every run and every tool sees the same samples.
#[allow(dead_code, reason = "marching-cubes benches only")]
pub fn blob_field(n: usize) -> chisel::Volume {
    let mut state = 0x5eed_b10b_u64;
    let mut unit = move || {
        state = state.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = state;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        ((z ^ (z >> 31)) >> 11) as f32 / (1u64 << 53) as f32
    };
    let blobs: Vec<([f32; 3], f32)> = (0..12)
        .map(|_| {
            let c = [0.2 + 0.6 * unit(), 0.2 + 0.6 * unit(), 0.2 + 0.6 * unit()];
            let r = 0.06 + 0.08 * unit();
            (c, 1.0 / (r * r))
        })
        .collect();
    let s = 1.0 / (n as f32 - 1.0);
    let mut data = Vec::with_capacity(n * n * n);
    for z in 0..n {
        for y in 0..n {
            for x in 0..n {
                let p = [x as f32 * s, y as f32 * s, z as f32 * s];
                let f: f32 = blobs
                    .iter()
                    .map(|(c, k)| {
                        let d2 =
                            (p[0] - c[0]).powi(2) + (p[1] - c[1]).powi(2) + (p[2] - c[2]).powi(2);
                        (-d2 * k).exp()
                    })
                    .sum();
                data.push(f);
            }
        }
    }
    chisel::Volume::new(
        [n; 3],
        [s as f64; 3],
        [0.0; 3],
        chisel::volume::VolumeData::F32(data),
    )
    .expect("blob field dims")
}
