//! Automatic exposure of a density grid: the extinction scale and the box to frame, from the
//! grid's own statistics, so a render with no tuning shows the structure instead of a white
//! haze (too thin) or a black blob (too thick).
//!
//! The voxels at least [`OCCUPIED`] of the reference density (the 99.9th percentile of the
//! non-zero voxels) are the structure. Its mean chord length follows Cauchy's formula for
//! random lines, 4 V / S (V the occupied volume, S the area of the faces between occupied and
//! empty voxels), so a thin tendril and a solid sponge each get the extinction that gives a
//! line crossing them [`TARGET_DEPTH`] optical depths on average:
//! `density_scale = TARGET_DEPTH / (mean occupied density * mean chord)`.

use crate::grid::{DensityGrid, WorldBox};
use rayon::prelude::*;

/// Fraction of the reference density above which a voxel counts as structure.
pub const OCCUPIED: f32 = 0.2;
/// Mean optical depth along a line crossing the structure that the automatic scale aims for:
/// enough that a tendril shades itself and casts shadows, not so much that it turns into a
/// silhouette.
pub const TARGET_DEPTH: f32 = 3.0;
/// Largest automatic extinction scale (the range `--density-scale` accepts is [0, 1e6]).
pub const MAX_SCALE: f32 = 1e5;

/// What the statistics say about a grid.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct Exposure {
    /// The extinction scale to render with.
    pub density_scale: f32,
    /// The box around the occupied voxels (the whole grid's box when none is occupied).
    #[serde(skip)]
    pub occupied_box: WorldBox,
    /// Fraction of voxels that count as structure.
    pub occupied_fraction: f64,
    /// Mean chord length of the structure, world units.
    pub mean_chord: f32,
    /// Mean density of the occupied voxels.
    pub mean_density: f32,
}

