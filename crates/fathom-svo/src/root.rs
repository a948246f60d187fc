//! The root cube: fitted to the scene's bounds, or given explicitly.
//!
//! A loose root wastes levels: with the Menger sponge ([-1, 1]^3) in a [-2, 2]^3 root every
//! voxel is one level deeper than it needs to be, the eye of a corner zoom sits inside the
//! root (so rays can never enter the sponge through a root face), and the voxel grid does not
//! line up with the sponge's own faces. [`RootSpec::Fit`] shrinks a search cube to the scene:
//! it subdivides the cube [`FIT_LEVELS`] levels with the same conservative full test the octree
//! uses (no false negatives; for estimate scenes, the corner test too), keeping only full cells, and takes the bounding cube of the full
//! cells. Since every voxel the surface crosses tests full, the fitted root contains the whole
//! surface (and the solid), padded by up to one cell of the search grid. When an exact
//! bounding cube is known (the Menger sponge), [`RootSpec::Cube`] gives it.

use crate::shader::{Probe, Shader};
use glam::DVec3;
use rayon::prelude::*;

/// Levels of the fitting search: cells of `2 * half / 2^FIT_LEVELS`.
pub const FIT_LEVELS: u32 = 7;

/// The Menger sponge's own cube, `[-1, 1]^3`, as the root of its zooms: exact, so the root's
/// faces are the sponge's faces and a zoom into the corner targets a corner of the root. A
/// fitted root only reaches about +-1.016 (one search cell of padding), which shifts every
/// voxel boundary off the sponge's faces and costs many more nodes per ray.
pub const MENGER_CUBE: RootSpec = RootSpec::Cube {
    centre: DVec3::ZERO,
    half: 1.0,
};

impl RootSpec {
    /// The exact cube when the scene has one (see [`MENGER_CUBE`] for why it matters), else
    /// the fitted default.
    pub fn from_cube(cube: Option<fathom_core::camera_path::ExactCube>) -> RootSpec {
        match cube {
            Some(c) => RootSpec::Cube {
                centre: c.centre,
                half: c.half,
            },
            None => RootSpec::default(),
        }
    }
}

/// How the root cube is chosen.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum RootSpec {
    /// Fit the root to the scene's full voxels inside the search cube `[-half, half]^3`.
    Fit {
        /// Half side of the search cube (the scene must lie inside it).
        half: f64,
    },
    /// An explicit cube `centre + [-half, half]^3`.
    Cube {
        /// Centre of the cube.
        centre: DVec3,
        /// Half side.
        half: f64,
    },
}

impl Default for RootSpec {
    fn default() -> Self {
        RootSpec::Fit { half: 4.0 }
    }
}

impl RootSpec {
    /// An explicit cube `[-half, half]^3`.
    pub fn centred(half: f64) -> RootSpec {
        RootSpec::Cube {
            centre: DVec3::ZERO,
            half,
        }
    }

    /// Checks that the spec is a finite cube with a positive side.
    pub fn validate(&self) -> Result<(), crate::error::OctreeError> {
        let (c, h) = match *self {
            RootSpec::Fit { half } => (DVec3::ZERO, half),
            RootSpec::Cube { centre, half } => (centre, half),
        };
        if !(h.is_finite() && h > 0.0 && c.is_finite()) {
            return Err(crate::error::OctreeError::Root);
        }
        Ok(())
    }

    /// The root cube as (minimum corner, side), fitting it to `sh`'s scene if asked.
    pub fn resolve(&self, sh: &Shader) -> (DVec3, f64) {
        match *self {
            RootSpec::Cube { centre, half } => (centre - DVec3::splat(half), 2.0 * half),
            RootSpec::Fit { half } => {
                let (lo, hi) = fit_bounds(sh, half, FIT_LEVELS)
                    .unwrap_or((DVec3::splat(-half), DVec3::splat(half)));
                let centre = (lo + hi) * 0.5;
                let h = ((hi - lo) * 0.5).max_element();
                (centre - DVec3::splat(h), 2.0 * h)
            }
        }
    }
}

