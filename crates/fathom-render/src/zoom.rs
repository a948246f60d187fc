//! A zoom (or tour) with the octree: the frame loop of `fathom zoom` and `fathom bench svo`.
//! Each frame takes its camera from the path (with the eye in double-double past f64:
//! [`ZoomPath::deep_camera`]), checks the precision guard (a zoom stops cleanly where the
//! octree's arithmetic runs out, and says so), steps the session's octree, and
//! hands the finished frame (when frames are wanted) and its statistics to the caller. Every
//! `compare_every`-th frame is also rendered by the sphere tracer at the same camera and the
//! two compared ([`crate::compare`]): SSIM on luminance, silhouette IoU, colour error, and the
//! largest visible voxel in pixels, with the frame's camera. Deep frames ([`ZoomPath::is_deep`])
//! are compared with the double-double reference instead of the f64 tracer.

use crate::compare::{Agreement, Reference, agreement, reduce};
use crate::control::Control;
use crate::error::RenderError;
use crate::request::{Backend, RenderRequest};
use crate::session::Session;
use fathom_core::Camera;
use fathom_core::Scene;
use fathom_core::Tape;
use fathom_core::camera_path::{
    CameraPath, ExactCube, PATH_PRESETS, PathPreset, path_preset, surface_point, target_tail,
    view_target,
};
use fathom_core::dd::to_dvec3;
use fathom_core::frame::Frame;
use fathom_core::presets::{self, PresetError};
use fathom_svo::stats::Summary;
use fathom_svo::{DeepEye, FrameStats, Traversal};
use glam::DVec3;
use serde::Serialize;
use std::borrow::Cow;

/// A zoom to run.
#[derive(Clone, Debug)]
pub struct Zoom {
    /// Zoom factor from the first to the last frame (ratio of eye distances), >= 1.
    pub depth: f64,
    /// Frames to render, [1, 10^7].
    pub frames: usize,
    /// Size, SSAO, threads and octree settings (the backend is the octree; the root cube
    /// comes from the path preset when it has one).
    pub request: RenderRequest,
    /// Compare every this many frames with the sphere tracer (and the last frame); 0: never.
    pub compare_every: usize,
    /// Rays a pixel side of the double-double reference deep frames are compared with,
    /// [1, `fathom_trace::deep::MAX_PIXEL_SAMPLES`] ([`DEFAULT_REFERENCE_SAMPLES`]).
    pub reference_samples: u32,
    /// Before the first frame, settle the octree at its camera for at most this many
    /// milliseconds (not counted in the frames' times; 0: start from the root cube).
    pub warmup_ms: f64,
}

/// What [`Zoom::run`] hands its caller after each frame.
pub struct ZoomFrame<'a> {
    /// Frame number from 0.
    pub index: usize,
    /// Zoom factor of the frame.
    pub zoom: f64,
    /// The finished image, when the caller asked for frames.
    pub image: Option<&'a Frame>,
    /// The frame's octree figures.
    pub stats: &'a FrameStats,
    /// On frames compared with the sphere tracer: the octree frame as compared (reduced like
    /// the reference on deep frames, see [`FrameComparison::reduced`]) and the tracer's.
    pub compared: Option<(&'a Frame, &'a Frame)>,
}

/// One frame of a zoom compared with the sphere tracer at the same camera.
#[derive(Clone, Debug, Serialize)]
pub struct FrameComparison {
    /// Frame number from 0.
    pub frame: usize,
    /// Zoom factor of the frame.
    pub zoom: f64,
    /// The frame's camera.
    pub camera: Camera,
    /// The largest visible voxel, in pixels.
    pub largest_voxel_px: f64,
    /// SSIM, silhouette IoU and colour agreement with the tracer's frame.
    #[serde(flatten)]
    pub agreement: Agreement,
    /// Milliseconds the tracer took (not part of the zoom's frame times).
    pub trace_ms: f64,
    /// Which reference: `"f64"` (the CPU sphere tracer from the f64 camera) or
    /// `"double-double"` (`fathom_trace::deep::deep_frame` from the double-double eye, for
    /// deep frames: [`ZoomPath::is_deep`]).
    pub reference: &'static str,
    /// The factor both frames were reduced by for the comparison (1: full size; the
    /// double-double reference is rendered at most [`crate::compare::DEEP_REFERENCE_PIXELS`]).
    pub reduced: u32,
    /// Rays a pixel side of the reference (the f64 tracer's frame: 1).
    pub reference_samples: u32,
}

