//! [`RenderRequest`]: everything that says how to render one frame (size, projection,
//! supersampling, tracer rule, prepass, SSAO, fog, backend, threads, and optionally a region of
//! the image), as one serialisable value. The command line, the window and a farm task all
//! build one of these and hand it to a [`crate::Session`]; a farm writes it into its manifest.

use fathom_core::Projection;
use fathom_core::camera_path::ExactCube;
use fathom_core::frame::Rect;
use fathom_svo::{OctreeError, OctreeViewConfig, RootSpec, Traversal};
use fathom_trace::{Method, Options, OptionsError};
use serde::{Deserialize, Serialize};

/// Which renderer draws the frame.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Backend {
    /// The CPU sphere tracer (f32 packets, f64 for deep views).
    #[default]
    Trace,
    /// The WGSL tape interpreter through wgpu; views past f32 precision fall back to the CPU
    /// tracer (the frame's [`crate::Stats::note`] says so).
    Gpu,
    /// The sparse voxel octree, subdivided until settled at the view.
    Octree,
    /// The scene as a cloud: its interior sampled into a density grid and path-traced by
    /// fathom-volume (settings in [`VolumeSettings`]).
    Volume,
    /// The progressive path tracer of fathom-pathtrace (settings in [`PathRequest`]): global
    /// illumination, soft shadows, depth of field; a session keeps accumulating samples
    /// while the view, the scene and the settings stay the same.
    Path,
}

impl Backend {
    /// The name used in stats and on the command line.
    pub fn name(self) -> &'static str {
        match self {
            Backend::Trace => "trace",
            Backend::Gpu => "gpu",
            Backend::Octree => "svo",
            Backend::Volume => "volume",
            Backend::Path => "path",
        }
    }
}

/// The sphere-tracing step rule.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum TracerRule {
    /// Step by the distance bound (Hart).
    Basic,
    /// Over-relaxed steps with a safe fallback (Keinert et al. 2014).
    #[default]
    Enhanced,
}

/// Settings of the octree backend.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct OctreeSettings {
    /// Voxels may project to this many pixels, [0.25, 16].
    pub fidelity: f64,
    /// Memory budget of the octree in bytes (at least 1 MiB).
    pub max_memory: usize,
    /// Traversal of the octree.
    pub traversal: Traversal,
    /// The scene's exact bounding cube as the root (else a cube fitted to the surface inside
    /// [-fit_half, fit_half]^3).
    pub root: Option<ExactCube>,
    /// Half side of the cube the root is fitted inside when `root` is not given (> 0).
    pub fit_half: f64,
    /// Most frames spent subdividing at a still view before rendering it.
    pub settle_frames: usize,
    /// Subdivision time per frame in ms, for stepped frames (zooms and the window).
    pub subdivide_ms: f64,
    /// Frame rate the stepped frames hold by giving subdivision no more than the render left,
    /// between half and all of `subdivide_ms` (0: a fixed `subdivide_ms`), [0, 1000].
    pub target_fps: f64,
    /// Unify (unload bricks no ray visited) every this many stepped frames.
    pub unify_every: u32,
    /// Side in pixels of the tiles whose frustum walk finds where all the tile's rays start
    /// (0: every ray from the eye's leaf; the images are the same), [0, 256].
    pub beam: u32,
    /// Finest side the tiles are refined to (quadrants), [1, 256].
    pub beam_min: u32,
    /// Draw leaves wider than a pixel with their surface planes instead of as cubes
    /// ([`fathom_svo::plane`]).
    pub planes: bool,
    /// How much nearer the screen's centre subdivision requests count: a voxel's size on
    /// screen is divided by `1 + fovea rho^2`, `rho` its distance from the centre in
    /// half-heights (0: the largest on screen first wherever they are), [0, 64].
    pub fovea: f64,
    /// Draw voxels at least two pixels wide smooth, each pixel the mean colour of a box as
    /// wide as its voxel on screen ([`fathom_svo::smooth`]; frames whose voxels are all
    /// narrower, settled frames at fidelity below 2, are unchanged).
    pub smooth: bool,
    /// Pixels between lattice rays (two pixels apart) that all met one voxel at least this
    /// many pixels wide take its colour without casting ([`fathom_svo::fill`]; 0: every pixel
    /// casts), 0 or [2, 64].
    pub fill_px: f64,
}

impl Default for OctreeSettings {
    fn default() -> Self {
        OctreeSettings {
            fidelity: 1.0,
            max_memory: 1 << 30,
            traversal: Traversal::Neighbour,
            root: None,
            fit_half: 4.0,
            settle_frames: 400,
            subdivide_ms: fathom_svo::octree_view::DEFAULT_SUBDIVIDE_MS,
            target_fps: 0.0,
            unify_every: 4,
            beam: fathom_svo::octree_view::DEFAULT_BEAM,
            beam_min: fathom_svo::octree_view::DEFAULT_BEAM_MIN,
            planes: false,
            fovea: fathom_svo::request_order::DEFAULT_FOVEA,
            smooth: true,
            fill_px: fathom_svo::fill::DEFAULT_FILL_PX,
        }
    }
}

