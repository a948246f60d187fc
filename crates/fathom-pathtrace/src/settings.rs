//! What a path-traced image asks for beyond the scene, its validation, and the crate's error.
//!
//! Everything here has a default that reproduces what the scene file means today (its sky, its
//! lights with the softness of their shadows, its fog, its materials through
//! [`crate::colour::Look::from_legacy`]), so `PathSettings::new(w, h)` renders any existing
//! scene. The extra knobs are what Blinn-Phong shading could not express: bounces, depth of
//! field, area lights, environment maps, participating media and per-node looks.

use crate::colour::{Look, LookError};
use crate::envmap::EnvMapError;
use crate::lights::{Environment, LightError, SphereLight};
use crate::medium::{Medium, MediumError};
use fathom_core::camera::CameraError;

/// Widest or tallest image.
pub const MAX_SIDE: u32 = 16384;
/// Most pixels in one image.
pub const MAX_PIXELS: u64 = 64 << 20;
/// Most bounces of one path.
pub const MAX_BOUNCES: u32 = 256;
/// Most sphere lights.
pub const MAX_SPHERE_LIGHTS: usize = 64;

/// How to path trace a scene.
#[derive(Clone, Debug)]
pub struct PathSettings {
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
    /// Surface and medium interactions a path may have, [1, MAX_BOUNCES].
    pub max_bounces: u32,
    /// Lens radius in world units (0: pinhole), [0, 1e6].
    pub aperture: f64,
    /// Distance to the plane of focus; `None`: the camera's eye-to-target distance.
    pub focus_distance: Option<f64>,
    /// Angular radius of the scene's directional lights in radians, [0, 0.5]; `None`: from
    /// `RenderSettings::shadow_softness` (see [`crate::lights`]).
    pub sun_radius: Option<f64>,
    /// Spherical area lights.
    pub sphere_lights: Vec<SphereLight>,
    /// `None`: the scene's sky gradient.
    pub environment: Option<Environment>,
    /// Scale of the environment's radiance where it lights surfaces (what the camera sees
    /// directly or in mirrors is unscaled); `None`: 1, except for the scene's own sky, where
    /// it is `ambient` / (the sky's mean luminance), so the sky lights the scene as strongly
    /// as today's ambient term did while the background keeps its colour. [0, 1e6].
    pub sky_light: Option<f64>,
    /// `None`: the scene's fog setting as a homogeneous medium (see [`default_fog`]).
    pub fog: Option<Medium>,
    /// One look per tape material (node, in tape order); `None`: the scene's materials.
    pub looks: Option<Vec<Look>>,
    /// Scene-wide sampler seed.
    pub seed: u32,
    /// Next-event estimation with MIS (the default); `false` finds lights only by BSDF
    /// sampling, which converges to the same image more slowly (for validation).
    pub light_sampling: bool,
}

impl PathSettings {
    /// Defaults for a `width` x `height` image.
    pub fn new(width: u32, height: u32) -> Self {
        PathSettings {
            width,
            height,
            max_bounces: 8,
            aperture: 0.0,
            focus_distance: None,
            sun_radius: None,
            sphere_lights: Vec::new(),
            environment: None,
            sky_light: None,
            fog: None,
            looks: None,
            seed: 0,
            light_sampling: true,
        }
    }
}

/// The medium today's `RenderSettings::fog` density means: homogeneous, slightly
/// forward-scattering, nearly white, so distant surfaces fade into lit haze.
pub fn default_fog(density: f64) -> Option<Medium> {
    (density > 0.0).then_some(Medium {
        density,
        kind: crate::medium::Density::Homogeneous,
        albedo: [0.9; 3],
        g: 0.3,
    })
}