/// The frame rate a zoom holds by default (`fathom zoom --target-fps`, the bench's zooms;
/// `OctreeSettings::target_fps`): a frame whose render leaves less than the split budget of
/// its 33 ms splits for what is left, down to half the budget. The window holds its own target
/// the same way. On the Menger zoom to 1e15 (1000 frames) it gave 32.0 fps against 30.4 and
/// 30.6 with a fixed budget, SSIM at the compared frames within 0.006.
pub const DEFAULT_TARGET_FPS: f64 = 30.0;

/// Rays a pixel side of the double-double reference ([`Zoom::reference_samples`]): 2x2 rays
/// score a deep Menger frame of the tracer's own block means 0.85 against 0.58 for one ray,
/// at four times one ray's cost.
pub const DEFAULT_REFERENCE_SAMPLES: u32 = 2;

/// Why a zoom was refused.
#[derive(Debug, thiserror::Error)]
pub enum ZoomError {
    /// The zoom depth (given) is not finite or below 1.
    #[error("--depth {0} must be a finite zoom factor >= 1")]
    Depth(f64),
    /// The frame count (given) is outside [1, 10000000].
    #[error("--frames {0} is out of range 1..=10000000")]
    Frames(usize),
    /// The warm-start time (given, ms) is not finite or outside [0, [`MAX_WARMUP_MS`]].
    #[error("--warmup-ms {0} is out of range 0..=600000")]
    Warmup(f64),
    /// The reference samples per pixel (given) are outside
    /// [1, [`fathom_trace::deep::MAX_PIXEL_SAMPLES`]].
    #[error("--reference-samples {0} is out of range 1..={max}", max = fathom_trace::deep::MAX_PIXEL_SAMPLES)]
    ReferenceSamples(u32),
    /// A frame failed to render.
    #[error(transparent)]
    Render(#[from] RenderError),
    /// `--pixel` names a pixel outside the image.
    #[error(
        "--pixel {x},{y} is outside the {width}x{height} image (x in 0..{width}, y in 0..{height})"
    )]
    PixelOutside {
        /// The pixel's column.
        x: u32,
        /// The pixel's row.
        y: u32,
        /// The image's width, pixels.
        width: u32,
        /// The image's height, pixels.
        height: u32,
    },
    /// `--toward` names the eye itself, or a point that is not finite.
    #[error(
        "--toward {x},{y},{z} gives no direction from the eye at {eye_x},{eye_y},{eye_z} (the point must differ from the eye and be finite)"
    )]
    TowardEye {
        /// The point's x.
        x: f64,
        /// The point's y.
        y: f64,
        /// The point's z.
        z: f64,
        /// The eye's x.
        eye_x: f64,
        /// The eye's y.
        eye_y: f64,
        /// The eye's z.
        eye_z: f64,
    },
    /// The eye of the view is inside the surface, so no ray reaches it from outside.
    #[error("the eye at {x},{y},{z} is inside the surface of {scene}; move the camera out first")]
    EyeInside {
        /// The scene's name.
        scene: String,
        /// The eye's x.
        x: f64,
        /// The eye's y.
        y: f64,
        /// The eye's z.
        z: f64,
    },
    /// The aimed ray never reaches the surface.
    #[error(
        "nothing to zoom into: {what} misses the surface of {scene}; aim at a pixel that shows the surface (--pixel X,Y) or toward a point on it (--toward x,y,z)"
    )]
    Miss {
        /// The scene's name.
        scene: String,
        /// Which ray missed (the centre ray, a pixel's, the one toward a point).
        what: String,
    },
    /// The octree's root cube does not contain the zoom target: the zoom would end on sky.
    #[error(
        "the zoom target {x},{y},{z} lies outside the octree's root cube (corner {min_x},{min_y},{min_z}, side {side}); the octree fits its root to the surface inside a cube around the origin 1.5 times the target's largest coordinate (at least [-4, 4]^3), so the surface there was not found"
    )]
    OutsideRoot {
        /// The target's x.
        x: f64,
        /// The target's y.
        y: f64,
        /// The target's z.
        z: f64,
        /// The root cube's lowest x.
        min_x: f64,
        /// The root cube's lowest y.
        min_y: f64,
        /// The root cube's lowest z.
        min_z: f64,
        /// The root cube's edge length.
        side: f64,
    },
    /// The scene does not compile.
    #[error("the scene {scene} does not compile: {message}")]
    Compile {
        /// The scene's name.
        scene: String,
        /// The compiler's error, as text.
        message: String,
    },
    /// The frame callback failed (writing a frame, say).
    #[error("{0}")]
    Output(String),
    /// No path preset or scene preset has this name.
    #[error("{0} (or a path preset: {paths})", paths = PATH_PRESETS.join(", "))]
    Preset(PresetError),
}

