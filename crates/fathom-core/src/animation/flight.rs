//! Flight paths: named camera paths kept in the scene file, as keyframes (position,
//! orientation, field of view, and optionally any parameter by its path), and the camera they
//! give at any time.
//!
//! - **Position**: a centripetal Catmull-Rom spline through the keys' eyes ([`spline`]).
//! - **Orientation**: squad through the keys' orientations (from eye, target and up).
//! - **Field of view and parameters**: Catmull-Rom Hermites through the keys that set them
//!   (the field of view in `ln tan(fov / 2)`), clamped to the parameter's declared range.
//! - **Scale-aware timing** (after the OptFlowCam paper, Piening et al. 2024, and
//!   Mandelbulber2 issue #961): each key has a scale, its distance to the surface (given, or
//!   the distance estimate at its eye). Within a segment the scale is interpolated along the
//!   chord, and the path is paced by a perceived length: distance travelled divided by the
//!   scale, plus the angle turned and the change of `ln tan(fov / 2)`. Equal times cover equal
//!   perceived lengths, so a dive between keys 10^6 apart in scale moves through equal factors
//!   of scale in equal times (the log of the distance to the surface changes linearly) instead
//!   of spending almost all its time at the large end.
//! - **Timing**: a path lasts `duration` seconds; keys may be pinned to a `time`, and the keys
//!   between pinned ones are spaced by perceived length. `ease_in` / `ease_out` seconds of
//!   constant acceleration at the ends. [`FlightPath::retime`] and [`FlightPath::pin`] retime.
//!
//! [`FlightPath::prepare`] turns a path into a [`Flight`], which [`Flight::sample`]s a
//! [`Pose`] (camera and parameter values) at any time; the CLI (`fathom render --path`) and the
//! explorer's timeline both sample it.

pub mod spline;

use crate::camera::Camera;
use crate::param_path::{ParamPath, ParamRange};
use crate::param_resolve::Resolved;
use crate::scene::Scene;
use crate::tape::Tape;
use glam::{DMat3, DQuat, DVec3};
use spline::CentripetalSegment;
use std::collections::BTreeMap;

pub use crate::flight_path::{
    FlightError, FlightPath, Keyframe, MAX_DURATION, MAX_KEY_PARAMS, MAX_KEYS, MAX_PATHS,
};

/// Samples per segment of the table that paces a path by perceived length.
const TABLE_SAMPLES: usize = 64;

/// The distance estimate at `eye`: the scale a key recorded there gets. `None` where the
/// estimate is not a positive finite number (inside the surface).
pub fn surface_scale(tape: &Tape, eye: DVec3) -> Option<f64> {
    let d = tape.eval_f64([eye.x, eye.y, eye.z]).d;
    (d.is_finite() && d > 0.0).then_some(d)
}

impl FlightPath {
    /// A path through `keys` lasting `duration` seconds, scale-aware, without easing.
    pub fn new(name: &str, duration: f64, keys: Vec<Keyframe>) -> FlightPath {
        FlightPath {
            name: name.into(),
            duration,
            ease_in: 0.0,
            ease_out: 0.0,
            scale_aware: true,
            keys,
        }
    }

    /// A zoom into `target` from distance `start` along unit `dir` down to `start / depth`:
    /// the same cameras as [`crate::camera_path::CameraPath::Zoom`], as a two-key path.
    pub fn zoom(target: DVec3, dir: DVec3, start: f64, depth: f64, fov: f64) -> FlightPath {
        let up = if dir.cross(DVec3::Y).length() > 1e-3 {
            DVec3::Y
        } else {
            DVec3::X
        };
        // Each key looks at a point `start` away along the view (through `target`), so its
        // orientation is exact even when the eye is 1e-12 from the target.
        let key = |d: f64| Keyframe {
            eye: target + dir * d,
            target: target + dir * (d - start),
            up,
            fov,
            time: None,
            scale: Some(d),
            params: BTreeMap::new(),
        };
        FlightPath::new("zoom", 1.0, vec![key(start), key(start / depth)])
    }

    /// Changes the duration, scaling pinned times and easing with it.
    pub fn retime(&mut self, duration: f64) {
        let f = duration / self.duration;
        self.duration = duration;
        self.ease_in *= f;
        self.ease_out *= f;
        for k in &mut self.keys {
            if let Some(t) = &mut k.time {
                *t *= f;
            }
        }
    }

