//! Parity of `kernels/ray_hits.wgsl` against `ray_cast::cpu::ray_hits`:
//! the same triangles in the same slots, parameters within
//! `DISTANCE_ULPS`, on a random triangle soup (many hits per ray) and the
//! foot bones, with a batch that starts mid-scan (offsets not from 0). The
//! mirror's lists agree with `ray_cast`'s nearest, farthest and count.
//! Negative controls: a hit moved to another triangle, a parameter a few
//! hundred ulps off, a shifted origin on the GPU.

use chisel::TriMesh;
use chisel::gpu::{Backend, Gpu};
use chisel::ray_cast::gpu::{BvhBuffers, HitBuffers};
use chisel::ray_cast::{Bvh, DISTANCE_ULPS, Hit, Hits, RayCaster, cpu};
use glam::Vec3;

use super::ray_cast::{close, dirs_of};
use crate::common;

/// The first slot where two hit lists disagree, as a message.
fn compare(what: &str, want: &[Hit], got: &[Hit]) -> Result<(), String> {
    if want.len() != got.len() {
        return Err(format!("{what}: {} hits vs {}", want.len(), got.len()));
    }
    for (i, (w, g)) in want.iter().zip(got).enumerate() {
        if w.tri != g.tri || !close(w.t, g.t, DISTANCE_ULPS) {
            return Err(format!("{what}: slot {i}: mirror {w:?}, GPU {g:?}"));
        }
    }
    Ok(())
}

/// The mirror's lists for `dirs` from `origin`, checked against `ray_cast`.
fn mirror(bvh: &Bvh, origin: Vec3, dirs: &[[f32; 4]]) -> Hits {
    let summary = cpu::ray_cast(bvh, origin.to_array(), dirs);
    let offsets = Hits::offsets_of(summary.iter().map(|h| h.count)).unwrap();
    let (hits, counts) = cpu::ray_hits(bvh, origin.to_array(), dirs, &offsets);
    let out = Hits { offsets, hits };
    for (i, s) in summary.iter().enumerate() {
        assert_eq!(counts[i], s.count, "ray {i}: counts of the two walks");
        let list = out.of(i);
        if let Some(near) = list.iter().min_by(|a, b| a.t.total_cmp(&b.t)) {
            assert_eq!(near.t, s.near, "ray {i}: nearest");
        }
        if let Some(far) = list.iter().max_by(|a, b| a.t.total_cmp(&b.t)) {
            assert_eq!(far.t, s.far, "ray {i}: farthest");
        }
    }
    out
}

/// The GPU's hits and counts for rays `range` of `dirs` (offsets sliced).
fn gpu_batch(
    gpu: &Gpu,
    bvh: &Bvh,
    origin: Vec3,
    dirs: &[[f32; 4]],
    offsets: &[u32],
    range: std::ops::Range<usize>,
) -> (Vec<Hit>, Vec<u32>) {
    let nodes = BvhBuffers::upload(gpu, bvh).unwrap();
    let batch = HitBuffers::upload(
        gpu,
        &nodes,
        origin,
        &dirs[range.clone()],
        &offsets[range.start..=range.end],
    )
    .unwrap();
    let mut encoder = gpu.encoder("ray_hits");
    batch.record(gpu, &nodes, &mut encoder).unwrap();
    gpu.submit_and_wait(encoder).unwrap();
    let hits = batch.hits.read(gpu).unwrap();
    let counts = batch.counts.read(gpu).unwrap();
    assert!(
        counts.iter().all(|&c| c != u32::MAX),
        "counts sentinel survived"
    );
    // Every slot of a ray whose walk found as many hits as it has slots
    // was written.
    let base = offsets[range.start];
    for (k, i) in range.clone().enumerate() {
        let slots = offsets[i] - base..offsets[i + 1] - base;
        if counts[k] >= slots.len() as u32 {
            let list = &hits[slots.start as usize..slots.end as usize];
            assert!(
                list.iter().all(|h| h.tri != u32::MAX && !h.t.is_nan()),
                "ray {i}: sentinel survived"
            );
        }
    }
    let span = (offsets[range.end] - base) as usize;
    (hits[..span].to_vec(), counts)
}