/// The bounding box of the cells that test full when `[-half, half]^3` is subdivided `levels`
/// levels (only full cells are refined), or `None` when nothing is full. World coordinates:
/// runs before the octree view moves the shader's origin off zero.
pub fn fit_bounds(sh: &Shader, half: f64, levels: u32) -> Option<(DVec3, DVec3)> {
    // Cells as (integer corner, level); side = 2 half / 2^level.
    let full = |ev: &mut Probe, c: [u32; 3], level: u32| {
        let s = 2.0 * half / (1u64 << level) as f64;
        let centre =
            DVec3::new(c[0] as f64, c[1] as f64, c[2] as f64) * s + DVec3::splat(-half + 0.5 * s);
        // The same test as generation, corner test of estimate scenes included, so the fit
        // cannot cut off a surface the octree would have kept.
        sh.full(ev, centre, 0.5 * s * 3f64.sqrt()).is_some()
            || sh.corner_inside(ev, centre, 0.5 * s)
    };
    let mut ev = Probe::new();
    if !full(&mut ev, [0; 3], 0) {
        return None;
    }
    let mut cells = vec![[0u32; 3]];
    for level in 1..=levels {
        cells = cells
            .par_iter()
            .map_init(Probe::new, |ev, c| {
                let mut out = Vec::new();
                for o in 0..8u32 {
                    let k = [
                        2 * c[0] + (o & 1),
                        2 * c[1] + (o >> 1 & 1),
                        2 * c[2] + (o >> 2 & 1),
                    ];
                    if full(ev, k, level) {
                        out.push(k);
                    }
                }
                out
            })
            .flatten()
            .collect();
        if cells.is_empty() {
            return None;
        }
    }
    let s = 2.0 * half / (1u64 << levels) as f64;
    let mut lo = [u32::MAX; 3];
    let mut hi = [0u32; 3];
    for c in &cells {
        for a in 0..3 {
            lo[a] = lo[a].min(c[a]);
            hi[a] = hi[a].max(c[a] + 1);
        }
    }
    let w =
        |k: [u32; 3]| DVec3::new(k[0] as f64, k[1] as f64, k[2] as f64) * s - DVec3::splat(half);
    Some((w(lo), w(hi)))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fitted_roots_contain_the_scene_and_are_tight() {
        // Sphere of radius 1: the fitted cube contains [-1, 1]^3 and is at most a few search
        // cells larger.
        let sh = Shader::new(&fathom_core::scenes::sphere(1.0), 0.01).unwrap();
        let (min, size) = RootSpec::Fit { half: 4.0 }.resolve(&sh);
        assert!(min.max_element() <= -1.0 && (min + DVec3::splat(size)).min_element() >= 1.0);
        let cell = 8.0 / 128.0;
        assert!(size <= 2.0 + 4.0 * cell, "root side {size}");
        // The Menger sponge: contains [-1, 1]^3, not exactly (the grid pads by a cell).
        let sh = Shader::new(&fathom_core::scenes::menger(6), 0.01).unwrap();
        let (min, size) = RootSpec::Fit { half: 2.0 }.resolve(&sh);
        assert!(min.max_element() <= -1.0 && (min + DVec3::splat(size)).min_element() >= 1.0);
        assert!(size < 2.2, "root side {size}");
        // The Mandelbulb's surface points lie inside its fitted root.
        let mb = fathom_core::presets::load("mandelbulb").unwrap();
        let sh = Shader::new(&mb, 0.01).unwrap();
        let (min, size) = RootSpec::default().resolve(&sh);
        assert!(size < 3.0, "mandelbulb root side {size}");
        let mut ev = Probe::new();
        // Rays from far away towards the centre: where each first reaches the surface is
        // inside the root. Every ray aims at the bulb's centre, so every ray must get there.
        let mut reached = 0;
        for i in 0..200 {
            let th = i as f64 * 2.399_963;
            let z = 1.0 - 2.0 * (i as f64 + 0.5) / 200.0;
            let r = (1.0 - z * z).sqrt();
            let dir = DVec3::new(r * th.cos(), z, r * th.sin());
            let mut t = 0.0;
            let o = dir * 4.0;
            for _ in 0..2000 {
                let p = o - dir * t;
                let d = sh.distance(&mut ev, p);
                if d < 1e-9 {
                    let u = (p - min) / size;
                    assert!(
                        u.min_element() > 0.0 && u.max_element() < 1.0,
                        "{p} outside"
                    );
                    reached += 1;
                    break;
                }
                t += d;
            }
        }
        assert_eq!(reached, 200, "rays that never reached the surface");
        assert_eq!(
            RootSpec::centred(1.0).resolve(&sh),
            (DVec3::splat(-1.0), 2.0)
        );
        assert!(RootSpec::Fit { half: -1.0 }.validate().is_err());
    }
}