/// Settings of the volume backend.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct VolumeSettings {
    /// Density grid resolution per axis, [2, 512].
    pub grid: u32,
    /// Smooth the density over this many voxels across the surface, [0, 64].
    pub smooth: f32,
    /// Extinction per unit density and length, [0, 1e6].
    pub density_scale: f32,
    /// Single-scattering albedo, [0, 1].
    pub albedo: f32,
    /// Henyey-Greenstein asymmetry, (-1, 1).
    pub g: f32,
    /// Samples per pixel per frame at supersample 1 (times supersample^2), [1, 4096].
    pub spp: u32,
}

impl Default for VolumeSettings {
    fn default() -> Self {
        VolumeSettings {
            grid: 96,
            smooth: 1.0,
            density_scale: 20.0,
            albedo: 0.8,
            g: 0.0,
            spp: 2,
        }
    }
}

/// Most samples per pixel a path-traced frame may ask for.
pub const MAX_PATH_SPP: u32 = 1 << 20;

/// Settings of the path-tracing backend ([`Backend::Path`]).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct PathRequest {
    /// Samples per pixel the frame is to have, [1, 2^20]. A session that already holds the
    /// same view with fewer samples adds only the difference (how a window refines).
    pub spp: u32,
    /// Stop adding samples after this many seconds even if `spp` is not reached,
    /// (0, 1e6]; at least one pass is always made.
    pub time_limit: Option<f64>,
    /// Surface and fog interactions a path may have, [1, 256].
    pub max_bounces: u32,
    /// Lens radius in world units for depth of field, [0, 1e6] (0: pinhole).
    pub aperture: f64,
    /// Distance to the plane in focus, [1e-9, 1e12]; absent: the camera's target.
    pub focus_distance: Option<f64>,
    /// Run the edge-aware à-trous denoiser over the result (guided by albedo, normal,
    /// depth).
    pub denoise: bool,
    /// Sampler seed (independent noise for another seed; equal seeds give equal images).
    pub seed: u32,
    /// Trace on the GPU (fathom-gpu's WGSL port of the same integrator, accumulating on the
    /// device); what it does not support yet is refused by name.
    pub gpu: bool,
}

impl Default for PathRequest {
    fn default() -> Self {
        PathRequest {
            spp: 64,
            time_limit: None,
            max_bounces: 8,
            aperture: 0.0,
            focus_distance: None,
            denoise: false,
            seed: 0,
            gpu: false,
        }
    }
}

/// What to render: one frame, or one region of it.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct RenderRequest {
    /// One eye's view width, pixels (the output is twice as wide or tall for stereo).
    pub width: u32,
    /// One eye's view height, pixels.
    pub height: u32,
    /// Mono, side-by-side or omni-directional stereo.
    pub projection: Projection,
    /// Samples per pixel along each axis, [1, 4].
    pub supersample: u32,
    /// Run the cone-marching depth prepass (tracer and GPU).
    pub prepass: bool,
    /// Sphere-tracing step rule (tracer; the GPU always uses the enhanced rule).
    pub tracer: TracerRule,
    /// Screen-space ambient occlusion strength, [0, 4] (0: off; never for ODS).
    pub ssao: f32,
    /// Distance fog density per world unit, overriding the scene's `render.fog`, [0, 1e6].
    pub fog: Option<f64>,
    /// Depth, ids and steps only: no colouring, no SSAO, no fog (tracer only).
    pub geometry_only: bool,
    /// The renderer.
    pub backend: Backend,
    /// Worker threads of the CPU renderers (default: all cores), [1, 1024].
    pub threads: Option<usize>,
    /// Only this rectangle of the output image (the whole image when absent).
    pub region: Option<Rect>,
    /// Octree settings (used by [`Backend::Octree`]).
    pub octree: OctreeSettings,
    /// Volume settings (used by [`Backend::Volume`]).
    pub volume: VolumeSettings,
    /// Path-tracing settings (used by [`Backend::Path`]).
    pub path: PathRequest,
}

impl Default for RenderRequest {
    fn default() -> Self {
        RenderRequest {
            width: 1280,
            height: 720,
            projection: Projection::Mono,
            supersample: 1,
            prepass: true,
            tracer: TracerRule::Enhanced,
            ssao: 0.0,
            fog: None,
            geometry_only: false,
            backend: Backend::Trace,
            threads: None,
            region: None,
            octree: OctreeSettings::default(),
            volume: VolumeSettings::default(),
            path: PathRequest::default(),
        }
    }
}