    /// Pins key `index` to `time` (or unpins it with `None`), checking the order against
    /// the other pinned keys; on error nothing changes.
    pub fn pin(&mut self, index: usize, time: Option<f64>, scene: &Scene) -> Result<(), String> {
        let old = self
            .keys
            .get(index)
            .ok_or_else(|| format!("path `{}` has no key {index}", self.name))?
            .time;
        self.keys[index].time = time;
        if let Err((at, e)) = self.validate(scene) {
            self.keys[index].time = old;
            return Err(format!("{at}: {e}"));
        }
        Ok(())
    }

    /// Prepares the path for sampling. Keys without a `scale` take the distance estimate of
    /// `tape` at their eye (or their distance to the target where there is no tape or the eye
    /// is inside). Assumes [`FlightPath::validate`] passed for `scene`; the parameter paths
    /// are resolved against it.
    pub fn prepare(&self, scene: &Scene, tape: Option<&Tape>) -> Result<Flight, FlightError> {
        self.validate(scene).map_err(|(_, e)| e)?;
        let mut qs: Vec<DQuat> = self.keys.iter().map(orientation).collect();
        spline::align_signs(&mut qs);
        let controls = spline::squad_controls(&qs);
        let keys: Vec<PreparedKey> = self
            .keys
            .iter()
            .zip(&qs)
            .map(|(k, &q)| {
                let focus = (k.target - k.eye).length();
                let scale = k
                    .scale
                    .or_else(|| tape.and_then(|t| surface_scale(t, k.eye)))
                    .unwrap_or(focus);
                PreparedKey {
                    eye: k.eye,
                    q,
                    focus,
                    lfov: (k.fov.to_radians() * 0.5).tan().ln(),
                    scale,
                }
            })
            .collect();
        let fov_knots: Vec<(f64, f64)> = keys
            .iter()
            .enumerate()
            .map(|(i, k)| (i as f64, k.lfov))
            .collect();
        let uniform_scale = if self.scale_aware {
            None
        } else {
            let mean_ln = keys.iter().map(|k| k.scale.ln()).sum::<f64>() / keys.len() as f64;
            Some(mean_ln.exp())
        };
        let n = keys.len();
        let segments: Vec<Segment> = (0..n - 1)
            .map(|i| {
                let curve = CentripetalSegment::new(
                    i.checked_sub(1).map(|j| keys[j].eye),
                    keys[i].eye,
                    keys[i + 1].eye,
                    keys.get(i + 2).map(|k| k.eye),
                );
                Segment::new(i, curve, &keys, &controls, &fov_knots, uniform_scale)
            })
            .collect();
        let mut tracks: BTreeMap<&str, Vec<(f64, f64)>> = BTreeMap::new();
        for (i, k) in self.keys.iter().enumerate() {
            for (path, &v) in &k.params {
                tracks.entry(path).or_default().push((i as f64, v));
            }
        }
        let tracks = tracks
            .into_iter()
            .map(|(path, knots)| {
                let resolved = ParamPath::parse(path)
                    .and_then(|p| p.resolve(scene))
                    .map_err(FlightError::Param)?;
                Ok(Track {
                    path: path.to_string(),
                    resolved,
                    knots,
                })
            })
            .collect::<Result<Vec<_>, FlightError>>()?;
        let key_times = key_times(self, &segments);
        Ok(Flight {
            name: self.name.clone(),
            duration: self.duration,
            ease_in: self.ease_in,
            ease_out: self.ease_out,
            keys,
            controls,
            fov_knots,
            segments,
            key_times,
            tracks,
        })
    }
}

/// A key's orientation: the rotation taking the camera's local axes (right = x, up = y,
/// forward = -z) to the key's view.
fn orientation(k: &Keyframe) -> DQuat {
    let f = (k.target - k.eye).normalize();
    let r = f.cross(k.up).normalize();
    let u = r.cross(f);
    DQuat::from_mat3(&DMat3::from_cols(r, u, -f)).normalize()
}

/// The times of the keys on the path's clock (before easing): pinned keys where pinned, the
/// first at 0 and the last at the duration, the rest spaced by perceived length in between.
fn key_times(p: &FlightPath, segments: &[Segment]) -> Vec<f64> {
    let n = p.keys.len();
    let mut times = vec![0.0; n];
    let anchors: Vec<(usize, f64)> = std::iter::once((0, 0.0))
        .chain(
            p.keys
                .iter()
                .enumerate()
                .filter_map(|(i, k)| k.time.filter(|_| i > 0 && i + 1 < n).map(|t| (i, t))),
        )
        .chain(std::iter::once((n - 1, p.duration)))
        .collect();
    for w in anchors.windows(2) {
        let ((a, ta), (b, tb)) = (w[0], w[1]);
        let total: f64 = segments[a..b].iter().map(|s| s.length).sum();
        let mut acc = 0.0;
        times[a] = ta;
        for (k, seg) in segments.iter().enumerate().take(b).skip(a) {
            acc += if total > 0.0 {
                seg.length / total
            } else {
                1.0 / (b - a) as f64
            };
            times[k + 1] = ta + (tb - ta) * acc;
        }
        times[b] = tb;
    }
    times
}

