//! Camera paths over a number of frames, for every renderer: a zoom into a point (the eye's
//! distance to it shrinks geometrically, so each frame zooms by the same factor) and a tour
//! (a [`crate::flight`] path through eye and look-at waypoints); and how to find the point to zoom
//! into: the surface point of a view, bracketed to f64 precision ([`surface_point`]) and refined
//! to double-double precision ([`surface_point_dd`]), so a zoom past 1e15 has an exact target and
//! eye ([`CameraPath::eye_dd`], [`CameraPath::deep_camera`]). [`path_preset`] pairs scenes with
//! paths (the zooms and the tour of `fathom zoom`).

use crate::camera::Camera;
use crate::dd::{Dd, add_offset};
use crate::eval::Evaluator;
use crate::flight::{FlightPath, Keyframe};
use crate::presets::{self, PresetError};
use crate::real::Real;
use crate::scene::Scene;
use crate::scenes;
use crate::tape::Tape;
use crate::vec3::V3;
use glam::DVec3;

/// A camera path over `frames` frames.
#[derive(Clone, Debug, PartialEq)]
pub enum CameraPath {
    /// Eye at `target + dir * start * depth^(-i / (frames - 1))`, looking at `target`.
    Zoom {
        /// Point zoomed into (for a surface target, the outside point of the f64 bracket).
        target: DVec3,
        /// What `target` misses of the double-double target: the point zoomed into is
        /// `target + target_lo` to ~1e-32 ([`CameraPath::target_dd`]). Zero when `target` is
        /// exact (the Menger corner) or was not refined; it matters past zoom ~1e14, where
        /// an f64 target is as far from the surface as the eye.
        target_lo: DVec3,
        /// Unit direction from the target to the eye.
        dir: DVec3,
        /// Eye distance at frame 0.
        start: f64,
    },
    /// A flight through (eye, target) waypoints (at least two), at constant speed.
    Tour {
        /// Waypoints: eye and look-at point.
        points: Vec<(DVec3, DVec3)>,
    },
}

impl CameraPath {
    /// A zoom from `cam`'s eye into the surface point of its view ([`view_target`]), or `None`
    /// when the view shows no surface.
    ///
    /// The target is refined to double-double precision along the same ray
    /// ([`surface_point_dd`]; its tail goes to `target_lo`), so the path stays sharp past
    /// zoom 1e15 ([`CameraPath::eye_dd`]).
    pub fn zoom_into_view(tape: &Tape, cam: &Camera) -> Option<CameraPath> {
        let (target, ray) = view_target_ray(tape, cam)?;
        let target_lo = surface_point_dd(tape, cam.eye, ray).map_or(DVec3::ZERO, |t| {
            crate::dd::sub_to_f64(t, crate::dd::dd3(target))
        });
        Some(CameraPath::Zoom {
            target,
            target_lo,
            dir: (cam.eye - target).normalize(),
            start: (cam.eye - target).length(),
        })
    }

    /// A zoom into `target` from distance `start` along unit `dir`, with no double-double tail
    /// (the target is taken as exact).
    pub fn zoom(target: DVec3, dir: DVec3, start: f64) -> CameraPath {
        CameraPath::Zoom {
            target,
            target_lo: DVec3::ZERO,
            dir,
            start,
        }
    }

    /// The camera at frame `i` of `frames` for a zoom of `depth` (ratio of first to last eye
    /// distance; ignored by tours), with vertical field of view `fov` degrees.
    pub fn camera(&self, i: usize, frames: usize, depth: f64, fov: f64) -> Camera {
        let f = if frames > 1 {
            i as f64 / (frames - 1) as f64
        } else {
            0.0
        };
        let (eye, target) = match self {
            CameraPath::Zoom {
                target, dir, start, ..
            } => (*target + *dir * (start * depth.powf(-f)), *target),
            CameraPath::Tour { points } => tour_point(points, f),
        };
        let fwd = (target - eye).normalize();
        let up = if fwd.cross(DVec3::Y).length() > 1e-3 {
            DVec3::Y
        } else {
            DVec3::X
        };
        Camera {
            eye,
            target,
            up,
            fov,
        }
    }

