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
//!   fixed point of the fractal gives depths scaled by `s`. The Mandelbulb's estimate is
//!   signed and first-order at its surface at any depth (`fractals/mandelbulb.rs`), so deep
//!   rays stop on the footprint rule near it, or inside after an overestimated step;
//! - **miss** beyond `far` or when the step budget runs out.
//!
//! The march is generic over [`Real`] ([`march_depths`]) so the same rule can run in f64, which
//! is how the tests show what double-double buys. Rows run in parallel (rayon).
//! [`zoom_frame_depths`] is the reference for frame `i` of a zoom path.
//!
//! **Rays a pixel.** One ray samples the pixel's centre. A frame compared with it that
//! averages more (the octree frame reduced by 8 for the zoom's comparison is a mean of 64 rays
//! a pixel) differs from it wherever detail is finer than a pixel, even where both are right:
//! on deep Menger frames the tracer's own 8x8 block means score an SSIM of 0.58 against its
//! centre samples and 0.85 against means of 2x2. [`DeepOptions::pixel_samples`] casts `n` x
//! `n` rays a pixel, each marched with the whole pixel's footprint (so each ray steps and stops
//! as one ray a pixel does; the cost grows by `n^2`).
//!
//! **Shaded.** [`deep_frame`] colours each hit as the ordinary tracer does, with the same
//! code run in double-double ([`crate::shade::shade_hits`], [`crate::render::post_params`]):
//! normals, materials, AO, lights (soft shadows when the scene has them), sky, fog. At shallow
//! views it matches the tracer's frame (mean display-colour difference below 0.01); past
//! double precision it is the only valid reference for the colours of deep frames
//! ([`zoom_frame`]).

use crate::render::post_params;
use crate::shade::{Shaded, Shading, shade_hits};
use fathom_core::camera_path::CameraPath;
use fathom_core::dd::{Dd, dd3};
use fathom_core::frame::{Frame, NO_ID, Rect};
use fathom_core::real::Real;
use fathom_core::{Camera, CameraFrame, Evaluator, Scene, Tape, V3};
use fathom_image::compare::covers;
use fathom_image::post;
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
    /// Rays per pixel side, [1, [`MAX_PIXEL_SAMPLES`]]: `n` x `n` rays on a regular grid
    /// inside the pixel, each marched with the pixel's own footprint (so `n` multiplies the
    /// cost by about `n^2`, not more). The pixel's colour is their mean; it is a hit, at the
    /// nearest of their depths, when at least half of them hit (the rule of the octree
    /// frame's block reduction, `fathom_image::compare::reduce`).
    pub pixel_samples: u32,
}

/// Most rays per pixel side of [`DeepOptions::pixel_samples`].
pub const MAX_PIXEL_SAMPLES: u32 = 4;

impl DeepOptions {
    /// Options for a view of size `scale` (the eye's distance to what it looks at): misses
    /// beyond `100 scale`, footprints measured from `scale / 100`, half-footprint steps, hits
    /// within half a footprint, 20 000 steps, one ray a pixel.
    pub fn for_scale(scale: f64) -> DeepOptions {
        DeepOptions {
            far: 100.0 * scale,
            near: 0.01 * scale,
            max_steps: 20_000,
            step_footprints: 0.5,
            hit_footprints: 0.5,
            pixel_samples: 1,
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
                    let rays = pixel_rays(&frame, x, y, width, height, opts.pixel_samples);
                    let hits = rays.map(|dir| march_ray(ev, tape, eye, dir, pixel_angle, opts).0);
                    covered_depth(hits)
                })
                .collect()
        })
        .collect();
    rows.into_iter().flatten().collect()
}

/// One ray of [`march_depths`]: the hit distance and the distance evaluations spent.
fn march_ray<S: Real>(
    ev: &mut Evaluator<S>,
    tape: &Tape,
    eye: V3<S>,
    dir: DVec3,
    pixel_angle: f64,
    opts: &DeepOptions,
) -> (Option<f64>, u32) {
    let mut t = 0.0f64;
    for step in 1..=opts.max_steps {
        let ts = S::splat(t);
        let p = V3::new(
            eye.x + ts * S::splat(dir.x),
            eye.y + ts * S::splat(dir.y),
            eye.z + ts * S::splat(dir.z),
        );
        let d = ev.distance(tape, p).lane(0);
        if d.is_nan() || d <= 0.0 {
            return (Some(t), step);
        }
        let footprint = pixel_angle * t.max(opts.near);
        if d < opts.hit_footprints * footprint {
            return (Some(t), step);
        }
        t += d.min(opts.step_footprints * footprint);
        if t > opts.far {
            return (None, step);
        }
    }
    (None, opts.max_steps)
}

/// The directions of pixel (`x`, `y`)'s rays: `n` x `n` (`n` clamped to
/// [1, [`MAX_PIXEL_SAMPLES`]]) at the centres of a regular grid inside the pixel, so one ray
/// is the pixel's centre.
fn pixel_rays(
    frame: &CameraFrame,
    x: u32,
    y: u32,
    width: u32,
    height: u32,
    n: u32,
) -> impl Iterator<Item = DVec3> + '_ {
    let n = n.clamp(1, MAX_PIXEL_SAMPLES);
    let at = move |i: u32| (i as f64 + 0.5) / n as f64;
    (0..n * n)
        .map(move |k| frame.ray_dir(x as f64 + at(k % n), y as f64 + at(k / n), width, height))
}

/// A pixel's depth from its rays' hits ([`pixel_rays`]): the nearest, when they cover it
/// ([`covers`]: at least half of them, the rule
/// [`fathom_image::compare::reduce`] applies to the octree frame's blocks).
fn covered_depth(hits: impl Iterator<Item = Option<f64>>) -> Option<f64> {
    let (mut rays, mut count, mut nearest) = (0, 0, f64::INFINITY);
    for t in hits {
        rays += 1;
        if let Some(t) = t {
            count += 1;
            nearest = nearest.min(t);
        }
    }
    covers(count, rays).then_some(nearest)
}

