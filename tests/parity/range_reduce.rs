//! Parity of `kernels/range_reduce.wgsl` against `reduce::cpu`: exact (order
//! keys), per pass and end to end, including the chunked path for data
//! larger than one storage binding; the real volumes' ranges are checked
//! against the data README.

use chisel::gpu::{Gpu, chunk_ranges};
use chisel::parity::{compare_exact, find_sentinel};
use chisel::reduce::gpu::RangeBuffers;
use chisel::reduce::{self, SampleRange, cpu};
use chisel::volume::VolumeData;
use chisel::{Backend, Error, Volume};

use crate::common;

/// Seeded samples in [-scale, scale] (xorshift).
fn random_samples(seed: u64, n: usize, scale: f32) -> Vec<f32> {
    let mut s = seed.max(1);
    (0..n)
        .map(|_| {
            s ^= s << 13;
            s ^= s >> 7;
            s ^= s << 17;
            ((s >> 40) as f32 / (1u64 << 24) as f32 * 2.0 - 1.0) * scale
        })
        .collect()
}

/// Independent oracle: a plain f32 fold.
fn oracle(samples: &[f32]) -> (f32, f32) {
    samples
        .iter()
        .fold((samples[0], samples[0]), |(lo, hi), &s| {
            (lo.min(s), hi.max(s))
        })
}

fn bits(r: SampleRange) -> [u32; 2] {
    [r.min.to_bits(), r.max.to_bits()]
}

/// Every pass equals the mirror's (keys, exactly) with no sentinel left;
/// end to end equals the mirror bit for bit and the oracle by value.
fn check(gpu: &Gpu, what: &str, samples: &[f32]) {
    if samples.len() * 4 <= gpu.max_binding_bytes() as usize {
        let buffers = RangeBuffers::new(gpu, samples).unwrap();
        let mut encoder = gpu.encoder("range_reduce");
        buffers.record(gpu, &mut encoder).unwrap();
        gpu.submit_and_wait(encoder).unwrap();
        let got = buffers.pass_outputs(gpu).unwrap();
        let mut want = vec![cpu::range_pass_samples(samples)];
        while want[want.len() - 1].len() > 1 {
            want.push(cpu::range_pass(&want[want.len() - 1]));
        }
        assert_eq!(got.len(), want.len(), "{what}: pass count");
        for (k, (g, w)) in got.iter().zip(&want).enumerate() {
            assert_eq!(
                find_sentinel(g, u32::MAX),
                None,
                "{what}: pass {k} sentinel"
            );
            let w: Vec<u32> = w.iter().flatten().copied().collect();
            compare_exact(&format!("range_reduce/{what}/pass{k}"), &w, g)
                .unwrap_or_else(|m| panic!("{m}"));
        }
    }
    let want = reduce::range_reduce(samples, Backend::Cpu)
        .unwrap()
        .unwrap();
    let got = reduce::range_reduce(samples, Backend::Gpu(gpu))
        .unwrap()
        .unwrap();
    assert_eq!(
        bits(want),
        bits(got),
        "range_reduce/{what}: {want:?} vs {got:?}"
    );
    let (lo, hi) = oracle(samples);
    assert!(
        got.min == lo && got.max == hi,
        "range_reduce/{what}: oracle ({lo}, {hi}) vs {got:?}"
    );
}

/// The test device with bindings capped at `bytes` (no second device).
fn capped_gpu(gpu: &Gpu, bytes: u64) -> Gpu {
    gpu.view(Some(bytes), false)
}

#[test]
fn synthetic() {
    let Some(gpu) = common::gpu() else { return };
    // Lanes (256), blocks (4096 items per workgroup) and pass counts.
    let (wg, b) = (256, cpu::BLOCK);
    for n in [
        1,
        2,
        wg - 1,
        wg,
        wg + 1,
        b - 1,
        b,
        b + 1,
        b * wg,
        b * wg + 1,
        1_000_007,
    ] {
        check(
            gpu,
            &format!("n{n}"),
            &random_samples(n as u64 + 1, n, 4096.0),
        );
    }
    let zeros = [0.0, -0.0, 0.0, -0.0];
    check(gpu, "zeros", &zeros);
    let r = reduce::range_reduce(&zeros, Backend::Gpu(gpu))
        .unwrap()
        .unwrap();
    assert_eq!(bits(r), [(-0.0f32).to_bits(), 0.0f32.to_bits()]);
    check(
        gpu,
        "inf",
        &[1.0, f32::INFINITY, -3.0, f32::NEG_INFINITY, 2.0],
    );
    check(gpu, "constant", &vec![42.5; 3 * b + 1]);
}

#[test]
fn grid_2d() {
    // max + 2 workgroups: past the per-dimension limit, so the host
    // dispatches a 2-D grid with surplus workgroups that must stay idle.
    // Needs (65_535 + 2)·4096 samples = 1 GiB on lavapipe, more than one
    // binding there, so this runs only on adapters with large bindings;
    // exclusive_scan::grid_2d covers the 2-D path on lavapipe.
    let Some(gpu) = common::gpu() else { return };
    let groups = gpu.device.limits().max_compute_workgroups_per_dimension as usize + 2;
    let n = groups * cpu::BLOCK - 100;
    if n * 4 > gpu.max_binding_bytes() as usize {
        eprintln!("skipping grid_2d: {n} samples exceed one binding");
        return;
    }
    let mut s = random_samples(17, n, 1.0);
    s[n - 1] = 3.0;
    s[n / 2] = -3.0;
    check(gpu, "grid_2d", &s);
}