/// Why a request was refused, before anything was allocated or rendered.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum RequestError {
    /// Size, projection, supersampling, SSAO or region out of range.
    #[error(transparent)]
    Options(#[from] OptionsError),
    /// The thread count (given) is outside [1, 1024].
    #[error("threads = {0} is out of range [1, 1024]")]
    Threads(usize),
    /// The fog density (given) is not finite or outside [0, 1e6].
    #[error("fog = {0} is out of range [0, 1e6] (density per world unit)")]
    Fog(f64),
    /// The octree backend was asked for a stereo view.
    #[error(
        "stereo is not supported by the octree renderer (it renders one mono view); use the sphere tracer for stereo"
    )]
    OctreeStereo,
    /// The octree backend was asked for a geometry-only frame.
    #[error("the octree renderer does not render geometry-only frames")]
    OctreeGeometryOnly,
    /// The volume backend was asked for a stereo or geometry-only frame.
    #[error(
        "stereo and geometry-only frames are not supported by the volume renderer (it renders one mono view)"
    )]
    VolumeView,
    /// A volume setting is out of its range.
    #[error("volume {name} = {value} is out of range {range}")]
    VolumeSetting {
        /// The setting's name.
        name: &'static str,
        /// The value given.
        value: f64,
        /// The setting's range, as text.
        range: &'static str,
    },
    /// The path backend was asked for stereo, supersampling, SSAO or a geometry-only frame.
    #[error(
        "the path tracer renders one mono view with its own antialiasing: stereo, \
         supersampling, SSAO and geometry-only frames are not supported with it (use more \
         samples per pixel instead of supersampling)"
    )]
    PathView,
    /// A path-tracing setting is out of its range.
    #[error("path {name} = {value} is out of range {range}")]
    PathSetting {
        /// The setting's name.
        name: &'static str,
        /// The value given.
        value: f64,
        /// The setting's range, as text.
        range: &'static str,
    },
    /// The octree's settle frames (given) are above 100000.
    #[error("octree settle_frames = {0} is out of range [0, 100000]")]
    SettleFrames(usize),
    /// The octree settings are invalid.
    #[error(transparent)]
    Octree(#[from] OctreeError),
}

impl RenderRequest {
    /// Checks the path tracer's view and settings.
    fn validate_path(&self) -> Result<(), RequestError> {
        if self.projection != Projection::Mono
            || self.supersample != 1
            || self.ssao != 0.0
            || self.geometry_only
        {
            return Err(RequestError::PathView);
        }
        let p = &self.path;
        let check = |name, value: f64, ok: bool, range| {
            if ok && value.is_finite() {
                Ok(())
            } else {
                Err(RequestError::PathSetting { name, value, range })
            }
        };
        check(
            "spp",
            p.spp as f64,
            (1..=MAX_PATH_SPP).contains(&p.spp),
            "[1, 1048576]",
        )?;
        if let Some(t) = p.time_limit {
            check("time_limit", t, t > 0.0 && t <= 1e6, "(0, 1e6] seconds")?;
        }
        check(
            "max_bounces",
            p.max_bounces as f64,
            (1..=256).contains(&p.max_bounces),
            "[1, 256]",
        )?;
        check(
            "aperture",
            p.aperture,
            (0.0..=1e6).contains(&p.aperture),
            "[0, 1e6]",
        )?;
        if let Some(f) = p.focus_distance {
            check(
                "focus_distance",
                f,
                (1e-9..=1e12).contains(&f),
                "[1e-9, 1e12]",
            )?;
        }
        Ok(())
    }

    /// The CPU tracer's options for this request (also the size limits every backend obeys).
    pub fn trace_options(&self) -> Options {
        Options {
            width: self.width,
            height: self.height,
            method: match self.tracer {
                TracerRule::Basic => Method::Basic,
                TracerRule::Enhanced => Method::Enhanced,
            },
            prepass: self.prepass,
            supersample: self.supersample,
            geometry_only: self.geometry_only,
            ssao: self.ssao,
            projection: self.projection,
        }
    }