/// Why settings were refused.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum SettingsError {
    /// Zero or too many pixels.
    #[error(
        "image size {width}x{height} is empty or exceeds {MAX_SIDE} per side / {MAX_PIXELS} pixels"
    )]
    Size {
        /// Requested width.
        width: u32,
        /// Requested height.
        height: u32,
    },
    /// A number out of its range.
    #[error("{field} = {value} is out of range {range}")]
    OutOfRange {
        /// The setting.
        field: &'static str,
        /// The value given.
        value: f64,
        /// The accepted range.
        range: &'static str,
    },
    /// The looks do not match the tape's materials.
    #[error("{given} looks given for a tape with {want} materials")]
    LookCount {
        /// Looks given.
        given: usize,
        /// Materials in the tape.
        want: usize,
    },
}

/// Why a path tracer could not be made or run.
#[derive(Debug, thiserror::Error)]
pub enum PathTraceError {
    /// Bad settings.
    #[error(transparent)]
    Settings(#[from] SettingsError),
    /// The scene's camera cannot form an image.
    #[error(transparent)]
    Camera(#[from] CameraError),
    /// A node's look (material or colouring) is bad.
    #[error("node {node}: {error}")]
    Look {
        /// Material index (node in tape order).
        node: usize,
        /// What is wrong.
        error: LookError,
    },
    /// A sphere light is bad.
    #[error(transparent)]
    Light(#[from] LightError),
    /// The fog is bad.
    #[error(transparent)]
    Medium(#[from] MediumError),
    /// An environment map could not be read.
    #[error(transparent)]
    EnvMap(#[from] EnvMapError),
    /// The caller cancelled; the accumulated image is as it was before the call.
    #[error("cancelled")]
    Cancelled,
}

impl PathSettings {
    /// Checks sizes and ranges (before anything is allocated).
    pub fn validate(&self) -> Result<(), PathTraceError> {
        let (w, h) = (self.width, self.height);
        if w == 0 || h == 0 || w > MAX_SIDE || h > MAX_SIDE || w as u64 * h as u64 > MAX_PIXELS {
            return Err(SettingsError::Size {
                width: w,
                height: h,
            }
            .into());
        }
        let range = |field, value: f64, lo: f64, hi: f64, text| {
            if value.is_finite() && (lo..=hi).contains(&value) {
                Ok(())
            } else {
                Err(SettingsError::OutOfRange {
                    field,
                    value,
                    range: text,
                })
            }
        };
        range(
            "max_bounces",
            self.max_bounces as f64,
            1.0,
            MAX_BOUNCES as f64,
            "[1, 256]",
        )?;
        range("aperture", self.aperture, 0.0, 1e6, "[0, 1e6]")?;
        if let Some(f) = self.focus_distance {
            range("focus_distance", f, 1e-9, 1e12, "[1e-9, 1e12]")?;
        }
        if let Some(k) = self.sky_light {
            range("sky_light", k, 0.0, 1e6, "[0, 1e6]")?;
        }
        if let Some(r) = self.sun_radius {
            range("sun_radius", r, 0.0, 0.5, "[0, 0.5] radians")?;
        }
        if self.sphere_lights.len() > MAX_SPHERE_LIGHTS {
            return Err(SettingsError::OutOfRange {
                field: "sphere_lights",
                value: self.sphere_lights.len() as f64,
                range: "at most 64 lights",
            }
            .into());
        }
        for (i, l) in self.sphere_lights.iter().enumerate() {
            l.validate(i)?;
        }
        if let Some(m) = &self.fog {
            m.validate()?;
        }
        if let Some(Environment::Map {
            strength, rotation, ..
        }) = &self.environment
        {
            range("environment strength", *strength, 0.0, 1e9, "[0, 1e9]")?;
            range(
                "environment rotation",
                *rotation,
                -1e3,
                1e3,
                "[-1e3, 1e3] radians",
            )?;
        }
        if let Some(Environment::Uniform(c)) = &self.environment {
            for v in c.to_array() {
                range("environment radiance", v, 0.0, 1e9, "[0, 1e9]")?;
            }
        }
        if let Some(looks) = &self.looks {
            for (node, l) in looks.iter().enumerate() {
                l.validate()
                    .map_err(|error| PathTraceError::Look { node, error })?;
            }
        }
        Ok(())
    }
}
