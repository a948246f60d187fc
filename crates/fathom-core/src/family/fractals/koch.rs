//! The Koch snowflake as a wire, by folding.
//!
//! Construction. The snowflake is three Koch curves on the edges of an equilateral triangle
//! centred at the origin in the xy plane, with vertices at angles 30, 150 and 270 degrees and
//! circumradius `2/sqrt 3`; the top edge runs from (-1, 1/sqrt 3) to (1, 1/sqrt 3).
//! 1. Snowflake fold: `x = |x|`, the mirror across the 30-degree line through the origin, and
//!    `x = |x|` again bring every point to the sector of the top edge; shifting by
//!    `-1/sqrt 3` in y puts that edge's curve on the segment from (-1, 0) to (1, 0).
//! 2. Each generation: the Koch curve over [-1, 1] is four copies at 1/3 scale, symmetric about
//!    x = 0, and its right half is two copies mirrored across the line through (1/3, 0) at
//!    60 degrees. So `x = |x|`, mirror onto the side of (1, 0), and map the copy over
//!    [1/3, 1] back to the whole with `p = 3 p - (2, 0, 0)`; then turn by `twist` about the
//!    x axis (the curve's own axis), which makes each generation bend out of the previous
//!    generation's plane.
//! 3. The base shape is the segment [-1, 1] on the x axis; the estimate is its distance
//!    minus `thickness`, divided by `3^n`.
//!
//! At `twist = 0` the mirrors never cut a copy (every copy lies in the 30-degree double cone
//! around its segment, on its own side of each mirror), so the estimate is the exact distance
//! to the depth-n polyline minus the tube radius; the tests check this against the explicit
//! polyline. With a twist the folds are the same continuous 1-Lipschitz maps, so it stays a
//! bound (checked by the Lipschitz tests).

use super::ifs::ifs_loop;
use crate::real::Real;
use crate::vec3::V3;

const SQRT3_2: f64 = 0.866_025_403_784_438_6;
const INV_SQRT3: f64 = 0.577_350_269_189_625_8;

/// User parameters (iterations, twist in degrees, thickness) to the buffer layout
/// (iterations, cos twist, sin twist, thickness).
pub(super) fn bake_koch(user: &[f64], out: &mut Vec<f64>) {
    let (s, c) = user[1].to_radians().sin_cos();
    out.extend_from_slice(&[user[0], c, s, user[2]]);
}

/// Mirrors `(x, y)` across the line through `(x0, 0)` with unit normal `(nx, ny)` when the point
/// lies on the negative side.
#[inline(always)]
fn mirror<S: Real>(x: S, y: S, x0: f64, nx: f64, ny: f64) -> (S, S) {
    let (nx, ny) = (S::splat(nx), S::splat(ny));
    let t = ((x - S::splat(x0)) * nx + y * ny).min(S::zero());
    let t2 = t + t;
    (x - t2 * nx, y - t2 * ny)
}

/// Koch snowflake estimate. Returns (distance, orbit trap).
#[inline(always)]
pub(super) fn koch<S: Real>(
    p: V3<S>,
    iterations: usize,
    twist_cos: S,
    twist_sin: S,
    thickness: S,
) -> (S, S) {
    // 1. Snowflake fold onto the top edge, then shift that edge onto the x axis.
    let (x, y) = mirror(p.x.abs(), p.y, 0.0, -0.5, SQRT3_2);
    let q = V3::new(x.abs(), y - S::splat(INV_SQRT3), p.z);
    let planar = twist_sin.lane(0) == 0.0 && twist_cos.lane(0) > 0.0;
    let three = S::splat(3.0);
    let two = S::splat(2.0);
    ifs_loop(
        q,
        iterations,
        three,
        |z| {
            // 2. One generation: mirror in x, the 60-degree mirror through (1/3, 0), rescale.
            let (x, y) = mirror(z.x.abs(), z.y, 1.0 / 3.0, SQRT3_2, -0.5);
            let (x, y, zz) = (x * three - two, y * three, z.z * three);
            if planar {
                V3::new(x, y, zz)
            } else {
                V3::new(
                    x,
                    twist_cos * y - twist_sin * zz,
                    twist_sin * y + twist_cos * zz,
                )
            }
        },
        // 3. Distance to the segment [-1, 1] x {0} x {0}, minus the tube radius.
        |z| {
            let dx = (z.x.abs() - S::one()).max(S::zero());
            (dx * dx + z.y * z.y + z.z * z.z).sqrt() - thickness
        },
    )
}