/// What a zoom flies: a scene, a camera path over it and, when the scene has one, its exact
/// bounding cube (the octree's root). A path preset ([`PathPreset`]) or any scene with an aim
/// ([`ZoomPath::aim`]).
#[derive(Clone, Debug)]
pub struct ZoomPath {
    /// Name for reports (preset name or scene file).
    pub name: String,
    /// The scene.
    pub scene: Scene,
    /// Vertical field of view, degrees.
    pub fov: f64,
    /// The camera path.
    pub path: CameraPath,
    /// The scene's exact bounding cube, if known.
    pub cube: Option<ExactCube>,
}

impl From<PathPreset> for ZoomPath {
    fn from(p: PathPreset) -> ZoomPath {
        ZoomPath {
            name: p.name.into(),
            scene: p.scene,
            fov: p.fov,
            path: p.path,
            cube: p.cube,
        }
    }
}

/// Where a zoom into a scene goes: the surface point hit by a ray from the view's eye.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Aim {
    /// The centre ray of the view, or the first ray that hits on a spiral around it.
    View,
    /// The ray from the eye through this world point.
    Toward(DVec3),
    /// The ray through the centre of this pixel of a `width` x `height` image of the view.
    Pixel {
        /// The pixel's column, from the left.
        x: u32,
        /// The pixel's row, from the top.
        y: u32,
        /// The image's width, pixels.
        width: u32,
        /// The image's height, pixels.
        height: u32,
    },
}

impl ZoomPath {
    /// The zoom a preset names: a path preset ([`PATH_PRESETS`]) as it is, or from its first
    /// camera toward `aim`; any scene preset from its camera toward `aim` (the view's centre
    /// when `None`). `frames` and `depth` place a path preset's first camera.
    pub fn from_preset(
        name: &str,
        aim: Option<Aim>,
        frames: usize,
        depth: f64,
    ) -> Result<ZoomPath, ZoomError> {
        if PATH_PRESETS.contains(&name) {
            let pp = path_preset(name).map_err(ZoomError::Preset)?;
            let Some(aim) = aim else {
                return Ok(pp.into());
            };
            let view = pp.camera(0, frames.max(1), depth.max(1.0));
            return ZoomPath::aim(name, pp.scene, &view, aim, pp.cube);
        }
        let scene = presets::load(name).map_err(ZoomError::Preset)?;
        let view = scene.camera.clone();
        ZoomPath::aim(name, scene, &view, aim.unwrap_or(Aim::View), None)
    }

