//! Camera paths over a number of frames, for every renderer: a zoom into a point (the eye's
//! distance to it shrinks geometrically, so each frame zooms by the same factor) and a tour
//! (a [`crate::flight`] path through eye and look-at waypoints); and how to find the point to zoom
//! into: the surface point of a view, bracketed to f64 precision. [`path_preset`] pairs scenes
//! with paths (the zooms and the tour of `fathom zoom`).

use crate::camera::Camera;
use crate::eval::Evaluator;
use crate::flight::{FlightPath, Keyframe};
use crate::presets::{self, PresetError};
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
        /// Point zoomed into.
        target: DVec3,
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
    pub fn zoom_into_view(tape: &Tape, cam: &Camera) -> Option<CameraPath> {
        let target = view_target(tape, cam)?;
        Some(CameraPath::Zoom {
            target,
            dir: (cam.eye - target).normalize(),
            start: (cam.eye - target).length(),
        })
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
            CameraPath::Zoom { target, dir, start } => {
                (*target + *dir * (start * depth.powf(-f)), *target)
            }
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
}

/// A cube known to bound a scene exactly (its faces are the scene's faces), which an octree
/// can take as its root instead of fitting one.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ExactCube {
    pub centre: DVec3,
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
            path: CameraPath::Zoom {
                target: DVec3::ONE,
                dir: DVec3::new(1.0, 0.8, 0.6).normalize(),
                start: 1.5,
            },
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
    let f = cam.frame();
    (0..64).find_map(|i| {
        // Golden-angle spiral over the middle of a 1x1 image.
        let r = 0.4 * (i as f64 / 64.0).sqrt();
        let a = i as f64 * 2.399_963_229_728_653;
        let d = f.ray_dir(0.5 + r * a.cos(), 0.5 + r * a.sin(), 1, 1);
        surface_point(tape, cam.eye, d)
    })
}

/// The point where the ray from `eye` along unit `dir` first reaches the surface, to f64
/// precision, on the outside: sphere tracing with half steps (the Mandelbulb's estimator is
/// an estimate and full steps can overshoot into the set), then bisection between the last
/// point outside (distance > 0) and the first point inside (distance <= 0) until they are
/// neighbouring floats along the ray. Returns the outside point, so every point of the ray
/// before it (where the eye of a zoom into it travels) was stepped over as outside.
pub fn surface_point(tape: &Tape, eye: DVec3, dir: DVec3) -> Option<DVec3> {
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
    Some(eye + dir * lo)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scenes;

    #[test]
    fn zooms_reach_their_depth_and_tours_hit_their_waypoints() {
        let z = CameraPath::Zoom {
            target: DVec3::ONE,
            dir: DVec3::new(1.0, 0.8, 0.6).normalize(),
            start: 1.5,
        };
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
        let CameraPath::Zoom { target, dir, start } = *p else {
            panic!()
        };
        let d = |q: DVec3| tape.eval_f64([q.x, q.y, q.z]).d;
        // Outside, and a few ulps further along the view is inside: the target is on the
        // surface to f64 precision. (The estimator's set is the points that do not escape in
        // 12 iterations; just outside it the estimate is ~7e-7, inside it is 0, so "on the
        // surface" means bracketed, not a distance near 0.)
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
}