    /// Zoom factor reached at frame `i` (1 for tours).
    pub fn zoom_at(&self, i: usize, frames: usize, depth: f64) -> f64 {
        match self {
            CameraPath::Zoom { .. } if frames > 1 => depth.powf(i as f64 / (frames - 1) as f64),
            _ => 1.0,
        }
    }

    /// The point zoomed into, for zooms.
    pub fn target(&self) -> Option<DVec3> {
        match self {
            CameraPath::Zoom { target, .. } => Some(*target),
            CameraPath::Tour { .. } => None,
        }
    }

    /// The point zoomed into to double-double precision (`target + target_lo`), for zooms.
    pub fn target_dd(&self) -> Option<V3<Dd>> {
        match self {
            CameraPath::Zoom {
                target, target_lo, ..
            } => Some(V3::new(
                Dd::new(target.x, target_lo.x),
                Dd::new(target.y, target_lo.y),
                Dd::new(target.z, target_lo.z),
            )),
            CameraPath::Tour { .. } => None,
        }
    }

    /// The eye's offset from the target at frame `i` (`dir * start * depth^-f`), for zooms: a
    /// small f64 vector with full relative precision at any depth.
    pub fn eye_offset(&self, i: usize, frames: usize, depth: f64) -> Option<DVec3> {
        match self {
            CameraPath::Zoom { dir, start, .. } => {
                Some(*dir * (start * depth.powf(-self.frame_fraction(i, frames))))
            }
            CameraPath::Tour { .. } => None,
        }
    }

    /// The eye at frame `i` in double-double: `target_dd + dir * distance`, for zooms. Exact
    /// to ~1e-32 of the coordinates, so a frame at zoom 1e15..1e28 has an eye at the right
    /// distance from the target (in f64 the eye of a zoom past ~1e16 coincides with the
    /// target).
    pub fn eye_dd(&self, i: usize, frames: usize, depth: f64) -> Option<V3<Dd>> {
        Some(add_offset(
            self.target_dd()?,
            self.eye_offset(i, frames, depth)?,
        ))
    }

    /// The frame-`i` camera of a zoom for deep frames: the eye in double-double
    /// ([`CameraPath::eye_dd`]) and a camera in coordinates relative to the target (eye at
    /// the offset, looking at the origin), exact at any depth. Renderers take the orientation
    /// and field of view from the camera and add its rays to the double-double eye.
    pub fn deep_camera(
        &self,
        i: usize,
        frames: usize,
        depth: f64,
        fov: f64,
    ) -> Option<(V3<Dd>, Camera)> {
        let off = self.eye_offset(i, frames, depth)?;
        let up = if off.cross(DVec3::Y).length() > 1e-3 * off.length() {
            DVec3::Y
        } else {
            DVec3::X
        };
        let cam = Camera {
            eye: off,
            target: DVec3::ZERO,
            up,
            fov,
        };
        Some((self.eye_dd(i, frames, depth)?, cam))
    }

    /// `i / (frames - 1)`, 0 for a single frame.
    fn frame_fraction(&self, i: usize, frames: usize) -> f64 {
        if frames > 1 {
            i as f64 / (frames - 1) as f64
        } else {
            0.0
        }
    }
}

/// A cube known to bound a scene exactly (its faces are the scene's faces), which an octree
/// can take as its root instead of fitting one.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ExactCube {
    /// The cube's centre, world units.
    pub centre: DVec3,
    /// Half its edge length, world units.
    pub half: f64,
}

/// A scene with a path to explore it by: what `fathom zoom --preset NAME` flies.
#[derive(Clone, Debug)]
pub struct PathPreset {
    /// Preset name.
    pub name: &'static str,
    /// The scene.
    pub scene: Scene,
    /// Vertical field of view (degrees).
    pub fov: f64,
    /// The camera path.
    pub path: CameraPath,
    /// The scene's exact bounding cube, when it has one.
    pub cube: Option<ExactCube>,
}

impl PathPreset {
    /// The camera at frame `i` of `frames` for a zoom of `depth`.
    pub fn camera(&self, i: usize, frames: usize, depth: f64) -> Camera {
        self.path.camera(i, frames, depth, self.fov)
    }
}

