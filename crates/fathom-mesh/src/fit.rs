//! Bounds fitted to a scene: an octree descent over a search cube keeps the cells the surface
//! may cross (the culling test), and the box of the survivors, padded by one of them, is the
//! mesh's bounds. A scene that reaches the search cube's faces (a floor plane, an unbounded
//! repetition) has no finite box here and is asked for `--bounds`.

use crate::IsoMeshError;
use fathom_core::scene::Scene;
use fathom_core::{Evaluator, Tape, V3};
use glam::DVec3;
use rayon::prelude::*;

/// Half side of the search cube. Kept small: escape-time estimators (the Mandelbulb's
/// `0.5 ln r r / dr`) overestimate far outside their bailout radius, which would cull the
/// object itself from a large search cube's first levels.
pub const SEARCH_HALF: f64 = 8.0;
/// Levels of the search: cells of `2 * SEARCH_HALF / 2^LEVELS`.
pub const LEVELS: u32 = 9;

/// The fitted box (min, max).
pub fn fit_bounds(_scene: &Scene, tape: &Tape) -> Result<(DVec3, DVec3), IsoMeshError> {
    let mut nodes = vec![DVec3::splat(-SEARCH_HALF)];
    let mut side = 2.0 * SEARCH_HALF;
    for _ in 0..LEVELS {
        side *= 0.5;
        let s = side;
        nodes = nodes
            .par_chunks(256)
            .flat_map_iter(|chunk| {
                let mut ev = Evaluator::<f64>::new();
                let mut out = Vec::new();
                for &lo in chunk {
                    for c in 0..8 {
                        let o = lo
                            + DVec3::new((c & 1) as f64, (c >> 1 & 1) as f64, (c >> 2 & 1) as f64)
                                * s;
                        let m = o + DVec3::splat(0.5 * s);
                        let d = ev.distance(tape, V3::new(m.x, m.y, m.z));
                        if d.abs() <= 0.5 * s * 3f64.sqrt() {
                            out.push(o);
                        }
                    }
                }
                out
            })
            .collect();
        if nodes.is_empty() {
            return Err(IsoMeshError::Bounds(format!(
                "the scene has no surface within +-{SEARCH_HALF}; give --bounds"
            )));
        }
        if nodes.len() > 4_000_000 {
            return Err(IsoMeshError::Bounds(
                "the scene's surface is too large to fit bounds automatically; give --bounds"
                    .into(),
            ));
        }
    }
    let lo = nodes.iter().fold(DVec3::splat(f64::MAX), |a, &b| a.min(b)) - DVec3::splat(side);
    let hi = nodes.iter().fold(DVec3::splat(f64::MIN), |a, &b| a.max(b)) + DVec3::splat(2.0 * side);
    if lo.min_element() <= -SEARCH_HALF || hi.max_element() >= SEARCH_HALF {
        return Err(IsoMeshError::Bounds(format!(
            "the scene reaches beyond +-{SEARCH_HALF} (a plane or an unbounded repetition?); \
             give --bounds x0,y0,z0,x1,y1,z1"
        )));
    }
    Ok((lo, hi))
}
