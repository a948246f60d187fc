//! Flight paths as the scene file keeps them: named camera paths of keyframes (eye, target,
//! up, field of view, an optional pinned time and scale, and parameter values by path), their
//! limits and what can be wrong with them. Plain data, below the scene model that holds it;
//! preparing and sampling a path against a scene is [`crate::flight`].

use crate::camera::{Camera, CameraError};
use crate::param_path::ParamPathError;
use glam::DVec3;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use thiserror::Error;

/// Most flight paths in one scene.
pub const MAX_PATHS: usize = 64;
/// Most keyframes in one path.
pub const MAX_KEYS: usize = 4096;
/// Most parameter values on one keyframe.
pub const MAX_KEY_PARAMS: usize = 64;
/// Longest path, in seconds.
pub const MAX_DURATION: f64 = 1e6;

fn default_duration() -> f64 {
    10.0
}
fn default_up() -> DVec3 {
    DVec3::Y
}
fn default_fov() -> f64 {
    45.0
}
fn yes() -> bool {
    true
}
fn is_true(b: &bool) -> bool {
    *b
}
fn is_zero(x: &f64) -> bool {
    *x == 0.0
}

/// A named camera path.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FlightPath {
    /// Name (`fathom render --path NAME`); unique within the scene.
    pub name: String,
    /// Length in seconds, (0, 1e6].
    #[serde(default = "default_duration")]
    pub duration: f64,
    /// Seconds of constant acceleration from rest at the start.
    #[serde(default, skip_serializing_if = "is_zero")]
    pub ease_in: f64,
    /// Seconds of constant deceleration to rest at the end.
    #[serde(default, skip_serializing_if = "is_zero")]
    pub ease_out: f64,
    /// Pace by distance relative to the surface (true) or by plain distance (false).
    #[serde(default = "yes", skip_serializing_if = "is_true")]
    pub scale_aware: bool,
    /// At least two.
    pub keys: Vec<Keyframe>,
}

/// One key of a flight path: a camera, and optionally values for any parameters.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Keyframe {
    /// Where the camera is, world units.
    pub eye: DVec3,
    /// A point looked at (the orientation comes from the direction; the distance is kept as
    /// the camera's focus distance).
    pub target: DVec3,
    /// The camera's up direction (need not be orthogonal to the view); +y when left out.
    #[serde(default = "default_up")]
    pub up: DVec3,
    /// Vertical field of view, degrees (0, 179].
    #[serde(default = "default_fov")]
    pub fov: f64,
    /// Pins this key to a time (seconds from the start); only keys between the first (at 0)
    /// and the last (at `duration`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub time: Option<f64>,
    /// The key's scale: its distance to the surface. Default: the distance estimate at the
    /// eye (or the distance to the target where there is none).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub scale: Option<f64>,
    /// Parameter values at this key, by parameter path (`"root.shape.power": 8.0`).
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    pub params: BTreeMap<String, f64>,
}

impl Keyframe {
    /// A key at a camera (no pinned time, scale or parameters).
    pub fn from_camera(c: &Camera) -> Keyframe {
        Keyframe {
            eye: c.eye,
            target: c.target,
            up: c.up,
            fov: c.fov,
            time: None,
            scale: None,
            params: BTreeMap::new(),
        }
    }

    /// The key's camera.
    pub fn camera(&self) -> Camera {
        Camera {
            eye: self.eye,
            target: self.target,
            up: self.up,
            fov: self.fov,
        }
    }
}

/// What is wrong with a flight path. The scene's error adds where (`paths[0].keys[2]`).
#[derive(Clone, Debug, PartialEq, Error)]
pub enum FlightError {
    /// The path's name is empty.
    #[error("a flight path needs a non-empty name")]
    NoName,
    /// Two paths of the scene share a name.
    #[error("two paths are named `{name}`; path names must be unique")]
    Duplicate {
        /// The shared name.
        name: String,
    },
    /// The scene has more than [`MAX_PATHS`] paths.
    #[error("{count} flight paths; the limit is {MAX_PATHS}")]
    TooManyPaths {
        /// How many paths the scene has.
        count: usize,
    },
    /// The path has fewer than two keys.
    #[error(
        "path `{name}` has {count} keyframe(s); its spline needs at least 2 (a start and an end)"
    )]
    TooFewKeys {
        /// The path's name.
        name: String,
        /// How many keys it has.
        count: usize,
    },
    /// The path has more than [`MAX_KEYS`] keys.
    #[error("path `{name}` has {count} keyframes; the limit is {MAX_KEYS}")]
    TooManyKeys {
        /// The path's name.
        name: String,
        /// How many keys it has.
        count: usize,
    },
    /// The duration is not in (0, [`MAX_DURATION`]] seconds.
    #[error("duration = {value} s is out of range (0, {MAX_DURATION}]")]
    Duration {
        /// The duration given, seconds.
        value: f64,
    },
    /// An ease time is negative, or the two together exceed the duration.
    #[error(
        "ease_in = {ease_in} s and ease_out = {ease_out} s must be >= 0 and together at most \
         the duration ({duration} s)"
    )]
    Ease {
        /// The ease-in time given, seconds.
        ease_in: f64,
        /// The ease-out time given, seconds.
        ease_out: f64,
        /// The path's duration, seconds.
        duration: f64,
    },
    /// A key's camera is invalid.
    #[error("{0}")]
    Camera(CameraError),
    /// The first or the last key pins a time (theirs are fixed at 0 and the duration).
    #[error(
        "time = {value}: only keys between the first and the last can be pinned (the first is \
         at 0 s, the last at the path's duration); remove `time` here"
    )]
    PinnedEnd {
        /// The pinned time given, seconds.
        value: f64,
    },
    /// A pinned time is not after the previous pinned key and before the path's end.
    #[error(
        "time = {value} s must lie after the previous pinned key ({after} s) and before the \
         path's end ({before} s)"
    )]
    TimeOrder {
        /// The pinned time given, seconds.
        value: f64,
        /// The previous pinned time (0 for the start), seconds.
        after: f64,
        /// The path's duration, seconds.
        before: f64,
    },
    /// A key's scale is not a finite number > 0.
    #[error("scale = {value} must be a finite number > 0 (the key's distance to the surface)")]
    Scale {
        /// The scale given.
        value: f64,
    },
    /// A key sets more than [`MAX_KEY_PARAMS`] parameters.
    #[error("{count} parameter values; the limit per key is {MAX_KEY_PARAMS}")]
    TooManyParams {
        /// How many parameters the key sets.
        count: usize,
    },
    /// A key's parameter path does not parse or name a number of the scene.
    #[error("{0}")]
    Param(ParamPathError),
    /// A key's parameter value is outside the parameter's declared range.
    #[error("`{path}` = {value} is out of range {range}")]
    ParamRange {
        /// The parameter path.
        path: String,
        /// The value given.
        value: f64,
        /// The declared range, as text.
        range: String,
    },
    /// A path asked for by name is not in the scene.
    #[error("no flight path is named `{name}`; {hint}")]
    Unknown {
        /// The name asked for.
        name: String,
        /// The nearest names the scene has, or a note that it has no paths.
        hint: String,
    },
}
