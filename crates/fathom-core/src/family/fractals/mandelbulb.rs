//! The Mandelbulb: `z -> z^power + c` in spherical coordinates (polar angle from +z via acos,
//! azimuth via atan2), with the running-derivative distance estimate `0.5 ln(r) r / dr`.
//!
//! Two iteration kernels compute the same map:
//! - [`step_trig`] for any power: acos, atan2, one powf and two sin_cos per iteration;
//! - [`step_pow8`] for power 8, trig-free: with `rho = sqrt(x^2 + y^2)`,
//!   `(z + i rho)^8 = r^8 (cos 8 theta + i sin 8 theta)` and
//!   `((x + i y) / rho)^8 = cos 8 phi + i sin 8 phi`, each by three complex squarings, so
//!   `z' = (Im A * Re U, Im A * Im U, Re A) + c`. Two square roots and one division replace five
//!   transcendental calls.
//!
//! The kernel is chosen once per call by comparing the `power` parameter (every lane shares it).

use crate::real::{Mask, Real};
use crate::shared::INSIDE_DEPTH;
use crate::vec3::V3;

/// One trig-form iteration: returns the new point (before the masked update) and `r^(power-1)`.
#[inline(always)]
fn step_trig<S: Real>(z: V3<S>, r: S, power: S, c: V3<S>, offsets: (S, S)) -> (V3<S>, S) {
    let safe_r = r.max(S::splat(1e-30));
    let theta = ((z.z / safe_r).clamp(-S::one(), S::one()).acos() + offsets.1) * power;
    let phi = (z.y.atan2(z.x) + offsets.0) * power;
    let rp1 = safe_r.powf(power - S::one());
    let zr = rp1 * safe_r;
    let (st, ct) = theta.sin_cos();
    let (sp, cp) = phi.sin_cos();
    (V3::new(zr * st * cp, zr * sp * st, zr * ct) + c, rp1)
}

/// `(re + i im)^2`.
#[inline(always)]
fn csq<S: Real>(re: S, im: S) -> (S, S) {
    (re * re - im * im, (re + re) * im)
}

/// `(re + i im)^8` by three squarings.
#[inline(always)]
fn cpow8<S: Real>(re: S, im: S) -> (S, S) {
    let (a, b) = csq(re, im);
    let (a, b) = csq(a, b);
    csq(a, b)
}

/// One power-8 iteration without trigonometry; returns the new point and `r^7`.
/// Where `rho = 0` (on the z axis) the azimuth is taken as 0, as `atan2(0, 0)` does.
#[inline(always)]
fn step_pow8<S: Real>(z: V3<S>, r: S, c: V3<S>) -> (V3<S>, S) {
    let rho2 = z.x * z.x + z.y * z.y;
    let rho = rho2.sqrt();
    let tiny = S::splat(1e-30);
    let on_axis = rho.le(tiny);
    let inv = S::one() / rho.max(tiny);
    let ux = S::select(on_axis, S::one(), z.x * inv);
    let uy = S::select(on_axis, S::zero(), z.y * inv);
    let (are, aim) = cpow8(z.z, rho);
    let (ure, uim) = cpow8(ux, uy);
    let r2 = r * r;
    let r7 = r2 * r2 * r2 * r;
    (V3::new(aim * ure, aim * uim, are) + c, r7)
}

/// Mandelbulb estimate, written with masks so the packet path iterates every lane until all
/// have escaped while leaving escaped lanes untouched. Returns (distance, orbit trap).
#[inline(always)]
pub(super) fn mandelbulb<S: Real>(
    c: V3<S>,
    power: S,
    iterations: usize,
    bailout: S,
    azimuth_offset: S,
    polar_offset: S,
) -> (S, S) {
    let no_offsets = azimuth_offset.lane(0) == 0.0 && polar_offset.lane(0) == 0.0;
    if power.lane(0) == 8.0 && no_offsets {
        iterate(c, iterations, bailout, S::splat(8.0), |z, r| {
            step_pow8(z, r, c)
        })
    } else {
        let deg = S::splat(std::f64::consts::PI / 180.0);
        let offsets = (azimuth_offset * deg, polar_offset * deg);
        iterate(c, iterations, bailout, power, |z, r| {
            step_trig(z, r, power, c, offsets)
        })
    }
}