/// What a pixel of [`deep_frame`] gathers from its rays: the sum of their colours (sky for a
/// miss), the nearest hit and its shading, and counts.
#[derive(Default)]
struct PixelSample {
    colour: [f32; 3],
    nearest: Option<(f64, Shaded)>,
    hits: u32,
    rays: u32,
    steps: u32,
}

impl PixelSample {
    fn add(&mut self, t: Option<f64>, steps: u32, s: Shaded) {
        for (acc, c) in self.colour.iter_mut().zip(s.colour) {
            *acc += c;
        }
        self.rays += 1;
        self.steps += steps;
        if let Some(t) = t {
            self.hits += 1;
            if self.nearest.is_none_or(|(n, _)| t < n) {
                self.nearest = Some((t, s));
            }
        }
    }
}

/// The shaded reference image: per pixel the march of [`deep_depths`] in double-double from
/// `eye`, then the tracer's colouring of the hit in double-double ([`shade_hits`] with the
/// tracer's [`Shading`] of `scene`'s lights and render settings, AO reach from `view_scale`,
/// the eye's distance to what it looks at), the tracer's sky for misses, and the tracer's
/// post effects ([`post_params`]: the scene's fog, SSAO of `ssao`). `scene` is what the
/// comparison wants drawn (the zoom's reference turns soft shadows off; a scene with them on
/// gets them, marched in double-double too). `camera` gives only the orientation and field of
/// view, as for [`deep_depths`]. Depths are those of [`deep_depths`] (f32, infinite for a
/// miss); steps are the march's distance evaluations. With [`DeepOptions::pixel_samples`]
/// above 1 each pixel is the mean of its rays' colours, a hit where at least half of them hit,
/// with the nearest hit's depth, normal and id.
#[allow(clippy::too_many_arguments)]
pub fn deep_frame(
    tape: &Tape,
    scene: &Scene,
    eye: V3<Dd>,
    camera: &Camera,
    view_scale: f64,
    width: u32,
    height: u32,
    opts: &DeepOptions,
    ssao: f32,
) -> Frame {
    let frame = camera.frame();
    let pixel_angle = frame.pixel_angle(height);
    let mut shading = Shading::new(tape, &scene.render, &scene.lights, view_scale);
    // The tracer's floor (1e-12) is for views of size ~1; past zoom 1e10 it would exceed the
    // pixel footprint and blur the normals, so it scales with the view here.
    shading.min_length = 1e-12 * view_scale.min(1.0);
    let rows: Vec<Vec<PixelSample>> = (0..height)
        .into_par_iter()
        .map_init(Evaluator::<Dd>::new, |ev, y| {
            (0..width)
                .map(|x| {
                    let rays = pixel_rays(&frame, x, y, width, height, opts.pixel_samples);
                    let mut px = PixelSample::default();
                    for dir in rays {
                        let (t, steps) = march_ray(ev, tape, eye, dir, pixel_angle, opts);
                        let mut out = [Shaded {
                            id: NO_ID,
                            ..Shaded::default()
                        }];
                        match t {
                            Some(t) => {
                                let d = V3::new(Dd::from(dir.x), Dd::from(dir.y), Dd::from(dir.z));
                                shade_hits(
                                    ev,
                                    &shading,
                                    eye,
                                    d,
                                    Dd::from(t),
                                    pixel_angle,
                                    true,
                                    &mut out,
                                );
                            }
                            None => out[0].colour = shading.sky([dir.x, dir.y, dir.z]),
                        }
                        px.add(t, steps, out[0]);
                    }
                    px
                })
                .collect()
        })
        .collect();
    let mut img = Frame::new(width, height);
    for (i, px) in rows.into_iter().flatten().enumerate() {
        img.colour[i] = px.colour.map(|c| c / px.rays.max(1) as f32);
        img.steps[i] = px.steps;
        if let Some((t, s)) = px.nearest.filter(|_| covers(px.hits, px.rays)) {
            img.depth[i] = t as f32;
            img.normal[i] = s.normal;
            img.id[i] = s.id;
        }
    }
    let all = Rect::full(width, height);
    let post = post_params(&scene.render, ssao, pixel_angle, false, 1);
    post::finish_view(img, all, all, &post)
}

/// The shaded reference of frame `i` of `frames` of a zoom `path` to `depth` (vertical field
/// of view `fov` degrees) of `scene`: [`deep_frame`] from the frame's double-double eye with the
/// exact orientation of [`CameraPath::deep_camera`], options [`DeepOptions::for_scale`] of the
/// eye's distance to the target with `pixel_samples` rays a pixel side. `None` for tours.
#[allow(clippy::too_many_arguments)]
pub fn zoom_frame(
    tape: &Tape,
    scene: &Scene,
    path: &CameraPath,
    i: usize,
    frames: usize,
    depth: f64,
    fov: f64,
    width: u32,
    height: u32,
    ssao: f32,
    pixel_samples: u32,
) -> Option<Frame> {
    let (eye, cam) = path.deep_camera(i, frames, depth, fov)?;
    let scale = cam.eye.length();
    let opts = DeepOptions {
        pixel_samples,
        ..DeepOptions::for_scale(scale)
    };
    Some(deep_frame(
        tape, scene, eye, &cam, scale, width, height, &opts, ssao,
    ))
}

/// The double-double eye of an f64 camera, for shallow views.
pub fn eye_of(camera: &Camera) -> V3<Dd> {
    dd3(camera.eye)
}

#[cfg(test)]
mod tests;
