//! A careful reference tracer for small images at any zoom depth: per pixel, one ray marched in
//! double-double ([`Dd`]) from a double-double eye, returning the hit distance. Slow (one scalar
//! double-double evaluation per step, small steps), meant as the reference that deep frames of
//! the other renderers are checked against (silhouette IoU, depths), not for display.
//!
//! **The march.** The ray leaves the eye (double-double) along the camera's f64 unit ray
//! direction ([`fathom_core::CameraFrame::ray_dir`]); positions are `eye + dir t` in
//! double-double with `t` an f64 distance (relative precision 1e-16 of the distance travelled
//! is plenty; what must be exact is the position, whose coordinates may be ~1 while the view is
//! 1e-20 wide). With the pixel footprint `fp(t) = pixel_angle * max(t, near)`:
//!
//! - **step** `min(d, step_footprints * fp(t))` (half a footprint by default): the distance
//!   estimate `d` alone may overshoot thin features where it is not a bound (the Mandelbulb's
//!   and the Mandelbox's estimates are not), so the ray also samples every half pixel of its
//!   length and cannot jump over anything a pixel wide;
//! - **hit** when `d <= 0` (inside; NaN too) or `d < hit_footprints * fp(t)`, half a
//!   footprint by default: the ordinary tracer's rule at `pixel_epsilon = 1`, and the
//!   resolution of every renderer that draws a pixel per voxel or per ray. A stricter rule sees
//!   through holes smaller than a pixel that those renderers draw as surface: with a thousandth
//!   of a footprint, the menger preset at 48x36 has 889 hit pixels against the ordinary
//!   tracer's 944 (IoU 0.94). The rule scales with the view, so a view scaled by `s` about a
//!   fixed point of the fractal gives depths scaled by `s`. For the Mandelbulb the estimate
//!   just outside its set is ~7e-7 of the view scale at the zoom target (`docs/svo.md`, "The
//!   Mandelbulb zoom target"), so at deep zoom a ray stops either inside the set (`d == 0`) or
//!   on the footprint rule;
//! - **miss** beyond `far` or when the step budget runs out.
//!
//! The march is generic over [`Real`] ([`march_depths`]) so the same rule can run in f64, which
//! is how the tests show what double-double buys. Rows run in parallel (rayon).
//! [`zoom_frame_depths`] is the reference for frame `i` of a zoom path.

use fathom_core::camera_path::CameraPath;
use fathom_core::dd::{Dd, dd3};
use fathom_core::real::Real;
use fathom_core::{Camera, Evaluator, Tape, V3};
use glam::DVec3;
use rayon::prelude::*;

/// How the reference tracer marches.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DeepOptions {
    /// Rays miss beyond this distance from the eye (world units).
    pub far: f64,
    /// Below this distance the footprint is taken as that at `near` (so steps near the eye are
    /// not vanishingly small).
    pub near: f64,
    /// Step budget per ray; a ray that runs out counts as a miss.
    pub max_steps: u32,
    /// Largest step, in pixel footprints.
    pub step_footprints: f64,
    /// Hit threshold, in pixel footprints.
    pub hit_footprints: f64,
}

impl DeepOptions {
    /// Options for a view of size `scale` (the eye's distance to what it looks at): misses
    /// beyond `100 scale`, footprints measured from `scale / 100`, half-footprint steps, hits
    /// within half a footprint, 20 000 steps.
    pub fn for_scale(scale: f64) -> DeepOptions {
        DeepOptions {
            far: 100.0 * scale,
            near: 0.01 * scale,
            max_steps: 20_000,
            step_footprints: 0.5,
            hit_footprints: 0.5,
        }
    }
}

/// Hit distances (`None`: miss) of a `width` x `height` image, row-major from the top left,
/// marched in double-double from `eye`. `camera` gives only the orientation and field of view
/// (its own `eye` is ignored: a camera in target-relative coordinates, such as
/// [`fathom_core::camera_path::CameraPath::deep_camera`] returns, is exact at any depth).
pub fn deep_depths(
    tape: &Tape,
    eye: V3<Dd>,
    camera: &Camera,
    width: u32,
    height: u32,
    opts: &DeepOptions,
) -> Vec<Option<f64>> {
    march_depths::<Dd>(tape, eye, camera, width, height, opts)
}

