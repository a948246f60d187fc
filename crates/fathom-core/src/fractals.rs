//! Fractal primitives: distance estimators of escape-time and folding fractals, each declared
//! once with its parameters, returning a distance bound and an orbit trap for colouring.
//!
//! The orbit trap of every fractal here is the smallest `|z|` reached over the iterations.

use crate::real::{Mask, Real};
use crate::vec3::V3;

crate::declare_family! {
    /// A fractal distance estimator.
    family Fractal, noun "fractal", table FRACTALS;
    fn estimate(p: V3<S>) -> (S, S);

    /// The Mandelbulb (White and Nylander), classic acos/atan2 spherical form, with the
    /// running-derivative distance estimate `0.5 ln(r) r / dr`.
    Mandelbulb [Bound] (
        power: Scalar = 8.0, [2.0, 32.0], "exponent of the spherical power map",
        iterations: Int = 12.0, [1.0, 1000.0], "maximum iterations",
        bailout: Scalar = 2.0, [1.0, 1e3], "escape radius",
    ) => mandelbulb(p, power, iterations, bailout);
}

/// Mandelbulb estimate, written with masks so the packet path iterates every lane until all
/// have escaped while leaving escaped lanes untouched.
#[inline(always)]
fn mandelbulb<S: Real>(c: V3<S>, power: S, iterations: usize, bailout: S) -> (S, S) {
    let mut z = c;
    let mut dr = S::one();
    let mut r = z.length();
    let mut trap = r;
    let mut active = r.lt(bailout);
    for _ in 0..iterations {
        if !active.any() {
            break;
        }
        let safe_r = r.max(S::splat(1e-30));
        let theta = (z.z / safe_r).clamp(-S::one(), S::one()).acos() * power;
        let phi = z.y.atan2(z.x) * power;
        let rp1 = safe_r.powf(power - S::one());
        let ndr = rp1 * power * dr + S::one();
        let zr = rp1 * safe_r;
        let (st, ct) = theta.sin_cos();
        let (sp, cp) = phi.sin_cos();
        let nz = V3::new(zr * st * cp, zr * sp * st, zr * ct) + c;
        z = V3::select(active, nz, z);
        dr = S::select(active, ndr, dr);
        r = z.length();
        trap = S::select(active, trap.min(r), trap);
        active = active & r.lt(bailout);
    }
    let d = S::splat(0.5) * r.max(S::splat(1e-30)).ln() * r / dr;
    (d, trap)
}