    /// A zoom from `view`'s eye into the surface of `scene` where `aim`'s ray first reaches it
    /// (bracketed to f64 precision, the outside point: [`surface_point`], with its
    /// double-double tail from [`target_tail`]); the camera then
    /// looks at that point from along the ray, so an aimed pixel moves to the image centre.
    pub fn aim(
        name: &str,
        scene: Scene,
        view: &Camera,
        aim: Aim,
        cube: Option<ExactCube>,
    ) -> Result<ZoomPath, ZoomError> {
        let tape = Tape::compile(&scene).map_err(|e| ZoomError::Compile {
            scene: name.into(),
            message: e.to_string(),
        })?;
        let eye = view.eye;
        let d0 = tape.eval_f64([eye.x, eye.y, eye.z]).d;
        if d0 <= 0.0 || d0.is_nan() {
            return Err(ZoomError::EyeInside {
                scene: name.into(),
                x: eye.x,
                y: eye.y,
                z: eye.z,
            });
        }
        let miss = |what: String| ZoomError::Miss {
            scene: name.into(),
            what,
        };
        let target = match aim {
            Aim::View => view_target(&tape, view)
                .or_else(|| {
                    let d = view.frame().ray_dir(0.5, 0.5, 1, 1);
                    near_surface_point(&tape, eye, d)
                })
                .ok_or_else(|| {
                    miss("the view's centre ray (and 63 rays on a spiral around it)".into())
                })?,
            Aim::Toward(p) => {
                let dir = (p - eye).normalize_or_zero();
                if !p.is_finite() || dir == DVec3::ZERO {
                    return Err(ZoomError::TowardEye {
                        x: p.x,
                        y: p.y,
                        z: p.z,
                        eye_x: eye.x,
                        eye_y: eye.y,
                        eye_z: eye.z,
                    });
                }
                target_on(&tape, eye, dir).ok_or_else(|| {
                    miss(format!(
                        "the ray from the eye {:.4},{:.4},{:.4} toward {},{},{} (direction {:.4},{:.4},{:.4})",
                        eye.x, eye.y, eye.z, p.x, p.y, p.z, dir.x, dir.y, dir.z
                    ))
                })?
            }
            Aim::Pixel {
                x,
                y,
                width,
                height,
            } => {
                if x >= width || y >= height {
                    return Err(ZoomError::PixelOutside {
                        x,
                        y,
                        width,
                        height,
                    });
                }
                let dir = view
                    .frame()
                    .ray_dir(x as f64 + 0.5, y as f64 + 0.5, width, height);
                target_on(&tape, eye, dir).ok_or_else(|| {
                    miss(format!(
                        "the ray through pixel {x},{y} of the {width}x{height} view (direction {:.4},{:.4},{:.4})",
                        dir.x, dir.y, dir.z
                    ))
                })?
            }
        };
        Ok(ZoomPath {
            name: name.into(),
            fov: view.fov,
            path: CameraPath::Zoom {
                target,
                target_lo: target_tail(&tape, eye, target),
                dir: (eye - target).normalize(),
                start: (eye - target).length(),
            },
            cube,
            scene,
        })
    }

    /// The camera at frame `i` of `frames` for a zoom of `depth`.
    pub fn camera(&self, i: usize, frames: usize, depth: f64) -> Camera {
        self.path.camera(i, frames, depth, self.fov)
    }

    /// Whether a frame's camera from [`ZoomPath::deep_camera`] is in the deep form: a zoom
    /// whose eye is within [`DEEP_VIEW`] of the target's largest coordinate (at least 1) of
    /// its target. Such frames are compared with the double-double reference.
    pub fn is_deep(&self, deep: &DeepEye) -> bool {
        match &self.path {
            CameraPath::Zoom { target, .. } => {
                deep.scale <= DEEP_VIEW * target.abs().max_element().max(1.0)
            }
            _ => false,
        }
    }

    /// The camera of frame `i` with the eye to double-double precision, for the octree. Once
    /// the eye is closer to its target than a millionth of the target's coordinates, the f64
    /// camera's look direction (target minus a rounded eye) is off by more than 1e-10 rad and
    /// past zoom ~1e16 the two points are the same f64 value; the camera then looks along the
    /// zoom's direction at a point one unit away, and [`DeepEye`] carries the eye's trailing
    /// part and the true distance to the target.
    pub fn deep_camera(&self, i: usize, frames: usize, depth: f64) -> (Camera, DeepEye) {
        let cam = self.camera(i, frames, depth);
        let (CameraPath::Zoom { dir, .. }, Some((eye, rel))) = (
            &self.path,
            self.path.deep_camera(i, frames, depth, self.fov),
        ) else {
            let deep = DeepEye::of(&cam);
            return (cam, deep);
        };
        // `rel` is the camera in target-relative coordinates: its orientation is exact at any
        // depth (the f64 camera's is not once eye and target round to the same point).
        let shallow = DeepEye {
            eye_lo: DVec3::ZERO,
            scale: rel.eye.length(),
        };
        if !self.is_deep(&shallow) {
            return (cam, shallow);
        }
        let hi = to_dvec3(eye);
        let cam = Camera {
            eye: hi,
            target: hi - *dir,
            up: rel.up,
            fov: rel.fov,
        };
        let deep = DeepEye {
            eye_lo: DVec3::new(eye.x.lo, eye.y.lo, eye.z.lo),
            scale: shallow.scale,
        };
        (cam, deep)
    }
}

/// Eye distance, relative to the target's largest coordinate (at least 1), below which a zoom
/// frame's camera takes the deep form ([`ZoomPath::deep_camera`], [`ZoomPath::is_deep`]).
pub const DEEP_VIEW: f64 = 1e-6;

/// The zoom target along the ray from `eye` along unit `dir`: the surface point bracketed to
/// f64 precision ([`surface_point`]), or, for estimators that never go inside along the ray,
/// [`near_surface_point`].
fn target_on(tape: &Tape, eye: DVec3, dir: DVec3) -> Option<DVec3> {
    surface_point(tape, eye, dir).or_else(|| near_surface_point(tape, eye, dir))
}

