//! The participating medium: a density grid scaled to an extinction, a single-scattering
//! albedo, a phase function and optional emission; with the two estimators a volume path
//! tracer needs, both stepping through the majorant grid's cells with each cell's majorant:
//!
//! - **delta tracking** (Woodcock) samples the distance to the next real collision: tentative
//!   collisions at rate `majorant`, each accepted with probability `sigma_t / majorant`;
//! - **ratio tracking** (Cramer; Novak et al. 2014) estimates transmittance: the product of
//!   `1 - sigma_t / majorant` over the tentative collisions, with pbrt-v4's Russian roulette
//!   once the estimate falls below 0.05.
//!
//! With `homogeneous_cells` on, cells whose minimum equals their maximum need no lookups
//! (every tentative collision there is real), and ratio tracking uses each cell's minimum as a
//! control extinction (residual ratio tracking): `exp(-min * length)` analytically, and
//! tentative collisions only at rate `max - min`. Both are unbiased; they only move work.

use crate::error::{VolumeError, check_range};
use crate::grid::{DensityGrid, WorldBox};
use crate::light::Emission;
use crate::majorant::MajorantGrid;
use crate::phase::HenyeyGreenstein;
use crate::sampling::Stream;
use glam::Vec3;
use serde::Serialize;

/// Which majorants the trackers step with.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
pub enum Majorant {
    /// One majorant for the whole grid (what Mitsuba 3's volpath does).
    Global,
    /// A coarse grid of per-block maxima, each cell covering `block`^3 voxels.
    Grid { block: u32 },
}

/// How the medium is made from a density grid.
#[derive(Clone, Debug, PartialEq)]
pub struct MediumParams {
    /// Extinction per unit density and unit length.
    pub density_scale: f32,
    /// Single-scattering albedo per channel, [0, 1].
    pub albedo: Vec3,
    /// Henyey-Greenstein asymmetry, (-1, 1).
    pub g: f32,
    /// Emission strength (0: none); the colour map spans 0 to the grid's largest density.
    pub emission: f32,
    pub majorant: Majorant,
    /// Skip lookups in homogeneous cells and use residual ratio tracking.
    pub homogeneous_cells: bool,
}

impl Default for MediumParams {
    fn default() -> Self {
        MediumParams {
            density_scale: 20.0,
            albedo: Vec3::splat(0.8),
            g: 0.0,
            emission: 0.0,
            majorant: Majorant::Grid { block: 8 },
            homogeneous_cells: true,
        }
    }
}

/// Largest density scale accepted.
pub const MAX_DENSITY_SCALE: f64 = 1e6;
/// Largest extinction (density times density scale, per unit length) a medium may reach:
/// beyond it f32 overflows to infinity (1e38 x 20) or delta tracking takes more null
/// collisions than a render can finish, so such a medium is refused with this limit.
pub const MAX_EXTINCTION: f64 = 1e12;
/// Largest emission strength accepted.
pub const MAX_EMISSION: f64 = 1e6;
/// Largest majorant block, in voxels.
pub const MAX_BLOCK: u32 = 1024;

impl MediumParams {
    /// Checks every parameter's range.
    pub fn validate(&self) -> Result<(), VolumeError> {
        check_range(
            "density scale",
            self.density_scale as f64,
            0.0,
            MAX_DENSITY_SCALE,
        )?;
        for a in self.albedo.to_array() {
            check_range("albedo", a as f64, 0.0, 1.0)?;
        }
        HenyeyGreenstein::new(self.g)?;
        check_range("emission", self.emission as f64, 0.0, MAX_EMISSION)?;
        if let Majorant::Grid { block } = self.majorant
            && !(1..=MAX_BLOCK).contains(&block)
        {
            return Err(VolumeError::param(
                "majorant block",
                block,
                format!("1..={MAX_BLOCK} voxels"),
            ));
        }
        Ok(())
    }
}

/// What the trackers did, for statistics.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct TrackCounters {
    /// Majorant-grid cells entered (DDA steps), free flights and shadow rays together.
    pub dda_steps: u64,
    /// Density lookups (trilinear).
    pub lookups: u64,
    /// Tentative collisions that were not real (free flights only).
    pub null_collisions: u64,
    /// Transmittance estimates (shadow rays).
    pub shadow_rays: u64,
}

impl TrackCounters {
    pub fn add(&mut self, o: &TrackCounters) {
        self.dda_steps += o.dda_steps;
        self.lookups += o.lookups;
        self.null_collisions += o.null_collisions;
        self.shadow_rays += o.shadow_rays;
    }
}

/// A real collision: where, and the (unscaled) density there.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Collision {
    pub t: f32,
    pub density: f32,
}

/// A density grid turned into a medium, with its majorant grid.
#[derive(Clone, Debug)]
pub struct Medium {
    pub density: DensityGrid,
    pub majorant: MajorantGrid,
    pub albedo: Vec3,
    pub phase: HenyeyGreenstein,
    pub emission: Option<Emission>,
    scale: f32,
    homogeneous: bool,
    /// World to voxel-centre coordinates: `p * q_scale + q_offset`.
    q_scale: Vec3,
    q_offset: Vec3,
}

/// Below this transmittance estimate, Russian roulette ends 3 in 4 estimates (pbrt-v4).
const SHADOW_RR_BELOW: f32 = 0.05;