/// The automatic exposure of `grid` (an empty grid gets scale 1 and its own box).
pub fn auto(grid: &DensityGrid) -> Exposure {
    let res = grid.res();
    let data = grid.data();
    let mut nz: Vec<f32> = data.par_iter().copied().filter(|&v| v > 0.0).collect();
    let empty = Exposure {
        density_scale: 1.0,
        occupied_box: grid.bbox,
        occupied_fraction: 0.0,
        mean_chord: 0.0,
        mean_density: 0.0,
    };
    if nz.is_empty() {
        return empty;
    }
    let k = ((nz.len() - 1) as f64 * 0.999) as usize;
    let reference = *nz.select_nth_unstable_by(k, |a, b| a.total_cmp(b)).1;
    drop(nz);
    let threshold = OCCUPIED * reference;
    let occ = |x: u32, y: u32, z: u32| grid.get(x, y, z) >= threshold;
    // Per z-slice: occupied count, density sum, exposed faces, and the occupied index box.
    #[derive(Clone, Copy)]
    struct Acc {
        n: u64,
        sum: f64,
        faces: u64,
        lo: [u32; 3],
        hi: [u32; 3],
    }
    let zero = Acc {
        n: 0,
        sum: 0.0,
        faces: 0,
        lo: [u32::MAX; 3],
        hi: [0; 3],
    };
    let merge = |a: Acc, b: Acc| Acc {
        n: a.n + b.n,
        sum: a.sum + b.sum,
        faces: a.faces + b.faces,
        lo: std::array::from_fn(|i| a.lo[i].min(b.lo[i])),
        hi: std::array::from_fn(|i| a.hi[i].max(b.hi[i])),
    };
    let acc = (0..res[2])
        .into_par_iter()
        .map(|z| {
            let mut a = zero;
            for y in 0..res[1] {
                for x in 0..res[0] {
                    if !occ(x, y, z) {
                        continue;
                    }
                    a.n += 1;
                    a.sum += grid.get(x, y, z) as f64;
                    let p = [x, y, z];
                    a.lo = std::array::from_fn(|i| a.lo[i].min(p[i]));
                    a.hi = std::array::from_fn(|i| a.hi[i].max(p[i]));
                    // The six neighbours; the grid's faces count as empty.
                    let n = [
                        x > 0 && occ(x - 1, y, z),
                        x + 1 < res[0] && occ(x + 1, y, z),
                        y > 0 && occ(x, y - 1, z),
                        y + 1 < res[1] && occ(x, y + 1, z),
                        z > 0 && occ(x, y, z - 1),
                        z + 1 < res[2] && occ(x, y, z + 1),
                    ];
                    a.faces += n.iter().filter(|&&o| !o).count() as u64;
                }
            }
            a
        })
        .reduce(|| zero, merge);
    if acc.n == 0 {
        return empty;
    }
    let voxel = grid.bbox.extent() / glam::UVec3::from(res).as_vec3();
    // Faces are counted on the voxel lattice; with cubic voxels V / S is n h / faces.
    let h = (voxel.x * voxel.y * voxel.z).cbrt();
    let mean_chord = 4.0 * acc.n as f32 * h / acc.faces.max(1) as f32;
    let mean_density = (acc.sum / acc.n as f64) as f32;
    let density_scale = (TARGET_DEPTH / (mean_density * mean_chord)).clamp(1e-3, MAX_SCALE);
    let corner = |i: [u32; 3]| grid.bbox.min + glam::UVec3::from(i).as_vec3() * voxel;
    let occupied_box =
        WorldBox::new(corner(acc.lo), corner(acc.hi.map(|v| v + 1))).unwrap_or(grid.bbox);
    Exposure {
        density_scale,
        occupied_box,
        occupied_fraction: acc.n as f64 / data.len() as f64,
        mean_chord,
        mean_density,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::grid::Grid;
    use glam::Vec3;

    fn grid_of(res: u32, f: impl Fn(Vec3) -> f32) -> DensityGrid {
        let bbox = WorldBox::new(Vec3::splat(-1.0), Vec3::splat(1.0)).unwrap();
        let mut g = Grid::new([res; 3], bbox, 1 << 30).unwrap();
        let data: Vec<f32> = (0..g.data().len())
            .map(|i| {
                let [x, y, z] = g.coords(i);
                f(g.voxel_centre(x, y, z))
            })
            .collect();
        g.data_mut().copy_from_slice(&data);
        g
    }

    #[test]
    fn a_solid_ball_gets_its_mean_chord_and_box() {
        // A ball of radius 0.5: mean chord 4V/S = 4r/3 = 0.667 (the voxel staircase has more
        // area than the sphere, 1.5 times on average, so the estimate runs low).
        let g = grid_of(64, |p| if p.length() < 0.5 { 1.0 } else { 0.0 });
        let e = auto(&g);
        assert!(
            (0.35..0.75).contains(&e.mean_chord),
            "mean chord {}",
            e.mean_chord
        );
        assert!((e.mean_density - 1.0).abs() < 1e-6);
        assert!(
            (e.density_scale * e.mean_chord - TARGET_DEPTH).abs() < 1e-3,
            "{e:?}"
        );
        for a in 0..3 {
            assert!((e.occupied_box.min[a] + 0.5).abs() < 0.05, "{e:?}");
            assert!((e.occupied_box.max[a] - 0.5).abs() < 0.05, "{e:?}");
        }
    }

    #[test]
    fn thin_structures_get_a_higher_scale_than_thick_ones_and_faint_haze_is_ignored() {
        // A rod of radius 0.05 along x inside a faint haze: the haze (1% of the rod's density)
        // is not structure, and the rod needs more extinction per density than the ball.
        let rod = grid_of(64, |p| {
            if p.y * p.y + p.z * p.z < 0.05 * 0.05 * 4.0 {
                2.0
            } else {
                0.02
            }
        });
        let ball = grid_of(64, |p| if p.length() < 0.5 { 2.0 } else { 0.0 });
        let (r, b) = (auto(&rod), auto(&ball));
        assert!(r.occupied_fraction < 0.05, "{r:?}");
        // Mean chords 2r = 0.2 against 4R/3 = 0.67 (3.3 times); the voxel staircase narrows it.
        assert!(r.density_scale > 2.0 * b.density_scale, "{r:?} vs {b:?}");
        assert!(
            r.occupied_box.max.y < 0.2 && r.occupied_box.max.x > 0.9,
            "{r:?}"
        );
    }

    #[test]
    fn an_empty_grid_keeps_its_box() {
        let g = grid_of(8, |_| 0.0);
        let e = auto(&g);
        assert_eq!(e.occupied_box, g.bbox);
        assert_eq!(e.density_scale, 1.0);
    }
}