/// Relative distance (of the distance travelled) below which [`near_surface_point`] stops.
pub const NEAR_SURFACE: f64 = 1e-7;

/// For estimators that stay positive near their set (the mandelbox preset's estimate creeps
/// along the view's centre ray at 1e-4 for thousands of steps and never goes inside, so
/// nothing can be bracketed): the first point of the ray from `eye` along `dir` where the
/// estimate is below [`NEAR_SURFACE`] of the distance travelled, tracing with half steps (at
/// most 10^6 of them, within 100 world units). A zoom into it is sharp to zoom ~10^7; past
/// that the estimator itself is the limit.
pub fn near_surface_point(tape: &Tape, eye: DVec3, dir: DVec3) -> Option<DVec3> {
    let mut ev = fathom_core::Evaluator::<f64>::new();
    let mut t = 0.0f64;
    for _ in 0..1_000_000 {
        let p = eye + dir * t;
        let d = ev.distance(tape, fathom_core::V3::new(p.x, p.y, p.z));
        if d <= 0.0 || d.is_nan() {
            return None;
        }
        if d < NEAR_SURFACE * t.max(1.0) {
            return Some(p);
        }
        t += 0.5 * d;
        if t > 100.0 {
            return None;
        }
    }
    None
}

/// Longest warm start a zoom accepts, in milliseconds ([`Zoom::warmup_ms`]).
pub const MAX_WARMUP_MS: f64 = 600_000.0;

/// The JSON written by `fathom zoom --stats`.
#[derive(Serialize)]
pub struct ZoomReport {
    /// The zoom's name (path preset or scene file).
    pub preset: String,
    /// The octree traversal used.
    pub traversal: Traversal,
    /// Frame width, pixels.
    pub width: u32,
    /// Frame height, pixels.
    pub height: u32,
    /// Zoom factor from the first to the last frame.
    pub depth: f64,
    /// Worker threads.
    pub threads: usize,
    /// Pixels a voxel may project to.
    pub fidelity: f64,
    /// Why the zoom stopped early (precision limit), if it did.
    pub stopped: Option<String>,
    /// Wall time of the warm start before the first frame, ms.
    pub warmup_ms: f64,
    /// Settling frames of the warm start.
    pub warmup_frames: usize,
    /// Figures over all frames.
    pub summary: Summary,
    /// Zoom factor per frame.
    pub zoom: Vec<f64>,
    /// The octree's figures per frame.
    pub frames: Vec<FrameStats>,
    /// The frames compared with the sphere tracer (`compare_every`).
    pub compare: Vec<FrameComparison>,
}

impl Zoom {
    /// Checks the zoom's own figures (the request is checked by the session).
    pub fn validate(&self) -> Result<(), ZoomError> {
        if !(self.depth.is_finite() && self.depth >= 1.0) {
            return Err(ZoomError::Depth(self.depth));
        }
        if self.frames == 0 || self.frames > 10_000_000 {
            return Err(ZoomError::Frames(self.frames));
        }
        if !(self.warmup_ms.is_finite() && (0.0..=MAX_WARMUP_MS).contains(&self.warmup_ms)) {
            return Err(ZoomError::Warmup(self.warmup_ms));
        }
        if !(1..=fathom_trace::deep::MAX_PIXEL_SAMPLES).contains(&self.reference_samples) {
            return Err(ZoomError::ReferenceSamples(self.reference_samples));
        }
        Ok(())
    }