#[derive(Clone, Debug, PartialEq)]
struct PreparedKey {
    eye: DVec3,
    q: DQuat,
    focus: f64,
    lfov: f64,
    scale: f64,
}

/// One segment between keys, with its pacing table.
#[derive(Clone, Debug)]
struct Segment {
    index: usize,
    curve: CentripetalSegment,
    /// Scales at the ends, or one scale throughout (not scale-aware).
    scales: (f64, f64),
    /// Perceived length from the segment's start at u = j / TABLE_SAMPLES.
    table: Vec<f64>,
    /// Scale at the same samples.
    scale_at: Vec<f64>,
    length: f64,
    scale_aware: bool,
}

impl PartialEq for Segment {
    fn eq(&self, o: &Self) -> bool {
        self.index == o.index && self.table == o.table && self.scales == o.scales
    }
}

/// The logarithmic mean of two positive numbers: the exact `|dp| / h` integral over a step
/// along which `h` changes linearly is `|dp| / logmean`.
/// The largest perceived length one step of a segment's table counts: a key scale of 1e-300
/// next to keys metres apart makes a step's length overflow, and sums over a path of
/// infinities have no proportions. Capped, every table and every path total stays finite.
const MAX_STEP_LENGTH: f64 = 1e250;

fn log_mean(a: f64, b: f64) -> f64 {
    let r = a / b;
    if (r - 1.0).abs() < 1e-9 {
        0.5 * (a + b)
    } else {
        (a - b) / r.ln()
    }
}

impl Segment {
    fn new(
        index: usize,
        curve: CentripetalSegment,
        keys: &[PreparedKey],
        controls: &[DQuat],
        fov_knots: &[(f64, f64)],
        uniform_scale: Option<f64>,
    ) -> Segment {
        let (k1, k2) = (&keys[index], &keys[index + 1]);
        let scales = match uniform_scale {
            Some(s) => (s, s),
            None => (k1.scale, k2.scale),
        };
        let mut seg = Segment {
            index,
            curve,
            scales,
            table: Vec::with_capacity(TABLE_SAMPLES + 1),
            scale_at: Vec::with_capacity(TABLE_SAMPLES + 1),
            length: 0.0,
            scale_aware: uniform_scale.is_none(),
        };
        let mut acc = 0.0;
        let mut prev: Option<(DVec3, f64, DQuat, f64)> = None;
        for j in 0..=TABLE_SAMPLES {
            let u = j as f64 / TABLE_SAMPLES as f64;
            let p = seg.curve.at(u);
            let h = seg.scale(u, p);
            let q = spline::squad(k1.q, k2.q, controls[index], controls[index + 1], u);
            let lf = spline::scalar_at(fov_knots, index as f64 + u);
            if let Some((p0, h0, q0, lf0)) = prev {
                let dp = (p - p0).length() / log_mean(h0, h);
                let dr = spline::angle_between(q0, q);
                let df = lf - lf0;
                // hypot: a scale of 1e-200 makes dp 1e200, whose square is infinite.
                let step = dp.hypot(dr).hypot(df);
                acc += if step.is_finite() {
                    step.min(MAX_STEP_LENGTH)
                } else {
                    MAX_STEP_LENGTH
                };
            }
            seg.table.push(acc);
            seg.scale_at.push(h);
            prev = Some((p, h, q, lf));
        }
        seg.length = acc;
        seg
    }

    /// The scale at `u` (point `p`): interpolated between the keys' scales by how far along
    /// the chord `p` is, so on a straight dive it is the distance to the point dived into.
    fn scale(&self, u: f64, p: DVec3) -> f64 {
        let (h1, h2) = self.scales;
        if h1 == h2 {
            return h1;
        }
        let (a, b) = (self.curve.at(0.0), self.curve.at(1.0));
        let c = b - a;
        let cc = c.length_squared();
        // The fraction along the chord measured from the nearer end, so the scale near a key
        // 1e-10 of the other's keeps its digits.
        let (from_start, from_end) = if cc > 0.0 {
            ((p - a).dot(c) / cc, (b - p).dot(c) / cc)
        } else {
            (u, 1.0 - u)
        };
        if from_start <= 0.5 {
            h1 + (h2 - h1) * from_start.clamp(0.0, 1.0)
        } else {
            h2 + (h1 - h2) * from_end.clamp(0.0, 1.0)
        }
    }

