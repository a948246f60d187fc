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
    for _ in 0..iterations {
        if !active.any() {
            break;
        }
        let (nz, rp1) = step(z, r);
        let ndr = rp1 * power * dr + S::one();
        z = V3::select(active, nz, z);
        dr = S::select(active, ndr, dr);
        r = z.length();
        trap = S::select(active, trap.min(r), trap);
        active = active & r.lt(bailout);
    }
    let d = S::splat(0.5) * r.max(S::splat(1e-30)).ln() * r / dr;
    // A lane that never escaped is inside (at this depth): the formula means nothing there.
    (S::select(active, S::zero(), d), trap)
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