    /// Runs the zoom along `preset`'s path. `on_frame` sees every frame ([`ZoomFrame`]: its
    /// image when `want_frames`, and on compared frames the two images compared).
    pub fn run<F>(
        &self,
        preset: &ZoomPath,
        want_frames: bool,
        mut on_frame: F,
    ) -> Result<ZoomReport, ZoomError>
    where
        F: FnMut(&ZoomFrame) -> Result<(), String>,
    {
        self.validate()?;
        let mut req = self.request.clone();
        req.backend = Backend::Octree;
        if preset.cube.is_some() {
            req.octree.root = preset.cube;
        } else if let Some(t) = preset.path.target() {
            // Fit the root inside a cube that holds the target with room around it (scenes
            // larger than the default [-4, 4]^3, such as the mandelbox preset, would be cut).
            req.octree.fit_half = req.octree.fit_half.max(1.5 * t.abs().max_element());
        }
        let mut session = Session::new(preset.scene.clone())?;
        let mut reference = match self.compare_every {
            0 => None,
            _ => {
                Some(Reference::new(&preset.scene, &req)?.with_deep_samples(self.reference_samples))
            }
        };
        let mut compare = Vec::new();
        let mut frames = Vec::with_capacity(self.frames);
        let mut zooms = Vec::with_capacity(self.frames);
        let mut stopped = None;
        let (warmup_frames, warmup_ms) = if self.warmup_ms > 0.0 {
            let t0 = std::time::Instant::now();
            let (cam, deep) = preset.deep_camera(0, self.frames, self.depth);
            let n = session.warm_octree(&cam, &deep, &req, self.warmup_ms)?;
            (n, t0.elapsed().as_secs_f64() * 1e3)
        } else {
            (0, 0.0)
        };
        for i in 0..self.frames {
            let (cam, deep) = preset.deep_camera(i, self.frames, self.depth);
            let z = preset.path.zoom_at(i, self.frames, self.depth);
            if let (Some(_), Some(ex)) = (preset.path.target(), session.octree()) {
                let pa = cam.frame().pixel_angle(ex.cfg.height);
                let dist = deep.scale;
                if let Err(e) = fathom_svo::precision::precision_check(
                    dist,
                    ex.tree.root_size,
                    pa,
                    ex.cfg.fidelity,
                    z,
                ) {
                    stopped = Some(e);
                    break;
                }
            }
            let compare_now =
                self.compare_every > 0 && (i % self.compare_every == 0 || i + 1 == self.frames);
            let (frame, st) = session.step_octree_deep(
                &cam,
                &deep,
                &req,
                want_frames || compare_now,
                &Control::default(),
            )?;
            let mut compared = None;
            if let (true, Some(r), Some(f)) = (compare_now, reference.as_mut(), frame.as_ref()) {
                let t0 = std::time::Instant::now();
                let deep_ref = if preset.is_deep(&deep) {
                    r.deep_frame(&preset.path, preset.fov, i, self.frames, self.depth)?
                } else {
                    None
                };
                // The octree frame as compared: reduced like the double-double reference,
                // else the frame itself (borrowed: no copy for the callback).
                let (octree, traced, reference, reduced, samples) = match deep_ref {
                    Some((traced, k)) => (
                        Cow::Owned(reduce(f, k)),
                        traced,
                        "double-double",
                        k,
                        self.reference_samples,
                    ),
                    None => (Cow::Borrowed(f), r.frame(&cam)?, "f64", 1, 1),
                };
                let agreement = agreement(&octree, &traced);
                compared = Some((octree, traced));
                compare.push(FrameComparison {
                    frame: i,
                    zoom: z,
                    camera: cam.clone(),
                    largest_voxel_px: st.largest_voxel_px,
                    agreement,
                    trace_ms: t0.elapsed().as_secs_f64() * 1e3,
                    reference,
                    reduced,
                    reference_samples: samples,
                });
            }
            if i == 0
                && let (Some(t), Some(ex)) = (preset.path.target(), session.octree())
                && !ex.tree.to_u(t).iter().all(|c| (0.0..=1.0).contains(c))
            {
                let (m, side) = (ex.tree.root_min, ex.tree.root_size);
                return Err(ZoomError::OutsideRoot {
                    x: t.x,
                    y: t.y,
                    z: t.z,
                    min_x: m.x,
                    min_y: m.y,
                    min_z: m.z,
                    side,
                });
            }
            on_frame(&ZoomFrame {
                index: i,
                zoom: z,
                image: if want_frames { frame.as_ref() } else { None },
                stats: &st,
                compared: compared.as_ref().map(|(a, b)| (a.as_ref(), b)),
            })
            .map_err(ZoomError::Output)?;
            frames.push(st);
            zooms.push(z);
        }
        let ex = session.octree().expect("the first frame built the octree");
        let cfg = &ex.cfg;
        let summary = Summary::new(&frames, &zooms, cfg.brick_period);
        Ok(ZoomReport {
            preset: preset.name.clone(),
            traversal: cfg.traversal,
            width: cfg.width,
            height: cfg.height,
            depth: self.depth,
            threads: cfg.threads,
            fidelity: cfg.fidelity,
            stopped,
            warmup_ms,
            warmup_frames,
            summary,
            zoom: zooms,
            frames,
            compare,
        })
    }
}
