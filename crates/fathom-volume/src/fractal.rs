//! The fractal density mode: any scene's tape sampled into a density grid, so every scene
//! renders as a cloud. Density is 1 where the distance is negative and 0 elsewhere, or with
//! smoothing a linear ramp `clamp(0.5 - d / (w h), 0, 1)` over `w` voxels of size `h` across
//! the surface. Sampled at voxel centres on the core's 8-lane f32 evaluator.

use crate::error::{VolumeError, check_range};
use crate::grid::{DensityGrid, Grid, WorldBox};
use fathom_core::eval::Evaluator;
use fathom_core::real::{F32x8, Real};
use fathom_core::tape::Tape;
use fathom_core::vec3::V3;
use glam::Vec3;
use rayon::prelude::*;

/// Half the side of the cube searched by [`fit_box`].
pub const FIT_HALF: f32 = 4.0;
/// Widest smoothing ramp, in voxels.
pub const MAX_SMOOTH: f64 = 64.0;

/// Distances at the centres of a row of `n` voxels starting at `p0`, `dx` apart along x.
fn row_distances(
    ev: &mut Evaluator<F32x8>,
    tape: &Tape,
    p0: Vec3,
    dx: f32,
    n: usize,
    out: &mut [f32],
) {
    for (k, chunk) in out[..n].chunks_mut(8).enumerate() {
        let xs: [f64; 8] = std::array::from_fn(|l| (p0.x + dx * (k * 8 + l) as f32) as f64);
        let p = V3::new(
            F32x8::from_lanes(&xs),
            <F32x8 as Real>::splat(p0.y as f64),
            <F32x8 as Real>::splat(p0.z as f64),
        );
        let d = ev.distance(tape, p);
        for (l, v) in chunk.iter_mut().enumerate() {
            *v = d.lane(l) as f32;
        }
    }
}

/// The smallest cube (inside `[-FIT_HALF, FIT_HALF]^3`) holding every 64^3-lattice cell the
/// surface or interior may reach: cells whose centre is closer than half a cell diagonal to
/// the surface or inside. Errors if the scene has nothing there.
pub fn fit_box(tape: &Tape) -> Result<WorldBox, VolumeError> {
    let n = 64usize;
    let h = 2.0 * FIT_HALF / n as f32;
    let reach = 0.5 * h * 3f32.sqrt();
    let (lo, hi) = (0..n * n)
        .into_par_iter()
        .map_init(
            || (Evaluator::<F32x8>::new(), vec![0.0f32; n]),
            |(ev, row), i| {
                let (y, z) = (i % n, i / n);
                let c = |j: usize| -FIT_HALF + (j as f32 + 0.5) * h;
                row_distances(ev, tape, Vec3::new(c(0), c(y), c(z)), h, n, row);
                let mut lo = Vec3::splat(f32::INFINITY);
                let mut hi = Vec3::splat(f32::NEG_INFINITY);
                for (x, d) in row.iter().enumerate() {
                    if *d < reach {
                        let p = Vec3::new(c(x), c(y), c(z));
                        lo = lo.min(p - 0.5 * h);
                        hi = hi.max(p + 0.5 * h);
                    }
                }
                (lo, hi)
            },
        )
        .reduce(
            || (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY)),
            |a, b| (a.0.min(b.0), a.1.max(b.1)),
        );
    if !lo.is_finite() {
        return Err(VolumeError::Invalid(format!(
            "the scene has no surface inside [-{FIT_HALF}, {FIT_HALF}]^3 to sample; give the box explicitly"
        )));
    }
    let half = 0.5 * (hi - lo).max_element();
    let c = 0.5 * (lo + hi);
    WorldBox::new(c - half, c + half)
}

/// Samples `tape` into a `res` grid over `bbox`: 1 inside, 0 outside, or a ramp `smooth`
/// voxels wide (0: none, up to [`MAX_SMOOTH`]). `slice_done` is called after each z slice.
pub fn sample(
    tape: &Tape,
    res: [u32; 3],
    bbox: WorldBox,
    smooth: f32,
    limit: u64,
    slice_done: &(dyn Fn() + Sync),
) -> Result<DensityGrid, VolumeError> {
    check_range("smooth", smooth as f64, 0.0, MAX_SMOOTH)?;
    let size = bbox.extent() / Vec3::new(res[0] as f32, res[1] as f32, res[2] as f32);
    let ramp = smooth * size.min_element();
    sample_field(tape, res, bbox, limit, slice_done, &|d| {
        if ramp > 0.0 {
            (0.5 - d / ramp).clamp(0.0, 1.0)
        } else if d < 0.0 {
            1.0
        } else {
            0.0
        }
    })
}

/// Samples `tape`'s signed distance (world units, negative inside) at the voxel centres of a
/// `res` grid over `bbox`, for export as a distance volume rather than a density. Escape-time
/// estimators do not measure depth inside (the Mandelbulb's is held at -1e-6 there, the
/// Mandelbox's stays a small positive `r / dr`), so their interiors read about 0.
pub fn sample_distance(
    tape: &Tape,
    res: [u32; 3],
    bbox: WorldBox,
    limit: u64,
    slice_done: &(dyn Fn() + Sync),
) -> Result<Grid<f32>, VolumeError> {
    sample_field(tape, res, bbox, limit, slice_done, &|d| d)
}