    /// Checks every field against its documented range.
    pub fn validate(&self) -> Result<(), RequestError> {
        let o = self.trace_options();
        o.validate()?;
        if let Some(r) = self.region {
            o.check_region(r)?;
        }
        if let Some(t) = self.threads
            && !(1..=1024).contains(&t)
        {
            return Err(RequestError::Threads(t));
        }
        if let Some(f) = self.fog
            && !(f.is_finite() && (0.0..=1e6).contains(&f))
        {
            return Err(RequestError::Fog(f));
        }
        if self.backend == Backend::Volume {
            if self.projection != Projection::Mono || self.geometry_only {
                return Err(RequestError::VolumeView);
            }
            let v = &self.volume;
            let check = |name, value: f64, ok: bool, range| {
                if ok && value.is_finite() {
                    Ok(())
                } else {
                    Err(RequestError::VolumeSetting { name, value, range })
                }
            };
            check(
                "grid",
                v.grid as f64,
                (2..=512).contains(&v.grid),
                "[2, 512]",
            )?;
            check(
                "smooth",
                v.smooth as f64,
                (0.0..=64.0).contains(&v.smooth),
                "[0, 64]",
            )?;
            check(
                "density_scale",
                v.density_scale as f64,
                (0.0..=1e6).contains(&v.density_scale),
                "[0, 1e6]",
            )?;
            check(
                "albedo",
                v.albedo as f64,
                (0.0..=1.0).contains(&v.albedo),
                "[0, 1]",
            )?;
            check("g", v.g as f64, v.g > -1.0 && v.g < 1.0, "(-1, 1)")?;
            check(
                "spp",
                v.spp as f64,
                (1..=4096).contains(&v.spp),
                "[1, 4096]",
            )?;
        }
        if self.backend == Backend::Path {
            self.validate_path()?;
        }
        if self.backend == Backend::Octree {
            if self.projection != Projection::Mono {
                return Err(RequestError::OctreeStereo);
            }
            if self.geometry_only {
                return Err(RequestError::OctreeGeometryOnly);
            }
            if self.octree.settle_frames > 100_000 {
                return Err(RequestError::SettleFrames(self.octree.settle_frames));
            }
            self.octree_config().validate()?;
        }
        Ok(())
    }

    /// The octree explorer's settings for this request (supersampled size; threads default to
    /// the machine's cores; the root is the exact cube when given, else fitted in [-4, 4]^3).
    pub fn octree_config(&self) -> OctreeViewConfig {
        let o = &self.octree;
        OctreeViewConfig {
            width: self.width * self.supersample,
            height: self.height * self.supersample,
            fidelity: o.fidelity,
            threads: self
                .threads
                .unwrap_or_else(|| std::thread::available_parallelism().map_or(2, |n| n.get())),
            max_memory: o.max_memory,
            traversal: o.traversal,
            subdivide_ms: o.subdivide_ms,
            target_fps: o.target_fps,
            unify_every: o.unify_every,
            beam: o.beam,
            beam_min: o.beam_min,
            planes: o.planes,
            fovea: o.fovea,
            smooth: o.smooth,
            fill_px: o.fill_px,
            root: match o.root {
                Some(c) => RootSpec::from_cube(Some(c)),
                None => RootSpec::Fit { half: o.fit_half },
            },
            ..OctreeViewConfig::default()
        }
    }

    /// Size of the output image (both eyes for stereo).
    pub fn output_size(&self) -> (u32, u32) {
        self.projection.output_size(self.width, self.height)
    }

    /// The rectangle this request renders (its region, or the whole output image).
    pub fn rect(&self) -> Rect {
        let (w, h) = self.output_size();
        self.region.unwrap_or(Rect::full(w, h))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn requests_round_trip_through_json_and_refuse_bad_values() {
        let r = RenderRequest {
            projection: Projection::SideBySide {
                eye_separation: 0.1,
            },
            region: Some(Rect {
                x: 8,
                y: 0,
                width: 16,
                height: 4,
            }),
            backend: Backend::Gpu,
            ..RenderRequest::default()
        };
        let text = serde_json::to_string(&r).unwrap();
        assert_eq!(serde_json::from_str::<RenderRequest>(&text).unwrap(), r);
        assert!(serde_json::from_str::<RenderRequest>(r#"{"widht": 3}"#).is_err());
        r.validate().unwrap();
        let bad = |f: &dyn Fn(&mut RenderRequest)| {
            let mut b = RenderRequest::default();
            f(&mut b);
            b.validate().unwrap_err()
        };
        assert!(matches!(
            bad(&|b| b.threads = Some(0)),
            RequestError::Threads(0)
        ));
        assert!(matches!(
            bad(&|b| b.fog = Some(f64::NAN)),
            RequestError::Fog(_)
        ));
        assert!(matches!(
            bad(&|b| b.width = 0),
            RequestError::Options(OptionsError::Empty { .. })
        ));
        let e = bad(&|b| {
            b.region = Some(Rect {
                x: 1270,
                y: 0,
                width: 20,
                height: 1,
            })
        });
        assert!(
            e.to_string().contains("not inside the 1280x720 image"),
            "{e}"
        );
        assert!(matches!(
            bad(&|b| {
                b.backend = Backend::Octree;
                b.projection = Projection::Ods {
                    eye_separation: 0.1,
                }
            }),
            RequestError::OctreeStereo
        ));
    }
}