/// Names accepted by [`path_preset`].
pub const PATH_PRESETS: &[&str] = &["menger", "mandelbulb", "menger-tour"];

/// The path presets: `menger` zooms into the corner (1, 1, 1), a fixed point of the sponge's
/// scaling by 1/3 (images at distances 1/3, 1/9, 1/27 of each other are strictly self-similar);
/// `mandelbulb` zooms into the surface point of the preset's view; `menger-tour` orbits the
/// sponge and flies down its central tunnel.
pub fn path_preset(name: &str) -> Result<PathPreset, PresetError> {
    let menger_cube = Some(ExactCube {
        centre: DVec3::ZERO,
        half: 1.0,
    });
    match name {
        "menger" => Ok(PathPreset {
            name: "menger",
            scene: scenes::menger(40),
            fov: 50.0,
            path: CameraPath::zoom(DVec3::ONE, DVec3::new(1.0, 0.8, 0.6).normalize(), 1.5),
            cube: menger_cube,
        }),
        "mandelbulb" => {
            let scene = presets::load("mandelbulb")?;
            let tape = Tape::compile(&scene).expect("the mandelbulb preset compiles");
            let path = CameraPath::zoom_into_view(&tape, &scene.camera)
                .expect("the mandelbulb preset's view shows the bulb");
            Ok(PathPreset {
                name: "mandelbulb",
                fov: scene.camera.fov,
                path,
                cube: None,
                scene,
            })
        }
        "menger-tour" => Ok(PathPreset {
            name: "menger-tour",
            scene: scenes::menger(40),
            fov: 60.0,
            path: CameraPath::Tour {
                points: vec![
                    (DVec3::new(3.0, 2.2, 3.4), DVec3::ZERO),
                    (DVec3::new(3.4, 1.0, -2.4), DVec3::ZERO),
                    (DVec3::new(-2.6, 0.6, -2.8), DVec3::ZERO),
                    (DVec3::new(-2.4, 0.3, 2.2), DVec3::ZERO),
                    (DVec3::new(0.0, 0.05, 2.4), DVec3::new(0.0, 0.0, 0.0)),
                    (DVec3::new(0.0, 0.0, 1.2), DVec3::new(0.0, 0.0, -1.0)),
                    (DVec3::new(0.0, 0.0, 0.4), DVec3::new(0.0, 0.0, -1.0)),
                    (DVec3::new(0.05, 0.0, -0.4), DVec3::new(0.3, 0.0, -1.2)),
                ],
            },
            cube: menger_cube,
        }),
        _ => Err(PresetError::Unknown {
            name: name.into(),
            hint: crate::call_serde::did_you_mean(name, PATH_PRESETS.iter().copied()),
        }),
    }
}

/// The tour through `(eye, target)` waypoints at `f` in [0, 1]: a [`FlightPath`] through them
/// (centripetal Catmull-Rom, squad orientations, paced by distance and angle: the tour's
/// waypoints carry no scale), so tours and scene-file paths share one spline.
fn tour_point(p: &[(DVec3, DVec3)], f: f64) -> (DVec3, DVec3) {
    if p.len() < 2 {
        return p.first().copied().unwrap_or((DVec3::Z, DVec3::ZERO));
    }
    let keys = p
        .iter()
        .map(|&(eye, target)| {
            let fwd = target - eye;
            let up = if fwd.cross(DVec3::Y).length() > 1e-3 * fwd.length() {
                DVec3::Y
            } else {
                DVec3::X
            };
            Keyframe {
                up,
                ..Keyframe::from_camera(&Camera {
                    eye,
                    target,
                    up,
                    fov: 45.0,
                })
            }
        })
        .collect();
    let path = FlightPath {
        scale_aware: false,
        ..FlightPath::new("tour", 1.0, keys)
    };
    match path.prepare(&crate::scenes::sphere(1.0), None) {
        Ok(flight) => {
            let c = flight.sample(f).camera;
            (c.eye, c.target)
        }
        // Coinciding eye and target: no orientation to interpolate; stay at the first.
        Err(_) => p[0],
    }
}