/// `value(distance)` at the voxel centres of a `res` grid over `bbox`, z slices in parallel
/// on the 8-lane evaluator; `slice_done` is called after each slice.
fn sample_field(
    tape: &Tape,
    res: [u32; 3],
    bbox: WorldBox,
    limit: u64,
    slice_done: &(dyn Fn() + Sync),
    value: &(dyn Fn(f32) -> f32 + Sync),
) -> Result<Grid<f32>, VolumeError> {
    let mut g = Grid::<f32>::new(res, bbox, limit)?;
    let [rx, ry, _] = res.map(|r| r as usize);
    let size = bbox.extent() / Vec3::new(res[0] as f32, res[1] as f32, res[2] as f32);
    g.data_mut()
        .par_chunks_mut(rx * ry)
        .enumerate()
        .for_each_init(
            || (Evaluator::<F32x8>::new(), vec![0.0f32; rx]),
            |(ev, row), (z, slice)| {
                for y in 0..ry {
                    let p0 = bbox.min + (Vec3::new(0.0, y as f32, z as f32) + 0.5) * size;
                    row_distances(ev, tape, p0, size.x, rx, row);
                    for (v, d) in slice[y * rx..(y + 1) * rx].iter_mut().zip(row.iter()) {
                        *v = value(*d);
                    }
                }
                slice_done();
            },
        );
    Ok(g)
}

#[cfg(test)]
mod tests {
    use super::*;
    use fathom_core::primitives::Primitive;
    use fathom_core::{Node, Scene};

    fn sphere() -> Tape {
        Tape::compile(&Scene::new(Node::new(Primitive::Sphere))).unwrap()
    }

    #[test]
    fn a_sphere_fills_its_share_of_the_grid() {
        let bbox = WorldBox::new(Vec3::splat(-1.5), Vec3::splat(1.5)).unwrap();
        let want = 4.0 / 3.0 * std::f64::consts::PI / 27.0;
        for smooth in [0.0, 2.0] {
            let g = sample(&sphere(), [40, 40, 40], bbox, smooth, 1 << 30, &|| {}).unwrap();
            let mean = g.data().iter().map(|&v| v as f64).sum::<f64>() / g.data().len() as f64;
            assert!(
                (mean - want).abs() < 0.01 * want + 2e-3,
                "smooth {smooth}: filled {mean}, want {want}"
            );
            assert_eq!(g.nearest(Vec3::ZERO), 1.0);
            assert_eq!(g.nearest(Vec3::splat(1.4)), 0.0);
            let partial = g.data().iter().filter(|v| **v > 0.0 && **v < 1.0).count();
            assert_eq!(
                partial > 0,
                smooth > 0.0,
                "smoothing makes a ramp, binary does not"
            );
        }
    }

    #[test]
    fn distance_grids_hold_the_signed_distance_at_voxel_centres() {
        let bbox = WorldBox::new(Vec3::splat(-1.5), Vec3::splat(1.5)).unwrap();
        let g = sample_distance(&sphere(), [12, 10, 8], bbox, 1 << 30, &|| {}).unwrap();
        let size = bbox.extent() / Vec3::new(12.0, 10.0, 8.0);
        let mut inside = 0;
        for z in 0..8 {
            for y in 0..10 {
                for x in 0..12 {
                    let p = bbox.min + (Vec3::new(x as f32, y as f32, z as f32) + 0.5) * size;
                    let got = g.data()[x + 12 * (y + 10 * z)];
                    assert!((got - (p.length() - 1.0)).abs() < 1e-5, "{p}: {got}");
                    inside += (got < 0.0) as usize;
                }
            }
        }
        assert!(inside > 0, "some centres are inside the sphere");
        // Refused before allocating when over the limit.
        assert!(sample_distance(&sphere(), [1024; 3], bbox, 1 << 20, &|| {}).is_err());
    }

    #[test]
    fn fit_box_encloses_the_object_tightly() {
        let b = fit_box(&sphere()).unwrap();
        assert!(
            b.min.max_element() < -1.0 && b.min.min_element() > -1.4,
            "{b:?}"
        );
        assert!(
            b.max.min_element() > 1.0 && b.max.max_element() < 1.4,
            "{b:?}"
        );
        let far = fathom_core::scene_file::parse(
            "Scene(version: 1, root: Node(shape: Sphere(radius: 0.5), ops: [Translate(offset: (40.0, 0.0, 0.0))]))",
            "far",
        )
        .unwrap();
        let e = fit_box(&Tape::compile(&far).unwrap())
            .unwrap_err()
            .to_string();
        assert!(e.contains("no surface inside"), "{e}");
        let e = sample(&sphere(), [4, 4, 4], b, -1.0, 1 << 20, &|| {})
            .unwrap_err()
            .to_string();
        assert!(e.contains("smooth = -1"), "{e}");
    }
}
