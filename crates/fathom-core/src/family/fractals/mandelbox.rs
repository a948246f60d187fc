//! The Mandelbox (Tom Lowe, "Tglad", 2010): each iteration box-folds every coordinate beyond
//! `folding_limit`, sphere-folds (scales by `fixed^2 / clamp(r^2, min^2, fixed^2)`), then
//! applies `z = scale z + c` with `c` the evaluated point. The running derivative `dr` follows
//! the sphere-fold factor and `|scale|`; the estimate is `|z| / dr`.

use crate::real::{Mask, Real};
use crate::vec3::V3;

/// Mandelbox estimate with masks (escaped lanes are left untouched). Returns (distance, trap).
#[inline(always)]
pub(super) fn mandelbox<S: Real>(
    c: V3<S>,
    scale: S,
    min_radius: S,
    fixed_radius: S,
    folding_limit: S,
    iterations: usize,
    bailout: S,
) -> (S, S) {
    let fixed2 = fixed_radius * fixed_radius;
    // A zero inner radius would divide by zero at the origin; 1e-6 is far below any detail.
    let min2 = (min_radius * min_radius).max(S::splat(1e-12));
    let abs_scale = scale.abs();
    let two = S::splat(2.0);
    let lim = V3::splat(folding_limit);
    let bail2 = bailout * bailout;
    let mut z = c;
    let mut dr = S::one();
    let mut r2 = z.length2();
    let mut trap = r2;
    let mut active = r2.lt(bail2);
    for _ in 0..iterations {
        if !active.any() {
            break;
        }
        // Box fold: reflect about +-limit whatever lies beyond it.
        let b = z.clamp(-lim, lim) * two - z;
        // Sphere fold; clamp(lo > hi) yields hi, so min > fixed means no fold at all.
        let f = fixed2 / b.length2().clamp(min2, fixed2);
        let nz = b * (f * scale) + c;
        let ndr = dr * f * abs_scale + S::one();
        z = V3::select(active, nz, z);
        dr = S::select(active, ndr, dr);
        r2 = z.length2();
        trap = S::select(active, trap.min(r2), trap);
        active = active & r2.lt(bail2);
    }
    (r2.sqrt() / dr, trap.sqrt())
}