impl Medium {
    /// Builds the medium and its majorant grid; the density grid must be valid (finite, >= 0).
    pub fn new(density: DensityGrid, p: &MediumParams) -> Result<Self, VolumeError> {
        p.validate()?;
        let peak = density.max_value() as f64 * p.density_scale as f64;
        if peak.is_nan() || peak > MAX_EXTINCTION {
            return Err(VolumeError::Invalid(format!(
                "the densest voxel ({}) times the density scale ({}) is an extinction of {peak:e} \
                 per unit length, more than the {MAX_EXTINCTION:e} a render can finish; lower \
                 --density-scale to at most {:e} or rescale the grid",
                density.max_value(),
                p.density_scale,
                MAX_EXTINCTION / density.max_value() as f64
            )));
        }
        let res = density.res();
        let majorant = match p.majorant {
            Majorant::Global => MajorantGrid::global(&density, p.density_scale),
            Majorant::Grid { block } => {
                MajorantGrid::build(&density, res.map(|r| r.div_ceil(block)), p.density_scale)
            }
        };
        let q_scale =
            Vec3::new(res[0] as f32, res[1] as f32, res[2] as f32) / density.bbox.extent();
        let q_offset = -density.bbox.min * q_scale - Vec3::splat(0.5);
        let max = density.max_value();
        Ok(Medium {
            majorant,
            albedo: p.albedo,
            phase: HenyeyGreenstein::new(p.g)?,
            emission: (p.emission > 0.0 && max > 0.0).then_some(Emission {
                strength: p.emission,
                reference: max,
            }),
            scale: p.density_scale,
            homogeneous: p.homogeneous_cells,
            q_scale,
            q_offset,
            density,
        })
    }

    /// The box the medium fills.
    pub fn bbox(&self) -> WorldBox {
        self.density.bbox
    }

    /// Extinction at world point `p`.
    #[inline(always)]
    pub fn sigma_t(&self, p: Vec3) -> f32 {
        self.density
            .trilinear_voxel(p * self.q_scale + self.q_offset)
            * self.scale
    }

    /// Delta tracking along `o + t d` for t in `[t0, t1]` (inside the box): the first real
    /// collision, or `None` if the ray leaves the interval.
    #[inline]
    pub fn sample_flight(
        &self,
        o: Vec3,
        d: Vec3,
        t0: f32,
        t1: f32,
        rng: &mut Stream,
        c: &mut TrackCounters,
    ) -> Option<Collision> {
        let mut tau = rng.exp1();
        for seg in self.majorant.dda(o, d, t0, t1) {
            c.dda_steps += 1;
            let maj = seg.bounds.max;
            if maj <= 0.0 {
                continue;
            }
            let mut t = seg.t0;
            loop {
                let room = (seg.t1 - t) * maj;
                if tau >= room {
                    tau -= room;
                    break;
                }
                t += tau / maj;
                if self.homogeneous && seg.bounds.min == maj {
                    return Some(Collision {
                        t,
                        density: maj / self.scale,
                    });
                }
                c.lookups += 1;
                let sigma = self.sigma_t(o + d * t);
                if rng.f32() * maj < sigma {
                    return Some(Collision {
                        t,
                        density: sigma / self.scale,
                    });
                }
                c.null_collisions += 1;
                tau = rng.exp1();
            }
        }
        None
    }

    /// Ratio tracking along `o + t d` for t in `[t0, t1]`: an unbiased estimate of the
    /// transmittance.
    #[inline]
    pub fn transmittance(
        &self,
        o: Vec3,
        d: Vec3,
        t0: f32,
        t1: f32,
        rng: &mut Stream,
        c: &mut TrackCounters,
    ) -> f32 {
        c.shadow_rays += 1;
        let mut tr = 1.0f32;
        // Russian roulette on a small estimate: unbiased (survivors count four times).
        let roulette = |tr: &mut f32, rng: &mut Stream| -> bool {
            if *tr < SHADOW_RR_BELOW {
                if rng.f32() < 0.75 {
                    return false;
                }
                *tr *= 4.0;
            }
            true
        };
        for seg in self.majorant.dda(o, d, t0, t1) {
            c.dda_steps += 1;
            let maj = seg.bounds.max;
            if maj <= 0.0 {
                continue;
            }
            let control = if self.homogeneous {
                seg.bounds.min
            } else {
                0.0
            };
            let resid = maj - control;
            if control > 0.0 {
                tr *= (-control * (seg.t1 - seg.t0)).exp();
                if !roulette(&mut tr, rng) {
                    return 0.0;
                }
            }
            if resid <= 0.0 {
                continue;
            }
            let mut t = seg.t0;
            loop {
                t += rng.exp1() / resid;
                if t >= seg.t1 {
                    break;
                }
                c.lookups += 1;
                tr *= 1.0 - (self.sigma_t(o + d * t) - control) / resid;
                if tr <= 0.0 || !roulette(&mut tr, rng) {
                    return 0.0;
                }
            }
        }
        tr
    }

    /// Where a ray from `p` (inside the box) leaves it.
    #[inline]
    pub fn exit(&self, p: Vec3, d: Vec3) -> f32 {
        self.bbox().intersect(p, d).map_or(0.0, |(_, t1)| t1)
    }
}

#[cfg(test)]
mod tests;