    /// The parameter u at which the perceived length from the start is `fraction` of the
    /// segment's.
    fn u_at(&self, fraction: f64) -> f64 {
        if self.length <= 0.0 {
            return fraction.clamp(0.0, 1.0);
        }
        let target = fraction.clamp(0.0, 1.0) * self.length;
        let j = self
            .table
            .partition_point(|&l| l < target)
            .clamp(1, TABLE_SAMPLES);
        let (l0, l1) = (self.table[j - 1], self.table[j]);
        let phi = if l1 > l0 {
            (target - l0) / (l1 - l0)
        } else {
            0.0
        };
        let (u0, u1) = (
            (j - 1) as f64 / TABLE_SAMPLES as f64,
            j as f64 / TABLE_SAMPLES as f64,
        );
        // Within a sample step the perceived length grows with the log of the scale (the
        // scale changing linearly with the distance travelled): find the point whose scale is
        // the geometric interpolation, on the curve itself (its speed varies within a step).
        let (h0, h1) = (self.scale_at[j - 1], self.scale_at[j]);
        if !(self.scale_aware && ((h0 - h1) / h0).abs() > 1e-12) {
            return u0 + phi * (u1 - u0);
        }
        let want = h0.powf(1.0 - phi) * h1.powf(phi);
        let (mut lo, mut hi) = (u0, u1);
        for _ in 0..60 {
            let mid = 0.5 * (lo + hi);
            let h = self.scale(mid, self.curve.at(mid));
            // Move towards the end while the scale has not yet reached `want`.
            if (h - want) * (h0 - h1) > 0.0 {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        0.5 * (lo + hi)
    }
}

/// A parameter set by some of a path's keys.
#[derive(Clone, Debug, PartialEq)]
struct Track {
    path: String,
    resolved: Resolved,
    /// (key index, value) of the keys that set it.
    knots: Vec<(f64, f64)>,
}

/// A flight path prepared for sampling.
#[derive(Clone, Debug, PartialEq)]
pub struct Flight {
    name: String,
    duration: f64,
    ease_in: f64,
    ease_out: f64,
    keys: Vec<PreparedKey>,
    controls: Vec<DQuat>,
    fov_knots: Vec<(f64, f64)>,
    segments: Vec<Segment>,
    key_times: Vec<f64>,
    tracks: Vec<Track>,
}

/// The path clock (before easing) at wall time `t` of a path `duration` seconds long that
/// accelerates from rest over its first `ease_in` seconds and comes to rest over its last
/// `ease_out` (constant acceleration): the clock keyframe times (`Keyframe::time`) are on.
pub fn path_clock(duration: f64, ease_in: f64, ease_out: f64, t: f64) -> f64 {
    let (d, a, b) = (duration, ease_in, ease_out);
    let t = t.clamp(0.0, d);
    if a == 0.0 && b == 0.0 {
        return t;
    }
    let v = d / (d - 0.5 * a - 0.5 * b);
    if t < a {
        v * t * t / (2.0 * a)
    } else if t > d - b {
        d - v * (d - t) * (d - t) / (2.0 * b)
    } else {
        v * (t - 0.5 * a)
    }
}

/// The state of a flight at one time.
#[derive(Clone, Debug, PartialEq)]
pub struct Pose {
    /// The camera at this time.
    pub camera: Camera,
    /// The exact unit view direction (the camera's look-at point may be so close to the eye
    /// at a deep zoom that `target - eye` resolves the direction only to ~1e-6).
    pub forward: DVec3,
    /// The interpolated scale (distance to the surface) at the eye.
    pub scale: f64,
    /// Values of the parameters the keys set, in the order of [`Flight::params`].
    pub params: Vec<f64>,
    /// The segment the time falls in: from key `segment` to `segment + 1`.
    pub segment: usize,
    /// The spline parameter in that segment, [0, 1].
    pub u: f64,
}

impl Flight {
    /// The path's name.
    pub fn name(&self) -> &str {
        &self.name
    }

    /// Length in seconds.
    pub fn duration(&self) -> f64 {
        self.duration
    }

    /// Each key's time in seconds from the start (after easing): where the timeline shows it.
    pub fn key_times(&self) -> Vec<f64> {
        self.key_times.iter().map(|&t| self.unease(t)).collect()
    }

    /// The parameter paths the keys set, in the order of [`Pose::params`].
    pub fn params(&self) -> Vec<&str> {
        self.tracks.iter().map(|t| t.path.as_str()).collect()
    }

    /// Where a key recorded at time `t` goes in the key list (after the keys before `t`).
    pub fn insert_index(&self, t: f64) -> usize {
        let tau = self.ease(t);
        self.key_times.partition_point(|&k| k <= tau)
    }

    /// Path clock (before easing) at wall time `t`.
    fn ease(&self, t: f64) -> f64 {
        path_clock(self.duration, self.ease_in, self.ease_out, t)
    }

    /// Wall time at path clock `tau` (the inverse of `ease`).
    fn unease(&self, tau: f64) -> f64 {
        let (d, a, b) = (self.duration, self.ease_in, self.ease_out);
        if a == 0.0 && b == 0.0 {
            return tau;
        }
        let v = d / (d - 0.5 * a - 0.5 * b);
        if tau < v * a / 2.0 {
            (2.0 * a * tau / v).sqrt()
        } else if tau > d - v * b / 2.0 {
            d - (2.0 * b * (d - tau) / v).max(0.0).sqrt()
        } else {
            tau / v + 0.5 * a
        }
    }

    /// The pose at `t` seconds from the start (clamped to the path).
    pub fn sample(&self, t: f64) -> Pose {
        let tau = self.ease(t);
        let n = self.keys.len();
        let i = (self.key_times.partition_point(|&k| k <= tau).max(1) - 1).min(n - 2);
        let (t0, t1) = (self.key_times[i], self.key_times[i + 1]);
        let f = if t1 > t0 { (tau - t0) / (t1 - t0) } else { 0.0 };
        let seg = &self.segments[i];
        let u = seg.u_at(f);
        self.pose_at(i, u)
    }

    fn pose_at(&self, i: usize, u: f64) -> Pose {
        let seg = &self.segments[i];
        let (k1, k2) = (&self.keys[i], &self.keys[i + 1]);
        let eye = seg.curve.at(u);
        let q = spline::squad(k1.q, k2.q, self.controls[i], self.controls[i + 1], u);
        let forward = q * DVec3::NEG_Z;
        let up = q * DVec3::Y;
        let focus = (k1.focus.ln() * (1.0 - u) + k2.focus.ln() * u).exp();
        let lf = spline::scalar_at(&self.fov_knots, i as f64 + u);
        let fov = (2.0 * lf.exp().atan()).to_degrees();
        let x = i as f64 + u;
        let params = self
            .tracks
            .iter()
            .map(|t| {
                let v = spline::scalar_at(&t.knots, x);
                clamp_to(&t.resolved.range, v)
            })
            .collect();
        Pose {
            camera: Camera {
                eye,
                target: eye + forward * focus,
                up,
                fov,
            },
            forward,
            scale: seg.scale(u, eye),
            params,
            segment: i,
            u,
        }
    }

    /// Samples the pose at `t` and writes it into `scene`: the camera and the parameters the
    /// keys set (parameter-only edits: a session re-bakes, never recompiles). Returns the pose.
    pub fn apply(&self, t: f64, scene: &mut Scene) -> Pose {
        let pose = self.sample(t);
        scene.camera = pose.camera.clone();
        for (track, &v) in self.tracks.iter().zip(&pose.params) {
            track.resolved.set(scene, v);
        }
        pose
    }
}

fn clamp_to(range: &ParamRange, v: f64) -> f64 {
    range.clamp(v).unwrap_or(v)
}

impl Scene {
    /// The flight path named `name`, or an error listing the scene's paths.
    pub fn path(&self, name: &str) -> Result<&FlightPath, FlightError> {
        self.paths
            .iter()
            .find(|p| p.name == name)
            .ok_or_else(|| FlightError::Unknown {
                name: name.into(),
                hint: if self.paths.is_empty() {
                    "this scene has no paths (add `paths: [FlightPath(name: ..., keys: [...])]`; \
                     see docs/scene-format.md)"
                        .into()
                } else {
                    crate::call_serde::did_you_mean(
                        name,
                        self.paths.iter().map(|p| p.name.as_str()),
                    )
                },
            })
    }
}

#[cfg(test)]
mod tests;
