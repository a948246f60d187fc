//! One camera path through the medium: the radiance estimate of the volume rendering
//! equation with delta-tracked free flights, next-event estimation toward the environment
//! (uniform directions) and the sun at every real collision, phase-function sampling for the
//! path's continuation, the two environment strategies combined by multiple importance
//! sampling (power heuristic), emission at collisions, and Russian roulette after a few
//! bounces. Albedo weights the throughput (no absorption events), as in Mitsuba's volpath.

use crate::error::VolumeError;
use crate::light::{Environment, Sun};
use crate::medium::{Medium, TrackCounters};
use crate::sampling::{Stream, uniform_sphere};
use glam::Vec3;
use serde::Serialize;

const INV_4PI: f32 = 1.0 / (4.0 * std::f32::consts::PI);

/// The medium and how it is lit, with the path-length controls.
#[derive(Clone, Debug)]
pub struct VolumeScene {
    pub medium: Medium,
    pub environment: Environment,
    pub sun: Option<Sun>,
    /// Most real scattering events a path may have (light after more is not counted).
    pub max_depth: u32,
    /// Russian roulette starts after this many scattering events.
    pub rr_depth: u32,
}

/// Largest `max_depth` accepted.
pub const MAX_DEPTH: u32 = 100_000;

/// `x,y,z` as the command line writes a vector.
fn rgb(v: Vec3) -> String {
    format!("{},{},{}", v.x, v.y, v.z)
}

impl VolumeScene {
    /// Checks the path-length controls and the lights.
    pub fn validate(&self) -> Result<(), VolumeError> {
        if self.max_depth > MAX_DEPTH {
            return Err(VolumeError::param(
                "max depth",
                self.max_depth,
                format!("0..={MAX_DEPTH}"),
            ));
        }
        if self.rr_depth > MAX_DEPTH {
            return Err(VolumeError::param(
                "rr depth",
                self.rr_depth,
                format!("0..={MAX_DEPTH}"),
            ));
        }
        let unit = |v: Vec3| (v.length() - 1.0).abs() < 1e-3;
        let ok = |v: Vec3| v.is_finite() && v.min_element() >= 0.0 && v.max_element() <= 1e6;
        let env_ok = match self.environment {
            Environment::Constant(c) => ok(c),
            Environment::Sky { top, bottom, up } => ok(top) && ok(bottom) && unit(up),
        };
        if !env_ok {
            return Err(VolumeError::param(
                "environment",
                match self.environment {
                    Environment::Constant(c) => format!("constant {}", rgb(c)),
                    Environment::Sky { top, bottom, up } => {
                        format!("sky top {} bottom {} up {}", rgb(top), rgb(bottom), rgb(up))
                    }
                },
                "radiances in [0, 1e6] per channel",
            ));
        }
        if let Some(s) = self.sun
            && (!ok(s.radiance) || !unit(s.towards))
        {
            return Err(VolumeError::param(
                "sun",
                format!("towards {} radiance {}", rgb(s.towards), rgb(s.radiance)),
                "a unit direction and radiance in [0, 1e6] per channel",
            ));
        }
        Ok(())
    }
}

/// What paths did, summed over paths.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct PathCounters {
    pub paths: u64,
    /// Real scattering events (path vertices in the medium).
    pub scatter_events: u64,
    #[serde(flatten)]
    pub track: TrackCounters,
}

impl PathCounters {
    pub fn add(&mut self, o: &PathCounters) {
        self.paths += o.paths;
        self.scatter_events += o.scatter_events;
        self.track.add(&o.track);
    }
}

/// Power heuristic weight of a strategy with pdf `a` against one with pdf `b`.
#[inline]
fn power(a: f32, b: f32) -> f32 {
    let (a2, b2) = (a * a, b * b);
    if a2 + b2 > 0.0 { a2 / (a2 + b2) } else { 0.0 }
}

impl VolumeScene {
    /// The radiance arriving at `o` from direction `-d` (the camera ray `o + t d`, `d` unit).
    pub fn radiance(
        &self,
        mut o: Vec3,
        mut d: Vec3,
        rng: &mut Stream,
        c: &mut PathCounters,
    ) -> Vec3 {
        c.paths += 1;
        let m = &self.medium;
        let bbox = m.bbox();
        let nee_env = !self.environment.is_black();
        let mut l = Vec3::ZERO;
        let mut beta = Vec3::ONE;
        // The phase pdf of the direction the current ray was sampled with (None: camera ray).
        let mut phase_pdf: Option<f32> = None;
        let mut depth = 0u32;
        loop {
            let collision = bbox
                .intersect(o, d)
                .and_then(|(t0, t1)| m.sample_flight(o, d, t0, t1, rng, &mut c.track));
            let Some(hit) = collision else {
                let w = match phase_pdf {
                    Some(p) if nee_env => power(p, INV_4PI),
                    _ => 1.0,
                };
                l += beta * self.environment.radiance(d) * w;
                break;
            };
            c.scatter_events += 1;
            let x = o + d * hit.t;
            if let Some(e) = &m.emission {
                l += beta * (Vec3::ONE - m.albedo) * e.radiance(hit.density);
            }
            beta *= m.albedo;
            depth += 1;
            if depth > self.max_depth || beta == Vec3::ZERO {
                break;
            }
            let last = depth == self.max_depth;
            if nee_env {
                let wi = uniform_sphere(rng.f32(), rng.f32());
                let fp = m.phase.eval(d.dot(wi));
                let tr = m.transmittance(x, wi, 0.0, m.exit(x, wi), rng, &mut c.track);
                if tr > 0.0 {
                    let w = if last { 1.0 } else { power(INV_4PI, fp) };
                    l += beta * self.environment.radiance(wi) * (fp * tr * w / INV_4PI);
                }
            }
            if let Some(sun) = &self.sun {
                let fp = m.phase.eval(d.dot(sun.towards));
                let tr = m.transmittance(
                    x,
                    sun.towards,
                    0.0,
                    m.exit(x, sun.towards),
                    rng,
                    &mut c.track,
                );
                l += beta * sun.radiance * (fp * tr);
            }
            if last {
                break;
            }
            // The phase function is sampled exactly: its weight f / pdf is 1.
            let (wi, pdf) = m.phase.sample(d, rng.f32(), rng.f32());
            if depth >= self.rr_depth {
                let q = beta.max_element().min(0.95);
                if rng.f32() >= q {
                    break;
                }
                beta /= q;
            }
            o = x;
            d = wi;
            phase_pdf = Some(pdf);
        }
        l
    }
}
