//! The perceptual colour map of scalar previews: viridis.
//!
//! Stops are matplotlib's `viridis` (van der Walt & Smith, 2015; released
//! CC0), resampled from its 256-entry table at t = k/32 (33 stops, sRGB). A
//! piecewise-linear lookup through these stops stays within 1.7/255 of the
//! full table. The same stops drive the GPU (`shaders/mesh.wgsl`, uploaded
//! as linear RGB) and the CPU legend ([`sample_srgb8`]), so bar and surface
//! agree.

/// Viridis in sRGB, 33 stops at t = 0, 1/32, …, 1.
const VIRIDIS: [[f32; 3]; 33] = [
    [0.267004, 0.004874, 0.329415],
    [0.276987, 0.050151, 0.375542],
    [0.282302, 0.094624, 0.417024],
    [0.282902, 0.135449, 0.453035],
    [0.278919, 0.174879, 0.482972],
    [0.270788, 0.213324, 0.506643],
    [0.259266, 0.250672, 0.524378],
    [0.245374, 0.286704, 0.536971],
    [0.230223, 0.321297, 0.545488],
    [0.214836, 0.354470, 0.551027],
    [0.199995, 0.386377, 0.554533],
    [0.186132, 0.417256, 0.556682],
    [0.173302, 0.447386, 0.557850],
    [0.161265, 0.477036, 0.558125],
    [0.149668, 0.506440, 0.557329],
    [0.138415, 0.535767, 0.555090],
    [0.128148, 0.565107, 0.550893],
    [0.120875, 0.594465, 0.544158],
    [0.120325, 0.623765, 0.534308],
    [0.130961, 0.652859, 0.520817],
    [0.155378, 0.681539, 0.503240],
    [0.192974, 0.709556, 0.481231],
    [0.241467, 0.736626, 0.454543],
    [0.298636, 0.762445, 0.423019],
    [0.362859, 0.786695, 0.386589],
    [0.432985, 0.809056, 0.345271],
    [0.508094, 0.829231, 0.299221],
    [0.587266, 0.846982, 0.248871],
    [0.669358, 0.862217, 0.195444],
    [0.752867, 0.875089, 0.142650],
    [0.835913, 0.886110, 0.102462],
    [0.916550, 0.896130, 0.100822],
    [0.993248, 0.906157, 0.143936],
];

/// sRGB transfer function, decoding: encoded value in [0, 1] → linear.
pub(crate) fn srgb_to_linear(c: f32) -> f32 {
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

/// sRGB transfer function, encoding: linear value in [0, 1] → encoded.
pub(crate) fn linear_to_srgb(c: f32) -> f32 {
    if c <= 0.003_130_8 {
        c * 12.92
    } else {
        1.055 * c.powf(1.0 / 2.4) - 0.055
    }
}

/// The stops as linear RGB `[r, g, b, 1]`, the layout of the shader's
/// `colormap` buffer (interpolated linearly in linear light there).
pub(crate) fn linear_stops() -> Vec<[f32; 4]> {
    VIRIDIS
        .iter()
        .map(|c| {
            [
                srgb_to_linear(c[0]),
                srgb_to_linear(c[1]),
                srgb_to_linear(c[2]),
                1.0,
            ]
        })
        .collect()
}

/// The colour at `t` (clamped to [0, 1]) as 8-bit sRGB, interpolating the
/// linear stops exactly as `colormap_at` in `shaders/mesh.wgsl` does.
pub(crate) fn sample_srgb8(t: f32) -> [u8; 3] {
    let n = VIRIDIS.len();
    let x = if t.is_nan() { 0.0 } else { t.clamp(0.0, 1.0) } * (n - 1) as f32;
    let lo = (x.floor() as usize).min(n - 2);
    let f = x - lo as f32;
    let mut out = [0u8; 3];
    for (k, o) in out.iter_mut().enumerate() {
        let a = srgb_to_linear(VIRIDIS[lo][k]);
        let b = srgb_to_linear(VIRIDIS[lo + 1][k]);
        let lin = a + (b - a) * f;
        *o = (linear_to_srgb(lin) * 255.0).round().clamp(0.0, 255.0) as u8;
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ends_are_viridis_purple_and_yellow() {
        assert_eq!(sample_srgb8(0.0), [68, 1, 84]);
        assert_eq!(sample_srgb8(1.0), [253, 231, 37]);
        assert_eq!(sample_srgb8(-3.0), sample_srgb8(0.0));
        assert_eq!(sample_srgb8(7.0), sample_srgb8(1.0));
    }

    #[test]
    fn srgb_round_trip() {
        for i in 0..=255 {
            let c = i as f32 / 255.0;
            let back = linear_to_srgb(srgb_to_linear(c));
            assert!((back - c).abs() < 1e-5, "{i}: {back}");
        }
    }

    #[test]
    fn lightness_increases_monotonically() {
        // Viridis is designed with monotone lightness; check its luma.
        let luma = |c: [u8; 3]| 0.2126 * c[0] as f32 + 0.7152 * c[1] as f32 + 0.0722 * c[2] as f32;
        let mut prev = -1.0;
        for k in 0..=64 {
            let l = luma(sample_srgb8(k as f32 / 64.0));
            assert!(l > prev, "luma not increasing at {k}: {l} <= {prev}");
            prev = l;
        }
    }
}
