//! The guard that stops a zoom cleanly at the limit of f64 precision of root-unit coordinates,
//! instead of rendering garbage.

use crate::octree::MAX_DEPTH;

/// Checks that an eye at distance `dist` (world) from the nearest surface can still be drawn
/// with f64 root-unit coordinates: the voxels it needs must be no deeper than [`MAX_DEPTH`].
/// Returns the depth needed, or an error that says the precision limit is reached.
pub fn precision_check(
    dist: f64,
    root_size: f64,
    pixel_angle: f64,
    fidelity: f64,
    zoom: f64,
) -> Result<u32, String> {
    let footprint = dist / root_size * pixel_angle * fidelity;
    let need = (-footprint.log2()).ceil().max(0.0) as u32;
    if !footprint.is_finite() || footprint <= 0.0 || need > MAX_DEPTH as u32 {
        return Err(format!(
            "f64 precision limit reached at zoom {zoom:.3e}: voxels of one pixel would need octree \
             depth {need}, deeper than {MAX_DEPTH} (2^-{MAX_DEPTH} of the root is 32 ulps of a root \
             coordinate); stopping here rather than rendering garbage (see docs/svo.md)"
        ));
    }
    Ok(need)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn precision_guard_says_so() {
        assert!(precision_check(1.0, 4.0, 1e-3, 1.0, 1.0).is_ok());
        let e = precision_check(1e-13, 4.0, 1e-3, 1.0, 1e13).unwrap_err();
        assert!(e.contains("precision limit"), "{e}");
    }
}