fn check(gpu: &Gpu, what: &str, mesh: &TriMesh, origin: Vec3, dirs: &[[f32; 4]]) -> Hits {
    let bvh = Bvh::build(mesh).unwrap();
    let want = mirror(&bvh, origin, dirs);
    let n = dirs.len();
    let (hits, counts) = gpu_batch(gpu, &bvh, origin, dirs, &want.offsets, 0..n);
    let walked: Vec<u32> = want.offsets.windows(2).map(|w| w[1] - w[0]).collect();
    assert_eq!(counts, walked, "{what}: counts");
    compare(what, &want.hits, &hits).unwrap_or_else(|m| panic!("{m}"));
    // A batch from the middle of the scan.
    let (a, b) = (n / 3, 2 * n / 3);
    let (hits, _) = gpu_batch(gpu, &bvh, origin, dirs, &want.offsets, a..b);
    let slice = &want.hits[want.offsets[a] as usize..want.offsets[b] as usize];
    compare(&format!("{what}, rays {a}..{b}"), slice, &hits).unwrap_or_else(|m| panic!("{m}"));
    // The caster, both backends.
    let caster = RayCaster::new(&bvh, Backend::Gpu(gpu)).unwrap();
    let listed = caster.hits(origin, dirs).unwrap();
    assert_eq!(listed.offsets, want.offsets, "{what}: caster offsets");
    compare(&format!("{what}, caster"), &want.hits, &listed.hits).unwrap_or_else(|m| panic!("{m}"));
    let on_cpu = RayCaster::new(&bvh, Backend::Cpu).unwrap();
    assert_eq!(
        on_cpu.hits(origin, dirs).unwrap(),
        want,
        "{what}: CPU caster"
    );
    want
}

#[test]
fn gpu_matches_mirror_on_a_soup_and_the_foot_bones() {
    let Some(gpu) = common::gpu() else { return };
    let dirs = dirs_of(&common::fibonacci_sphere(3000));
    let soup = common::random_mesh(7, 600, 2000);
    let hits = check(gpu, "soup", &soup, Vec3::new(0.05, 0.0, -0.1), &dirs);
    assert!(
        hits.offsets.windows(2).any(|w| w[1] - w[0] > 5),
        "soup: no ray with many hits"
    );
    if let Some(feet) = common::real_mesh("fsu/footbones.ply") {
        let dirs = dirs_of(&common::fibonacci_sphere(20_000));
        let hits = check(gpu, "footbones", &feet, Vec3::new(0.1, 0.2, -0.3), &dirs);
        assert!(hits.offsets.windows(2).any(|w| w[1] - w[0] >= 4));
    }
}

#[test]
fn comparison_catches_wrong_hits() {
    let soup = common::random_mesh(3, 200, 600);
    let bvh = Bvh::build(&soup).unwrap();
    let dirs = dirs_of(&common::fibonacci_sphere(300));
    let origin = Vec3::new(0.02, 0.0, 0.0);
    let want = mirror(&bvh, origin, &dirs);
    assert!(want.hits.len() > 20);
    compare("same", &want.hits, &want.hits).unwrap();
    let mut other = want.hits.clone();
    other[11].tri ^= 1;
    assert!(compare("moved", &want.hits, &other).is_err());
    let mut other = want.hits.clone();
    other[7].t = f32::from_bits(other[7].t.to_bits() + 300);
    assert!(compare("far", &want.hits, &other).is_err());
    assert!(compare("dropped", &want.hits, &want.hits[1..]).is_err());
    if let Some(gpu) = common::gpu() {
        let n = dirs.len();
        let shifted = Vec3::new(0.0201, 0.0, 0.0);
        let (got, _) = gpu_batch(gpu, &bvh, shifted, &dirs, &want.offsets, 0..n);
        assert!(compare("shifted origin", &want.hits, &got).is_err());
    }
}
