//! Fractal primitives: distance estimators of escape-time and folding fractals, each declared
//! once (in the single table below) with its parameters, returning a distance bound and an orbit
//! trap for colouring.
//!
//! The orbit trap of every fractal here is the smallest `|z|` reached by the iterated point,
//! counting the starting point, in the fractal's own (unscaled) iteration coordinates.
//!
//! - [`mandelbulb`]: the power-n Mandelbulb (trig form, and an exact trig-free power-8 path);
//! - [`mandelbox`]: Tglad's Mandelbox (box fold + sphere fold, `z = scale z + c`);
//! - [`ifs`]: the kaleidoscopic IFS family (Menger, Sierpinski, the polyhedral flakes) and
//!   the shared escape loop;
//! - [`koch`]: the Koch snowflake wire built by folding.
//!
//! Why the folding fractals are `Bound`: every fold used here (abs, sort, reflection across a
//! plane when on its wrong side) is continuous and 1-Lipschitz, rotations are isometries and the
//! scale step multiplies lengths by exactly `scale`, which the estimate divides back out. The
//! final shape (box, tetrahedron, polyhedron, segment) is itself a 1-Lipschitz bound, so the
//! composition is 1-Lipschitz, hence a bound on the distance to its own zero set — the fractal
//! at the given depth. The only departure is the bailout (a lane whose point left radius
//! `1e4` stops iterating): the value it returns is the estimate of a shallower level, which
//! differs by at most ~1e-4 relative; the Lipschitz test in [`tests`] measures it.

mod ifs;
mod koch;
mod mandelbox;
mod mandelbulb;
#[cfg(test)]
mod tests;

use crate::vec3::V3;

/// The range limit used for offsets.
const OFFSET_MAX: f64 = 10.0;