/// The shared escape loop; `step(z, r)` returns the next point and `r^(power-1)`.
///
/// The estimate is the running-derivative one, `0.5 ln(r) r / dr`, except near the surface
/// of the set the `iterations` define, where it is `ln(r / bailout) r / dr`: for points that
/// escape at the last iteration (outside, positive) and points that never escape (inside,
/// negative, down to [`INSIDE_DEPTH`]). Why: `0.5 ln(r) r / dr` estimates the distance to the
/// limit set and never falls below about `0.5 ln(bailout) bailout / dr` (7e-7 for the
/// preset's 12 iterations), so at zooms past ~1e6 every point near the surface read either
/// that floor or 0, the surface was a step between them and its normals were noise (rings in
/// the traced frames, a checker of voxels in the octree's). The set of points that do not
/// escape in `iterations` steps is `r_N < bailout` (past the bailout an orbit only grows, so
/// no earlier iterate escaped either), and `ln(r_N / B) r_N / dr_N ~ (r_N - B) / dr_N` is its
/// first-order distance with `dr` for the gradient of `r_N`: zero on the surface, continuous
/// and signed across it, at any depth. No 0.5 here: that factor bounds the distance to the
/// limit set, and halving a first-order distance only moves the surface the octree and the
/// tracers see out by the extra margin. Across the contour where escapes move from the
/// second-to-last to the last iteration the estimate rises by about 7/4 (`ln(B^7)` against
/// `0.5 ln(B^8)` with `r ~ B^8`), a thin band of overestimate like those `Safety` allows;
/// earlier iterations keep the plain estimate, whose contours lie outside the set.
#[inline(always)]
fn iterate<S: Real>(
    c: V3<S>,
    iterations: usize,
    bailout: S,
    power: S,
    step: impl Fn(V3<S>, S) -> (V3<S>, S),
) -> (S, S) {
    let mut z = c;
    let mut dr = S::one();
    let mut r = z.length();
    let mut trap = r;
    let mut active = r.lt(bailout);
    // Lanes that escape at the last iteration (with no iterations, the ball is the set).
    let mut last = if iterations == 0 {
        !active
    } else {
        active & !active
    };
    for i in 0..iterations {
        if !active.any() {
            break;
        }
        let (nz, rp1) = step(z, r);
        let ndr = rp1 * power * dr + S::one();
        z = V3::select(active, nz, z);
        dr = S::select(active, ndr, dr);
        r = z.length();
        trap = S::select(active, trap.min(r), trap);
        let stays = active & r.lt(bailout);
        if i + 1 == iterations {
            last = active & !stays;
        }
        active = stays;
    }
    let r = r.max(S::splat(1e-30));
    let near = active | last;
    // One logarithm: of r / B near the surface, of r (halved) elsewhere.
    let l = (r / S::select(near, bailout, S::one())).ln();
    // ln(r / B) = ln(1 + x) with x = (r - B) / B formed exactly: deep in a zoom x is far
    // below the precision of `ln` near 1 (f64-accurate even in double-double), so small x
    // take the series, whose first dropped term is below 1e-12 of it there.
    let x = (r - bailout) / bailout;
    let third = S::splat(1.0 / 3.0);
    let series = x * (S::one() - x * (S::splat(0.5) - x * (third - x * S::splat(0.25))));
    let l = S::select(near & x.abs().lt(S::splat(1e-3)), series, l);
    let d = S::select(near, l, S::splat(0.5) * l) * r / dr;
    // Inside, the first-order distance means something only near the surface: deeper in it
    // follows `dr`, which can be small and change fast, so it is held at `-INSIDE_DEPTH`.
    (S::select(active, d.max(S::splat(-INSIDE_DEPTH)), d), trap)
}

/// Test access to the two kernels, to check that they agree.
#[cfg(test)]
pub(super) fn steps_for_test(z: V3<f64>, c: V3<f64>) -> (V3<f64>, V3<f64>) {
    let r = z.length();
    (step_trig(z, r, 8.0, c, (0.0, 0.0)).0, step_pow8(z, r, c).0)
}

/// The trig form forced at power 8, to compare whole estimates with the fast path.
#[cfg(test)]
pub(super) fn mandelbulb_trig_for_test(c: V3<f64>, iterations: usize, bailout: f64) -> (f64, f64) {
    iterate(c, iterations, bailout, 8.0, |z, r| {
        step_trig(z, r, 8.0, c, (0.0, 0.0))
    })
}
