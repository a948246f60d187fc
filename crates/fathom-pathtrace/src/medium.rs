//! Participating media outside the surfaces: homogeneous fog and exponential height fog, with
//! single scattering by the Henyey-Greenstein phase function.
//!
//! Both densities have closed-form optical depth along a ray, so transmittance is exact and a
//! scattering distance is drawn by inverting it (no tracking needed): for height fog
//! sigma(y) = sigma_0 exp(-(y - y_0) / H), the depth along o + t d is
//! sigma(o.y) H / d.y (1 - exp(-d.y t / H)). "Single scattering": a path scatters in the
//! medium at most once; afterwards the medium only attenuates it (the integrator enforces
//! that). Fog therefore brightens towards the light and veils distance as in the Blinn-Phong
//! fog, at the cost of the darkening that multiple scattering would add.
//!
//! Henyey-Greenstein sampling inverts its CDF in cos(theta) (Henyey and Greenstein 1941; the
//! form used by pbrt-v4). Here `g > 0` scatters forward along the propagation direction.

use crate::sampling::Frame;
use glam::DVec3;
use std::f64::consts::PI;

/// How the fog's density varies.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Density {
    /// The same everywhere.
    Homogeneous,
    /// `exp(-(y - base) / falloff)` times the density (denser below `base`).
    Height {
        /// Height where the density is the nominal one.
        base: f64,
        /// Height over which it falls by e, > 0.
        falloff: f64,
    },
}

/// A fog.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Medium {
    /// Extinction coefficient per world unit (at `base` for height fog), [0, 1e6].
    pub density: f64,
    /// How the density varies.
    pub kind: Density,
    /// Scattering albedo sigma_s / sigma_t per channel, [0, 1].
    pub albedo: [f64; 3],
    /// Henyey-Greenstein asymmetry, (-1, 1).
    pub g: f64,
}

/// Why a medium was refused.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum MediumError {
    /// A field out of range.
    #[error("fog: {field} = {value} is out of range {range}")]
    OutOfRange {
        /// The field.
        field: &'static str,
        /// The value given.
        value: f64,
        /// The accepted range.
        range: &'static str,
    },
}

/// Largest exponent the height fog evaluates (keeps exp finite far below the base).
const MAX_EXP: f64 = 60.0;

impl Medium {
    /// Checks the fields.
    pub fn validate(&self) -> Result<(), MediumError> {
        let bad = |field, value, range| {
            Err(MediumError::OutOfRange {
                field,
                value,
                range,
            })
        };
        if !(self.density.is_finite() && (0.0..=1e6).contains(&self.density)) {
            return bad("density", self.density, "[0, 1e6]");
        }
        if !(self.g.is_finite() && self.g.abs() < 1.0) {
            return bad("g", self.g, "(-1, 1)");
        }
        for &a in &self.albedo {
            if !(a.is_finite() && (0.0..=1.0).contains(&a)) {
                return bad("albedo", a, "[0, 1]");
            }
        }
        if let Density::Height { base, falloff } = self.kind {
            if !base.is_finite() {
                return bad("base", base, "finite");
            }
            if !(falloff.is_finite() && falloff > 0.0) {
                return bad("falloff", falloff, "(0, inf)");
            }
        }
        Ok(())
    }

    /// Extinction at height `y`.
    fn sigma_at(&self, y: f64) -> f64 {
        match self.kind {
            Density::Homogeneous => self.density,
            Density::Height { base, falloff } => {
                self.density * (-(y - base) / falloff).min(MAX_EXP).exp()
            }
        }
    }

    /// Optical depth from `o` along unit `d` over length `t` (may be infinite).
    pub fn optical_depth(&self, o: DVec3, d: DVec3, t: f64) -> f64 {
        if self.density <= 0.0 || t <= 0.0 {
            return 0.0;
        }
        match self.kind {
            Density::Homogeneous => self.density * t,
            Density::Height { falloff, .. } => {
                let s0 = self.sigma_at(o.y);
                let k = d.y / falloff;
                if k.abs() < 1e-9 {
                    return s0 * t;
                }
                // s0 / k (1 - exp(-k t)), with exp(-k t) bounded for rays going down.
                let e = (-k * t).min(MAX_EXP).exp();
                (s0 / k * (1.0 - e)).max(0.0)
            }
        }
    }

    /// Transmittance over a segment.
    pub fn transmittance(&self, o: DVec3, d: DVec3, t: f64) -> f64 {
        (-self.optical_depth(o, d, t)).exp()
    }