crate::declare_family! {
    /// A fractal distance estimator.
    family Fractal, noun "fractal", table FRACTALS;
    fn estimate(p: V3<S>) -> (S, S);

    /// The Mandelbulb (White and Nylander), classic acos/atan2 spherical form, with the
    /// running-derivative distance estimate `0.5 ln(r) r / dr` times `safety`. Near the
    /// surface of the set the iterations define (points that escape at the last iteration, or
    /// never: inside) it is `ln(r / bailout) r / dr` (no 0.5: a first-order distance), signed
    /// and zero on that surface, so the surface stays smooth at any zoom (inside it is held at
    /// -1e-6, `INSIDE_DEPTH`; the plain estimate never fell below ~7e-7 outside and read 0
    /// inside, a step whose normals were noise at zooms past ~1e6). At `power = 8` an exact
    /// trig-free form (repeated complex squaring) is used instead; it is the same map. The
    /// angle offsets (Mandelbulber's alpha and beta, in this colatitude convention) turn each
    /// iteration's angles before the power; at zero they leave the classic bulb.
    /// Not a strict bound: on random pairs `|f(a) - f(b)| / |a - b|` is heavy-tailed (about
    /// 1.4e-4 of pairs exceed 1 at safety 1, the worst seen grows with the sample: 13 in
    /// 600 000 pairs); the default `safety` 0.8 brings the exceeding fraction near 1e-4.
    Mandelbulb [Safety] (
        power: Scalar = 8.0, [2.0, 32.0], soft [2.0, 16.0], "exponent of the spherical power map",
        iterations: Int = 12.0, [1.0, 1000.0], soft [1.0, 24.0], "maximum iterations",
        bailout: Scalar = 4.0, [1.0, 1e3], soft [2.0, 256.0], "escape radius (below 4 the estimate degrades)",
        safety: Scalar = 0.8, [0.01, 1.0], soft [0.01, 1.0], "factor on the estimate (smaller: safer, slower)",
        azimuth_offset: Scalar = 0.0, [-360.0, 360.0], soft [-180.0, 180.0], "degrees added to the azimuth before it is multiplied by power",
        polar_offset: Scalar = 0.0, [-360.0, 360.0], soft [-180.0, 180.0], "degrees added to the polar angle (from +z) before it is multiplied by power",
    ) => {
        let (d, trap) = mandelbulb::mandelbulb(p, power, iterations, bailout, azimuth_offset, polar_offset);
        (d * safety, trap)
    };

    /// The Mandelbox (Tglad): per iteration a box fold (reflect each coordinate beyond
    /// `folding_limit`), a sphere fold (inversion between `min_radius` and `fixed_radius`), then
    /// `z = scale z + p`, tracking the running derivative; estimate `safety |z| / |dr|`.
    /// The default scale -1.5 fits inside `|x|, |y|, |z| < 2.2`.
    /// Not a strict bound: `|z| / dr` overestimates by up to ~2.6x (worst of 600 000 random
    /// pairs); about 4e-3 of pairs exceed ratio 1 at safety 1, 2e-4 exceed 1/0.6.
    Mandelbox [Safety] (
        scale: Scalar = -1.5, [-4.0, 4.0], soft [-4.0, 4.0], "scale of each iteration (classic: 2 or -1.5)",
        min_radius: Scalar = 0.5, [0.0, 4.0], soft [0.0, 4.0], "inner radius of the sphere fold",
        fixed_radius: Scalar = 1.0, [0.01, 4.0], soft [0.01, 4.0], "outer radius of the sphere fold",
        folding_limit: Scalar = 1.0, [0.0, 4.0], soft [0.0, 4.0], "half-width of the box fold",
        iterations: Int = 12.0, [1.0, 1000.0], soft [1.0, 24.0], "maximum iterations",
        bailout: Scalar = 1000.0, [2.0, 1e6], soft [2.0, 10000.0], "escape radius",
        safety: Scalar = 0.6, [0.01, 1.0], soft [0.01, 1.0], "factor on the estimate (smaller: safer, slower)",
    ) => {
        let (d, trap) = mandelbox::mandelbox(p, scale, min_radius, fixed_radius, folding_limit, iterations, bailout);
        (d * safety, trap)
    };

    /// The Menger sponge of the cube `[-1, 1]^3` as a kaleidoscopic IFS (Knighty, as in
    /// Fragmentarium): abs and sort folds, scale about `offset`, the middle cut along z; the
    /// estimate is the box distance of the final point divided by `scale^n`.
    Menger [Bound] (
        iterations: Int = 6.0, [0.0, 1000.0], soft [0.0, 20.0], "depth of the sponge",
        scale: Scalar = 3.0, [1.0, 10.0], soft [1.0, 10.0], "contraction factor (3: the Menger sponge)",
        offset: Vec3 = [1.0, 1.0, 1.0], [-OFFSET_MAX, OFFSET_MAX], soft [-10.0, 10.0], "corner the copies scale towards",
    ) => ifs::menger(p, iterations, scale, offset);

    /// The Sierpinski tetrahedron on the vertices (1,1,1), (-1,-1,1), (1,-1,-1), (-1,1,-1):
    /// plane folds `x+y<0`, `x+z<0`, `y+z<0`, scale about `offset`; the estimate is the
    /// tetrahedron distance bound of the final point divided by `scale^n`.
    Sierpinski [Bound] (
        iterations: Int = 10.0, [0.0, 1000.0], soft [0.0, 20.0], "depth",
        scale: Scalar = 2.0, [1.0, 10.0], soft [1.0, 10.0], "contraction factor (2: the Sierpinski tetrahedron)",
        offset: Vec3 = [1.0, 1.0, 1.0], [-OFFSET_MAX, OFFSET_MAX], soft [-10.0, 10.0], "vertex the copies scale towards",
    ) => ifs::sierpinski(p, iterations, scale, offset);

    /// The Koch snowflake as a wire: three Koch curves on an equilateral triangle (circumradius
    /// 2/sqrt 3, in the xy plane), folded onto one curve, which is folded onto its right quarter
    /// each generation (mirror in x, then the 60-degree mirror through (1/3, 0)); `twist` turns
    /// each generation about its own axis, making a space curve. The estimate is the distance to
    /// the depth-n polyline (exact at twist 0) minus a tube radius of `thickness` finest
    /// half-segments.
    Koch [Bound] (
        iterations: Int = 5.0, [0.0, 1000.0], soft [0.0, 20.0], "generations of the curve",
        twist: Scalar = 0.0, [-360.0, 360.0], soft [-180.0, 180.0], "degrees each generation turns about its axis (0: planar)",
        thickness: Scalar = 0.15, [0.0, 1.0], soft [0.0, 1.0], "tube radius, as a fraction of the finest half-segment",
    ) baked(koch::bake_koch) (iterations: Int, twist_cos: Scalar, twist_sin: Scalar, thickness: Scalar)
        => koch::koch(p, iterations, twist_cos, twist_sin, thickness);

    /// Knighty's kaleidoscopic IFS with octahedral symmetry: abs and sort folds, rotation by
    /// `rotation` (Euler angles in degrees, about x then y then z), scale about `offset`; the
    /// estimate is the distance bound of the unit octahedron divided by `scale^n`. The defaults
    /// give the octahedron flake (six half-size copies at the vertices).
    KifsOctahedron [Bound] (
        iterations: Int = 10.0, [0.0, 1000.0], soft [0.0, 20.0], "depth",
        scale: Scalar = 2.0, [1.0, 10.0], soft [1.0, 10.0], "contraction factor",
        offset: Vec3 = [1.0, 0.0, 0.0], [-OFFSET_MAX, OFFSET_MAX], soft [-10.0, 10.0], "point the copies scale towards",
        rotation: Vec3 = [0.0, 0.0, 0.0], [-360.0, 360.0], soft [-180.0, 180.0], "Euler angles (degrees) applied each iteration",
    ) baked(ifs::bake_kifs) (iterations: Int, scale: Scalar, offset: Vec3, r0: Vec3, r1: Vec3, r2: Vec3)
        => ifs::kifs_octahedron(p, iterations, scale, offset, [r0, r1, r2]);

    /// Knighty's kaleidoscopic IFS with icosahedral symmetry (the 120 reflections of H3, folded
    /// as abs(x), abs(y) and one oblique mirror, five times), rotation, scale about `offset`; the
    /// estimate is the distance bound of the unit icosahedron divided by `scale^n`. The defaults
    /// (scale 1 + golden ratio, offset a vertex) give the icosahedron flake.
    KifsIcosahedron [Bound] (
        iterations: Int = 8.0, [0.0, 1000.0], soft [0.0, 20.0], "depth",
        scale: Scalar = 2.618033988749895, [1.0, 10.0], soft [1.0, 10.0], "contraction factor",
        offset: Vec3 = [0.5257311121191336, 0.0, 0.8506508083520399], [-OFFSET_MAX, OFFSET_MAX], soft [-10.0, 10.0], "point the copies scale towards",
        rotation: Vec3 = [0.0, 0.0, 0.0], [-360.0, 360.0], soft [-180.0, 180.0], "Euler angles (degrees) applied each iteration",
    ) baked(ifs::bake_kifs) (iterations: Int, scale: Scalar, offset: Vec3, r0: Vec3, r1: Vec3, r2: Vec3)
        => ifs::kifs_icosahedral(p, iterations, scale, offset, [r0, r1, r2], ifs::DODECA_VERTEX);

    /// Knighty's kaleidoscopic IFS with icosahedral symmetry whose copies sit at the vertices of
    /// a dodecahedron; the estimate is the distance bound of the unit dodecahedron divided by
    /// `scale^n`. The defaults (scale 2 + golden ratio, offset a vertex) give the dodecahedron
    /// flake.
    KifsDodecahedron [Bound] (
        iterations: Int = 6.0, [0.0, 1000.0], soft [0.0, 20.0], "depth",
        scale: Scalar = 3.618033988749895, [1.0, 10.0], soft [1.0, 10.0], "contraction factor",
        offset: Vec3 = [0.0, 0.35682208977308993, 0.9341723589627157], [-OFFSET_MAX, OFFSET_MAX], soft [-10.0, 10.0], "point the copies scale towards",
        rotation: Vec3 = [0.0, 0.0, 0.0], [-360.0, 360.0], soft [-180.0, 180.0], "Euler angles (degrees) applied each iteration",
    ) baked(ifs::bake_kifs) (iterations: Int, scale: Scalar, offset: Vec3, r0: Vec3, r1: Vec3, r2: Vec3)
        => ifs::kifs_icosahedral(p, iterations, scale, offset, [r0, r1, r2], ifs::ICO_VERTEX);
}