/// The reference depths of frame `i` of `frames` of a zoom `path` to `depth` (vertical field
/// of view `fov` degrees): [`deep_depths`] from the frame's double-double eye with the exact
/// target-relative orientation of [`CameraPath::deep_camera`], options
/// [`DeepOptions::for_scale`] of the eye's distance to the target. `None` for tours.
#[allow(clippy::too_many_arguments)]
pub fn zoom_frame_depths(
    tape: &Tape,
    path: &CameraPath,
    i: usize,
    frames: usize,
    depth: f64,
    fov: f64,
    width: u32,
    height: u32,
) -> Option<Vec<Option<f64>>> {
    let (eye, cam) = path.deep_camera(i, frames, depth, fov)?;
    let opts = DeepOptions::for_scale(cam.eye.length());
    Some(deep_depths(tape, eye, &cam, width, height, &opts))
}

/// [`deep_depths`] in f64 from an f64 eye: the same march without the extra precision.
pub fn f64_depths(
    tape: &Tape,
    eye: DVec3,
    camera: &Camera,
    width: u32,
    height: u32,
    opts: &DeepOptions,
) -> Vec<Option<f64>> {
    march_depths::<f64>(tape, eye.into(), camera, width, height, opts)
}

/// The march of [`deep_depths`] in any scalar type `S` (one lane).
pub fn march_depths<S: Real>(
    tape: &Tape,
    eye: V3<S>,
    camera: &Camera,
    width: u32,
    height: u32,
    opts: &DeepOptions,
) -> Vec<Option<f64>> {
    assert_eq!(S::LANES, 1, "march_depths marches one ray at a time");
    let frame = camera.frame();
    let pixel_angle = frame.pixel_angle(height);
    let rows: Vec<Vec<Option<f64>>> = (0..height)
        .into_par_iter()
        .map_init(Evaluator::<S>::new, |ev, y| {
            (0..width)
                .map(|x| {
                    let dir = frame.ray_dir(x as f64 + 0.5, y as f64 + 0.5, width, height);
                    march_ray(ev, tape, eye, dir, pixel_angle, opts)
                })
                .collect()
        })
        .collect();
    rows.into_iter().flatten().collect()
}

/// One ray of [`march_depths`].
fn march_ray<S: Real>(
    ev: &mut Evaluator<S>,
    tape: &Tape,
    eye: V3<S>,
    dir: DVec3,
    pixel_angle: f64,
    opts: &DeepOptions,
) -> Option<f64> {
    let mut t = 0.0f64;
    for _ in 0..opts.max_steps {
        let ts = S::splat(t);
        let p = V3::new(
            eye.x + ts * S::splat(dir.x),
            eye.y + ts * S::splat(dir.y),
            eye.z + ts * S::splat(dir.z),
        );
        let d = ev.distance(tape, p).lane(0);
        if d.is_nan() || d <= 0.0 {
            return Some(t);
        }
        let footprint = pixel_angle * t.max(opts.near);
        if d < opts.hit_footprints * footprint {
            return Some(t);
        }
        t += d.min(opts.step_footprints * footprint);
        if t > opts.far {
            return None;
        }
    }
    None
}

/// The double-double eye of an f64 camera, for shallow views.
pub fn eye_of(camera: &Camera) -> V3<Dd> {
    dd3(camera.eye)
}

/// Silhouette intersection over union of two depth images of the same size: pixels both hit
/// over pixels either hits (1 when neither hits anything).
pub fn silhouette_iou(a: &[Option<f64>], b: &[Option<f64>]) -> f64 {
    assert_eq!(a.len(), b.len(), "depth images differ in size");
    let (mut inter, mut union) = (0usize, 0usize);
    for (x, y) in a.iter().zip(b) {
        inter += (x.is_some() && y.is_some()) as usize;
        union += (x.is_some() || y.is_some()) as usize;
    }
    if union == 0 {
        1.0
    } else {
        inter as f64 / union as f64
    }
}

#[cfg(test)]
mod tests;