/// The zoom target of a scene's view (it follows the camera, so a preset that is reframed keeps
/// a target in view; no hard-coded aim point): the surface point of the camera's centre ray,
/// or, if that misses, of the first ray that hits on a spiral of image points around the
/// centre.
pub fn view_target(tape: &Tape, cam: &Camera) -> Option<DVec3> {
    view_target_ray(tape, cam).map(|(p, _)| p)
}

/// [`view_target`] and the unit direction of the ray that found it.
fn view_target_ray(tape: &Tape, cam: &Camera) -> Option<(DVec3, DVec3)> {
    let f = cam.frame();
    (0..64).find_map(|i| {
        // Golden-angle spiral over the middle of a 1x1 image.
        let r = 0.4 * (i as f64 / 64.0).sqrt();
        let a = i as f64 * 2.399_963_229_728_653;
        let d = f.ray_dir(0.5 + r * a.cos(), 0.5 + r * a.sin(), 1, 1);
        surface_point(tape, cam.eye, d).map(|p| (p, d))
    })
}

/// The point where the ray from `eye` along unit `dir` first reaches the surface, to f64
/// precision, on the outside: sphere tracing with half steps (the Mandelbulb's estimator is
/// an estimate and full steps can overshoot into the set), then bisection between the last
/// point outside (distance > 0) and the first point inside (distance <= 0) until they are
/// neighbouring floats along the ray. Returns the outside point, so every point of the ray
/// before it (where the eye of a zoom into it travels) was stepped over as outside.
pub fn surface_point(tape: &Tape, eye: DVec3, dir: DVec3) -> Option<DVec3> {
    surface_bracket(tape, eye, dir).map(|(lo, _)| eye + dir * lo)
}

