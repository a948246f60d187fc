//! The guard that stops a zoom cleanly where the octree's arithmetic runs out, instead of
//! rendering garbage.
//!
//! Box corners are exact relative to the anchor at any depth (`crate::octree`), the eye and the
//! anchor's world position are double-double, and deep frames evaluate the scene in
//! double-double: what bounds the depth is the anchor's own lattice (at most
//! [`MAX_ANCHOR_DEPTH`] levels, so its per-depth offsets stay exact in f64) plus the span below
//! it that stays exact near the eye ([`ANCHOR_SPAN`]), capped at [`MAX_DEPTH`] (2^-100 of the
//! root is 64 units in the last place of a double-double root coordinate).

use crate::octree::{ANCHOR_SPAN, MAX_ANCHOR_DEPTH, MAX_DEPTH};

/// The deepest octree level any frame can use.
pub const DEEPEST: u8 = if MAX_ANCHOR_DEPTH + ANCHOR_SPAN < MAX_DEPTH {
    MAX_ANCHOR_DEPTH + ANCHOR_SPAN
} else {
    MAX_DEPTH
};

/// Checks that an eye at distance `dist` (world) from the surface it looks at can still be
/// drawn: voxels of one pixel footprint (times `fidelity`) there must be no deeper than
/// [`DEEPEST`]. Returns the depth needed, or an error that says which limit is reached.
pub fn precision_check(
    dist: f64,
    root_size: f64,
    pixel_angle: f64,
    fidelity: f64,
    zoom: f64,
) -> Result<u32, String> {
    let footprint = dist / root_size * pixel_angle * fidelity;
    let need = (-footprint.log2()).ceil().max(0.0) as u32;
    if !footprint.is_finite() || footprint <= 0.0 || need > DEEPEST as u32 {
        return Err(format!(
            "precision limit reached at zoom {zoom:.3e}: voxels of one pixel would need octree \
             depth {need}, deeper than {DEEPEST} (the anchor's lattice stops at depth \
             {MAX_ANCHOR_DEPTH}, where its offsets are still exact in f64, and boxes stay exact \
             {ANCHOR_SPAN} levels below it; double-double evaluation resolves 2^-106 of a \
             root coordinate); stopping here rather than rendering garbage (see docs/svo.md)"
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
        // Zoom 1e15 at 640x480 needs about depth 60: fine now (f64 root units stopped at 48).
        assert_eq!(precision_check(1.5e-15, 2.0, 1.94e-3, 1.0, 1e15), Ok(60));
        let e = precision_check(1e-28, 4.0, 1e-3, 1.0, 1e28).unwrap_err();
        assert!(e.contains("precision limit") && e.contains("98"), "{e}");
        assert!(precision_check(0.0, 4.0, 1e-3, 1.0, 1e28).is_err());
    }
}
