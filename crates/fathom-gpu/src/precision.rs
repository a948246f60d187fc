//! Where f32 runs out. The GPU forms every point as `eye_hi + (eye_lo + dir * t)`: the camera's
//! f64 position is split into two f32s on the CPU, so the eye itself is carried to about 48
//! bits and moving the camera does not make the image jump. The point handed to the distance
//! function is still one f32 vector, though, so its spacing is `ulp(|p|) = |p| * 2^-23`. Once
//! the pixel footprint at the surface falls to a few ulps, neighbouring pixels evaluate the same
//! f32 point and the image turns blocky and jitters as the camera moves.
//!
//! The threshold is the CPU tracer's (`fathom-trace` switches to its f64 path at the same
//! place): a footprint below `DEEP_FOOTPRINT = 1e-5` times `max(|eye|, 1)`, about 80 ulps. For
//! the Mandelbulb at unit scale, a 480-pixel-high 40-degree view reaches it at a distance of
//! about 8e-3 from its target, a zoom of about 350 over the whole-bulb view (distance 2.8); past it the GPU
//! renderer refuses with [`crate::GpuError::TooDeep`] and the caller hands the frame to the CPU.

/// Relative pixel footprint below which f32 positions are not enough (same as fathom-trace).
pub const DEEP_FOOTPRINT: f64 = 1e-5;

/// Splits an f64 into an f32 and the f32 rounding of the remainder: `hi + lo` carries ~48 bits.
pub fn split(x: f64) -> (f32, f32) {
    let hi = x as f32;
    let lo = (x - hi as f64) as f32;
    (hi, lo)
}

/// Whether a view with pixel footprint `footprint` (at the target) from an eye at distance
/// `eye_dist` from the origin needs f64.
pub fn too_deep(footprint: f64, eye_dist: f64) -> bool {
    footprint < DEEP_FOOTPRINT * eye_dist.max(1.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn split_keeps_what_f32_alone_loses() {
        let x = 12_345.678_901_234_5_f64;
        let (hi, lo) = split(x);
        assert!(
            (x - hi as f64).abs() > 1e-4,
            "f32 alone is off by ~1e-4 here"
        );
        assert!((x - (hi as f64 + lo as f64)).abs() < 1e-9);
    }

    #[test]
    fn deep_threshold_scales_with_distance_from_origin() {
        assert!(!too_deep(1e-3, 3.0));
        assert!(too_deep(1e-6, 3.0));
        assert!(!too_deep(1e-4, 5.0));
        assert!(too_deep(1e-4, 1e4));
    }
}