/// The distances `(lo, hi)` along the ray of [`surface_point`]: `eye + dir * lo` is outside,
/// `eye + dir * hi` inside, and they are neighbouring floats (or `hi` is the first inside
/// point found).
fn surface_bracket(tape: &Tape, eye: DVec3, dir: DVec3) -> Option<(f64, f64)> {
    let mut ev = Evaluator::<f64>::new();
    let mut dist = |t: f64| {
        let p = eye + dir * t;
        ev.distance(tape, V3::new(p.x, p.y, p.z))
    };
    let outside = |d: f64| d > 0.0; // NaN counts as inside
    if !outside(dist(0.0)) {
        return None;
    }
    // 1. Half steps until the step no longer moves t or a step lands inside.
    let mut lo = 0.0f64;
    let mut hi = None;
    for _ in 0..200_000 {
        let d = dist(lo);
        let next = lo + 0.5 * d;
        if next > 100.0 {
            return None;
        }
        if next == lo {
            break;
        }
        if !outside(dist(next)) {
            hi = Some(next);
            break;
        }
        lo = next;
    }
    // 2. Find a point inside just beyond `lo`: grow a step from one ulp.
    let hi = match hi {
        Some(h) => h,
        None => {
            let mut s = lo.max(1e-300) * f64::EPSILON;
            loop {
                if !outside(dist(lo + s)) {
                    break lo + s;
                }
                s *= 2.0;
                if s > 1e-6 {
                    return None;
                }
            }
        }
    };
    // 3. Bisection down to neighbouring floats.
    let mut hi = hi;
    loop {
        let mid = 0.5 * (lo + hi);
        if mid <= lo || mid >= hi {
            break;
        }
        if outside(dist(mid)) {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    Some((lo, hi))
}

/// What an f64 surface `target` seen from `eye` misses of the double-double surface point on
/// the ray from `eye` through it ([`surface_point_dd`]): the `target_lo` of a
/// [`CameraPath::Zoom`]. Zero when there is none within 1e-13 of the coordinates (a target
/// that is not a bracketed surface point, such as one of `fathom zoom`'s near-surface targets).
pub fn target_tail(tape: &Tape, eye: DVec3, target: DVec3) -> DVec3 {
    let dir = (target - eye).normalize_or_zero();
    if dir == DVec3::ZERO {
        return DVec3::ZERO;
    }
    let Some(p) = surface_point_dd(tape, eye, dir) else {
        return DVec3::ZERO;
    };
    let tail = crate::dd::sub_to_f64(p, crate::dd::dd3(target));
    if tail.abs().max_element() <= 1e-13 * target.abs().max_element().max(1.0) {
        tail
    } else {
        DVec3::ZERO
    }
}

/// Width (relative to the size of the point's coordinates, at least 1) below which
/// [`surface_point_dd`] stops bisecting: about 100 double-double ulps.
pub const DD_BRACKET: f64 = 1e-30;

/// [`surface_point`] refined to double-double precision: the f64 bracket along the ray is
/// checked (and widened if needed) with double-double evaluation, then bisected in
/// double-double until the outside and inside points are within [`DD_BRACKET`] of each other
/// (relative to the coordinates, at least 1). Same rule: outside is `d > 0`, inside
/// `d <= 0` or NaN; for the Mandelbulb the surface is the boundary of the points that do not
/// escape in its iteration count. Returns the outside point, or `None` where
/// [`surface_point`] finds nothing.
///
/// Meaningful where the estimator is exact in double-double (see [`crate::dd`]): the power-8
/// Mandelbulb, the Mandelbox, the folding fractals and polynomial primitives; for estimators
/// with trigonometry the refined point is only as good as their f64 accuracy.
pub fn surface_point_dd(tape: &Tape, eye: DVec3, dir: DVec3) -> Option<V3<Dd>> {
    let (lo, hi) = surface_bracket(tape, eye, dir)?;
    let mut ev = Evaluator::<Dd>::new();
    let e = crate::dd::dd3(eye);
    let at = |t: Dd| V3::new(e.x + t * dir.x, e.y + t * dir.y, e.z + t * dir.z);
    let mut outside = |t: Dd| ev.distance(tape, at(t)) > Dd::ZERO; // NaN counts as inside
    // The f64 bracket seen in double-double: widen either end (doubling) until it holds.
    let (mut lo, mut hi) = (Dd::from(lo), Dd::from(hi));
    let mut w = (hi - lo)
        .hi
        .max(lo.hi.abs() * f64::EPSILON)
        .max(f64::MIN_POSITIVE);
    let mut tries = 0;
    while !outside(lo) {
        lo = (lo - w).max(Dd::ZERO);
        w *= 2.0;
        tries += 1;
        if tries > 60 || lo.hi <= 0.0 && !outside(lo) {
            return None;
        }
    }
    let mut w = (hi - lo).hi.max(f64::MIN_POSITIVE);
    let mut tries = 0;
    while outside(hi) {
        lo = hi;
        hi += w;
        w *= 2.0;
        tries += 1;
        if tries > 60 {
            return None;
        }
    }
    let p = at(lo);
    let scale = p.x.hi.abs().max(p.y.hi.abs()).max(p.z.hi.abs()).max(1.0);
    for _ in 0..200 {
        let width = (hi - lo).hi;
        if width * dir.abs().max_element() <= DD_BRACKET * scale {
            break;
        }
        let mid = (lo + hi) * 0.5;
        if mid <= lo || mid >= hi {
            break;
        }
        if outside(mid) {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    Some(at(lo))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scenes;

    #[test]
    fn zooms_reach_their_depth_and_tours_hit_their_waypoints() {
        let z = CameraPath::zoom(DVec3::ONE, DVec3::new(1.0, 0.8, 0.6).normalize(), 1.5);
        let d0 = (z.camera(0, 11, 1e10, 50.0).eye - DVec3::ONE).length();
        let d1 = (z.camera(10, 11, 1e10, 50.0).eye - DVec3::ONE).length();
        assert!((d0 / d1 / 1e10 - 1.0).abs() < 1e-4, "{}", d0 / d1);
        assert!((z.zoom_at(10, 11, 1e10) / 1e10 - 1.0).abs() < 1e-12);
        let points = vec![
            (DVec3::new(3.0, 2.0, 3.0), DVec3::ZERO),
            (DVec3::new(3.0, 1.0, -2.0), DVec3::ZERO),
            (DVec3::new(-2.0, 0.5, -2.0), DVec3::ZERO),
        ];
        let t = CameraPath::Tour {
            points: points.clone(),
        };
        assert!((t.camera(0, 100, 1.0, 60.0).eye - points[0].0).length() < 1e-12);
        assert!((t.camera(99, 100, 1.0, 60.0).eye - points[2].0).length() < 1e-12);
        assert_eq!(t.zoom_at(50, 100, 1e9), 1.0);
    }

    #[test]
    fn path_presets_exist_and_unknown_names_are_explained() {
        for n in PATH_PRESETS {
            let p = path_preset(n).unwrap();
            assert_eq!(p.name, *n);
            p.camera(0, 10, 1e3).validate().unwrap();
        }
        let e = path_preset("mengr").unwrap_err().to_string();
        assert!(e.contains("menger"), "{e}");
    }

    #[test]
    fn surface_points_are_bracketed_to_f64_precision() {
        // A sphere of radius 1, approached head on and at a grazing angle.
        let tape = Tape::compile(&scenes::sphere(1.0)).unwrap();
        for (eye, dir) in [
            (DVec3::new(0.0, 0.0, 3.0), DVec3::NEG_Z),
            (DVec3::new(0.0, 0.999, 3.0), DVec3::NEG_Z),
        ] {
            let q = surface_point(&tape, eye, dir).unwrap();
            let r = q.length();
            assert!(r > 1.0 - 1e-15 && r < 1.0 + 1e-14, "{r}");
            assert!(tape.eval_f64([q.x, q.y, q.z]).d > 0.0);
        }
        assert!(surface_point(&tape, DVec3::new(0.0, 2.0, 3.0), DVec3::NEG_Z).is_none());
    }

    #[test]
    fn mandelbulb_target_is_on_the_surface_and_the_eye_stays_outside() {
        let pp = path_preset("mandelbulb").unwrap();
        let (scene, p) = (&pp.scene, &pp.path);
        let tape = Tape::compile(scene).unwrap();
        let CameraPath::Zoom {
            target, dir, start, ..
        } = *p
        else {
            panic!()
        };
        let d = |q: DVec3| tape.eval_f64([q.x, q.y, q.z]).d;
        // Outside, and a few ulps further along the view is inside: the target is on the
        // surface to f64 precision. (The estimator's set is the points that do not escape in
        // 12 iterations; the estimate is signed across its surface, so bracketed means a
        // change of sign within a few ulps.)
        let eps = 4.0 * f64::EPSILON * target.abs().max_element().max(1.0);
        assert!(d(target) > 0.0, "target inside: {}", d(target));
        assert!(
            d(target) < 1e-5,
            "target {} far from the surface",
            d(target)
        );
        assert!(
            d(target - dir * eps) <= 0.0,
            "no inside point within 4 ulps beyond the target"
        );
        assert!(start > 0.5);
        // The zoom's eye stays outside at every frame of a zoom to 1e13 (past the precision
        // limit of 640x480, where `fathom zoom` stops).
        let frames = 600;
        for i in 0..frames {
            let eye = p.camera(i, frames, 1e13, scene.camera.fov).eye;
            assert!(
                d(eye) > 0.0,
                "frame {i}: eye inside at zoom {:.2e}",
                p.zoom_at(i, frames, 1e13)
            );
        }
    }
    #[test]
    fn dd_surface_points_are_bracketed_to_double_double_precision() {
        let tape = Tape::compile(&scenes::sphere(1.0)).unwrap();
        let d = |q: V3<Dd>| tape.eval_dd(q).d;
        for (eye, dir) in [
            (DVec3::new(0.0, 0.0, 3.0), DVec3::NEG_Z),
            (DVec3::new(0.0, 0.999, 3.0), DVec3::NEG_Z),
            (
                DVec3::new(2.0, 1.5, 1.0),
                DVec3::new(-2.0, -1.4, -1.1).normalize(),
            ),
        ] {
            let q = surface_point_dd(&tape, eye, dir).unwrap();
            // |q|^2 - 1 in double-double: on the sphere to ~1e-30 (f64 gets ~1e-16).
            let r2 = q.x * q.x + q.y * q.y + q.z * q.z - Dd::ONE;
            assert!(r2.hi.abs() < 1e-29, "{eye:?}: |q|^2 - 1 = {r2:?}");
            assert!(d(q) > Dd::ZERO, "{eye:?}: the point is inside");
            assert!(
                d(add_offset(q, dir * 1e-28)) <= Dd::ZERO,
                "{eye:?}: not bracketed"
            );
        }
        assert!(surface_point_dd(&tape, DVec3::new(0.0, 2.0, 3.0), DVec3::NEG_Z).is_none());
    }

    #[test]
    fn mandelbulb_dd_target_is_bracketed_and_deep_eyes_stay_outside() {
        let pp = path_preset("mandelbulb").unwrap();
        let tape = Tape::compile(&pp.scene).unwrap();
        let p = &pp.path;
        let CameraPath::Zoom {
            target,
            target_lo,
            dir,
            start,
        } = *p
        else {
            panic!()
        };
        let d = |q: V3<Dd>| tape.eval_dd(q).d;
        let t = p.target_dd().unwrap();
        // The double-double target is outside and 1e-25 further along the view is inside.
        assert!(d(t) > Dd::ZERO, "target inside: {:?}", d(t));
        assert!(
            d(add_offset(t, -dir * 1e-25)) <= Dd::ZERO,
            "no inside point within 1e-25 beyond the target"
        );
        // The f64 target alone is not: it is outside by more than 1e-25 (its tail is ~1e-17,
        // as far from the surface as the eye of a zoom to 1e17).
        let t64 = crate::dd::dd3(target);
        assert!(d(add_offset(t64, -dir * 1e-25)) > Dd::ZERO);
        eprintln!("f64 target's tail: {target_lo:?}");
        assert!(target_lo != DVec3::ZERO);
        assert!(target_lo.abs().max_element() < 1e-14);
        for depth in [1e15, 1e18] {
            let dist = start / depth;
            let eye = p.eye_dd(1, 2, depth).unwrap();
            assert!(d(eye) > Dd::ZERO, "zoom {depth:e}: eye inside");
            // The double-double eye is at its distance from the target, to f64 precision.
            let got = crate::dd::sub_to_f64(eye, t);
            assert!((got - dir * dist).length() <= 1e-15 * dist, "{got:?}");
            // The f64 eye cannot be placed: at 1e15 its offset from the target is off by more
            // than 0.1 % (1.3 % measured: ulps of a coordinate near 1 against 2e-15); at 1e18
            // it is the target itself.
            let eye64 = p.camera(1, 2, depth, pp.fov).eye;
            let err = ((eye64 - target) - dir * dist).length() / dist;
            eprintln!("zoom {depth:e}: f64 eye offset error {err:.2e} of the eye distance");
            if depth == 1e15 {
                assert!(err > 1e-3, "{err}");
            } else {
                assert_eq!(eye64, target);
            }
        }
        // Every frame of a zoom to 1e20 keeps its eye outside, and its deep camera is valid
        // and looks along -dir.
        let frames = 120;
        for i in 0..frames {
            let (eye, cam) = p.deep_camera(i, frames, 1e20, pp.fov).unwrap();
            assert!(d(eye) > Dd::ZERO, "frame {i}: eye inside");
            cam.validate().unwrap();
            assert!((cam.frame().forward + dir).length() < 1e-12);
        }
    }

    #[test]
    fn menger_corner_eyes_are_exact() {
        let pp = path_preset("menger").unwrap();
        assert_eq!(pp.path.target_dd(), Some(crate::dd::dd3(DVec3::ONE)));
        let CameraPath::Zoom { dir, start, .. } = pp.path else {
            panic!()
        };
        for depth in [1e15, 1e20, 1e25] {
            let eye = pp.path.eye_dd(1, 2, depth).unwrap();
            let off = crate::dd::sub_to_f64(eye, crate::dd::dd3(DVec3::ONE));
            assert!((off - dir * (start / depth)).length() <= 1e-15 * start / depth);
        }
        assert!(
            CameraPath::Tour { points: vec![] }
                .eye_dd(0, 2, 1.0)
                .is_none()
        );
    }
}