#[test]
fn chunked_over_binding_limit() {
    // 4 KiB bindings = 1024 samples per chunk: 300_000 samples span 293
    // chunks; the extremes sit in different chunks.
    let Some(base) = common::gpu() else { return };
    let gpu = capped_gpu(base, 4096);
    let mut s = random_samples(23, 300_000, 100.0);
    s[5] = -1000.0;
    s[299_999] = 1000.0;
    assert!(chunk_ranges(s.len(), 4, gpu.max_binding_bytes()).len() > 100);
    check(&gpu, "chunked", &s);
    let r = reduce::range_reduce(&s, Backend::Gpu(&gpu))
        .unwrap()
        .unwrap();
    assert_eq!((r.min, r.max), (-1000.0, 1000.0));
    // A single-sample last chunk.
    check(&gpu, "chunked+1", &random_samples(29, 1025, 1.0));
}

#[test]
fn nan_and_empty() {
    let Some(gpu) = common::gpu() else { return };
    for backend in [Backend::Cpu, Backend::Gpu(gpu)] {
        assert_eq!(reduce::range_reduce(&[], backend).unwrap(), None);
        for nan in [f32::NAN, -f32::NAN] {
            let mut s = random_samples(3, 1000, 1.0);
            s[999] = nan;
            assert!(matches!(
                reduce::range_reduce(&s, backend),
                Err(Error::InvalidParameter { ref value, .. }) if value == "NaN"
            ));
        }
    }
}

#[test]
fn integer_volumes_convert_exactly() {
    // i16 extremes are exact in f32 (ScalarType::exact_in_f32).
    let Some(gpu) = common::gpu() else { return };
    let mut data: Vec<i16> = (0..4096).map(|i| (i * 37 % 1000) as i16).collect();
    data[100] = i16::MIN;
    data[4000] = i16::MAX;
    let v = Volume::new([16, 16, 16], [1.0; 3], [0.0; 3], VolumeData::I16(data)).unwrap();
    let r = reduce::volume_range(&v, Backend::Gpu(gpu))
        .unwrap()
        .unwrap();
    assert_eq!((r.min, r.max), (-32768.0, 32767.0));
    assert_eq!(Some(r), reduce::volume_range(&v, Backend::Cpu).unwrap());
}

/// A real volume: mirror, GPU (one binding and chunked) and README range.
fn real(rel: &str, min: f32, max: f32, chunk_bytes: u64) {
    let Some(v) = common::real_volume(rel) else {
        return;
    };
    let Some(gpu) = common::gpu() else { return };
    let samples = v.data.to_f32();
    check(gpu, rel, &samples);
    let r = reduce::volume_range(&v, Backend::Gpu(gpu))
        .unwrap()
        .unwrap();
    assert_eq!((r.min, r.max), (min, max), "{rel} vs README");
    let capped = capped_gpu(gpu, chunk_bytes);
    assert!(chunk_ranges(samples.len(), 4, capped.max_binding_bytes()).len() > 1);
    let c = reduce::volume_range(&v, Backend::Gpu(&capped))
        .unwrap()
        .unwrap();
    assert_eq!(bits(c), bits(r), "{rel}: chunked vs whole");
}

#[test]
fn real_headsq() {
    real("headsq/quarter.nhdr", 0.0, 3926.0, 64 * 1024);
}

#[test]
fn real_head_mr() {
    real("HeadMRVolume.mhd", 0.0, 255.0, 64 * 1024);
}

#[test]
fn real_foot_2d() {
    real("foot/foot.mha", 0.0, 218.0, 64 * 1024);
}

#[test]
fn real_frogtissue() {
    // 31.96 M samples = 127.84 MB as f32: just under lavapipe's 128 MiB
    // binding; 32 MiB chunks make the chunked path split it in four.
    real("froggy/frogtissue.mhd", 0.0, 29.0, 32 << 20);
}

#[test]
fn negative_control() {
    let Some(gpu) = common::gpu() else { return };
    let s = random_samples(5, 50_000, 1.0);
    let buffers = RangeBuffers::new(gpu, &s).unwrap();
    let mut encoder = gpu.encoder("range_reduce");
    buffers.record(gpu, &mut encoder).unwrap();
    gpu.submit_and_wait(encoder).unwrap();
    let mut got = buffers.pass_outputs(gpu).unwrap().swap_remove(0);
    let want: Vec<u32> = cpu::range_pass_samples(&s).into_iter().flatten().collect();
    compare_exact("range_reduce/control", &want, &got).unwrap();
    let k = 12;
    got[k] = got[k].wrapping_add(1);
    let m = compare_exact("range_reduce/control", &want, &got).unwrap_err();
    assert_eq!((m.index, m.count), (k, 1), "{m}");
}