    /// A scattering distance along the ray for uniform `u`, if it falls before `t_max`.
    /// Its density is sigma_t(t) T(t); the probability of none is T(t_max).
    pub fn sample_distance(&self, o: DVec3, d: DVec3, t_max: f64, u: f64) -> Option<f64> {
        if self.density <= 0.0 {
            return None;
        }
        let tau = -(1.0 - u).ln();
        let t = match self.kind {
            Density::Homogeneous => tau / self.density,
            Density::Height { falloff, .. } => {
                let s0 = self.sigma_at(o.y);
                let k = d.y / falloff;
                if k.abs() < 1e-9 {
                    tau / s0
                } else {
                    // Solve s0 / k (1 - exp(-k t)) = tau.
                    let q = 1.0 - tau * k / s0;
                    if q <= 0.0 {
                        return None;
                    }
                    -q.ln() / k
                }
            }
        };
        (t.is_finite() && t < t_max && t >= 0.0).then_some(t)
    }

    /// The scattering albedo.
    pub fn albedo(&self) -> DVec3 {
        DVec3::from(self.albedo)
    }
}

/// The Henyey-Greenstein phase function for the cosine between the propagation directions
/// before and after scattering.
pub fn hg(cos: f64, g: f64) -> f64 {
    let den = 1.0 + g * g - 2.0 * g * cos;
    (1.0 - g * g) / (4.0 * PI * den * den.sqrt().max(1e-12))
}

/// A new propagation direction after scattering a ray travelling along `d`: (direction,
/// density = the phase function's value).
pub fn sample_hg(d: DVec3, g: f64, u: [f64; 2]) -> (DVec3, f64) {
    let cos = if g.abs() < 1e-3 {
        1.0 - 2.0 * u[0]
    } else {
        let s = (1.0 - g * g) / (1.0 - g + 2.0 * g * u[0]);
        ((1.0 + g * g - s * s) / (2.0 * g)).clamp(-1.0, 1.0)
    };
    let sin = (1.0 - cos * cos).max(0.0).sqrt();
    let phi = 2.0 * PI * u[1];
    let local = DVec3::new(sin * phi.cos(), sin * phi.sin(), cos);
    let wi = Frame::new(d).to_world(local);
    (wi, hg(cos, g))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hg_is_normalised_and_sampling_matches_it() {
        for g in [-0.6, 0.0, 0.3, 0.85] {
            let n = 200_000;
            let mut s = 0.0;
            for k in 0..n {
                let c = -1.0 + 2.0 * (k as f64 + 0.5) / n as f64;
                s += hg(c, g) * 2.0 * PI * 2.0 / n as f64;
            }
            assert!((s - 1.0).abs() < 1e-3, "g {g}: {s}");
            // Mean cosine of sampled directions is g.
            let m = 20_000;
            let mut mean = 0.0;
            for k in 0..m {
                let u = [(k as f64 + 0.5) / m as f64, 0.3];
                let (w, pdf) = sample_hg(DVec3::Z, g, u);
                assert!((pdf - hg(w.z, g)).abs() < 1e-9 * pdf.max(1.0));
                mean += w.z;
            }
            assert!(
                (mean / m as f64 - g).abs() < 2e-3,
                "g {g}: {}",
                mean / m as f64
            );
        }
    }

    #[test]
    fn height_fog_depth_matches_numeric_integration_and_inverts() {
        let m = Medium {
            density: 0.3,
            kind: Density::Height {
                base: 0.0,
                falloff: 0.7,
            },
            albedo: [0.9; 3],
            g: 0.2,
        };
        m.validate().unwrap();
        let o = DVec3::new(0.0, 0.5, 0.0);
        for d in [
            DVec3::new(1.0, 0.3, 0.0).normalize(),
            DVec3::new(1.0, -0.4, 0.2).normalize(),
            DVec3::X,
        ] {
            let t = 3.0;
            let n = 100_000;
            let mut num = 0.0;
            for k in 0..n {
                let s = (k as f64 + 0.5) / n as f64 * t;
                num += m.sigma_at(o.y + d.y * s) * t / n as f64;
            }
            let got = m.optical_depth(o, d, t);
            assert!((got - num).abs() < 1e-6 * num.max(1.0), "{got} vs {num}");
            // Inverting: the distance drawn for u has optical depth -ln(1 - u).
            let u = 0.4;
            if let Some(s) = m.sample_distance(o, d, 1e9, u) {
                assert!((m.optical_depth(o, d, s) + (1.0 - u).ln()).abs() < 1e-9);
            }
        }
        let bad = Medium { g: 1.0, ..m };
        assert_eq!(
            bad.validate().unwrap_err().to_string(),
            "fog: g = 1 is out of range (-1, 1)"
        );
    }
}
