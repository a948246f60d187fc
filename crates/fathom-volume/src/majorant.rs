//! The majorant grid: a coarse grid over the density grid's box whose cells hold the largest
//! (and smallest) extinction any trilinear lookup inside the cell can return, and the 3D DDA
//! (Amanatides and Woo) that walks a ray through its cells in order, as pbrt-v4's grid medium
//! does. Free-flight sampling and transmittance then step with each cell's own majorant, so
//! empty and thin regions are crossed in one step. One cell is the single global majorant.
//!
//! A cell's bounds cover every voxel a trilinear lookup inside it can touch (the voxels whose
//! centres lie within one voxel of the cell), so they hold for every point of the cell. When a
//! cell's minimum equals its maximum the medium is homogeneous there, which the tracker uses
//! to skip lookups.

use crate::grid::{DensityGrid, WorldBox};
use glam::Vec3;
use rayon::prelude::*;

/// Bounds of the extinction (density times scale) over one majorant cell.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Bounds {
    pub max: f32,
    pub min: f32,
}

/// Per-cell extinction bounds over a box.
#[derive(Clone, Debug)]
pub struct MajorantGrid {
    res: [u32; 3],
    cells: Vec<Bounds>,
    bbox: WorldBox,
    /// World to cell coordinates: `(p - bbox.min) * to_cell`.
    to_cell: Vec3,
}

/// One cell along a ray: its bounds and the ray's interval `[t0, t1]` inside it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Segment {
    pub cell: [u32; 3],
    pub bounds: Bounds,
    pub t0: f32,
    pub t1: f32,
}

/// The voxel range a trilinear lookup inside `[lo, hi]` of local coordinates may touch along
/// an axis of `res` voxels.
fn voxel_range(lo: f32, hi: f32, res: u32) -> (u32, u32) {
    let q = |l: f32| l * res as f32 - 0.5;
    let a = (q(lo).floor() as i64).clamp(0, res as i64 - 1);
    let b = (q(hi).floor() as i64 + 1).clamp(0, res as i64 - 1);
    (a as u32, b as u32)
}

impl MajorantGrid {
    /// Bounds of `density * scale` over `res` cells spanning the density grid's box.
    pub fn build(density: &DensityGrid, res: [u32; 3], scale: f32) -> Self {
        let res = res.map(|r| r.max(1));
        let dres = density.res();
        let ranges: [Vec<(u32, u32)>; 3] = std::array::from_fn(|a| {
            (0..res[a])
                .map(|c| {
                    voxel_range(
                        c as f32 / res[a] as f32,
                        (c + 1) as f32 / res[a] as f32,
                        dres[a],
                    )
                })
                .collect()
        });
        let n = (res[0] * res[1] * res[2]) as usize;
        let cells: Vec<Bounds> = (0..n)
            .into_par_iter()
            .map(|i| {
                let i = i as u32;
                let (cx, cy, cz) = (i % res[0], i / res[0] % res[1], i / (res[0] * res[1]));
                let (x0, x1) = ranges[0][cx as usize];
                let (y0, y1) = ranges[1][cy as usize];
                let (z0, z1) = ranges[2][cz as usize];
                let mut b = Bounds {
                    max: f32::NEG_INFINITY,
                    min: f32::INFINITY,
                };
                for z in z0..=z1 {
                    for y in y0..=y1 {
                        let row = density.index(x0, y, z);
                        for &v in &density.data()[row..=row + (x1 - x0) as usize] {
                            b.max = b.max.max(v);
                            b.min = b.min.min(v);
                        }
                    }
                }
                Bounds {
                    max: b.max * scale,
                    min: b.min * scale,
                }
            })
            .collect();
        MajorantGrid {
            res,
            cells,
            bbox: density.bbox,
            to_cell: Vec3::new(res[0] as f32, res[1] as f32, res[2] as f32) / density.bbox.extent(),
        }
    }

    /// One cell: the single global majorant (and minorant) of the whole grid.
    pub fn global(density: &DensityGrid, scale: f32) -> Self {
        Self::build(density, [1, 1, 1], scale)
    }

    /// Cells per axis.
    pub fn res(&self) -> [u32; 3] {
        self.res
    }

    /// The bounds of cell (x, y, z).
    pub fn bounds(&self, c: [u32; 3]) -> Bounds {
        self.cells[(c[0] + self.res[0] * (c[1] + self.res[1] * c[2])) as usize]
    }

    /// The world box of cell `c`.
    pub fn cell_box(&self, c: [u32; 3]) -> WorldBox {
        let size = self.bbox.extent()
            / Vec3::new(self.res[0] as f32, self.res[1] as f32, self.res[2] as f32);
        let lo = self.bbox.min + Vec3::new(c[0] as f32, c[1] as f32, c[2] as f32) * size;
        WorldBox {
            min: lo,
            max: lo + size,
        }
    }

    /// The cells the ray `o + t d` crosses for t in `[t0, t1]` (an interval inside the box),
    /// in order.
    #[inline]
    pub fn dda(&self, o: Vec3, d: Vec3, t0: f32, t1: f32) -> Dda<'_> {
        let og = (o - self.bbox.min) * self.to_cell;
        let dg = d * self.to_cell;
        let p = og + dg * t0;
        let mut cell = [0i32; 3];
        let mut step = [0i32; 3];
        let mut next = [f32::INFINITY; 3];
        let mut delta = [f32::INFINITY; 3];
        for a in 0..3 {
            let r = self.res[a] as i32;
            cell[a] = (p[a].floor() as i32).clamp(0, r - 1);
            if dg[a] > 0.0 {
                step[a] = 1;
                next[a] = t0 + (cell[a] as f32 + 1.0 - p[a]) / dg[a];
                delta[a] = 1.0 / dg[a];
            } else if dg[a] < 0.0 {
                step[a] = -1;
                next[a] = t0 + (cell[a] as f32 - p[a]) / dg[a];
                delta[a] = -1.0 / dg[a];
            }
        }
        Dda {
            grid: self,
            cell,
            step,
            next,
            delta,
            t: t0,
            t_end: t1,
        }
    }
}

/// The walk of one ray through the majorant grid.
pub struct Dda<'a> {
    grid: &'a MajorantGrid,
    cell: [i32; 3],
    step: [i32; 3],
    next: [f32; 3],
    delta: [f32; 3],
    t: f32,
    t_end: f32,
}

impl Iterator for Dda<'_> {
    type Item = Segment;

    #[inline]
    fn next(&mut self) -> Option<Segment> {
        if self.t >= self.t_end {
            return None;
        }
        let a = if self.next[0] < self.next[1] {
            if self.next[0] < self.next[2] { 0 } else { 2 }
        } else if self.next[1] < self.next[2] {
            1
        } else {
            2
        };
        let t1 = self.next[a].min(self.t_end);
        let c = self.cell.map(|v| v as u32);
        let r = self.grid.res;
        let seg = Segment {
            cell: c,
            bounds: self.grid.cells[(c[0] + r[0] * (c[1] + r[1] * c[2])) as usize],
            t0: self.t,
            t1,
        };
        self.t = t1;
        self.cell[a] += self.step[a];
        self.next[a] += self.delta[a];
        if self.cell[a] < 0 || self.cell[a] >= r[a] as i32 {
            self.t = self.t_end;
        }
        Some(seg)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::grid::Grid;
    use crate::sampling::{Stream, uniform_sphere};

    fn noise_grid(res: [u32; 3], bbox: WorldBox) -> DensityGrid {
        let mut r = Stream::new(5, 0, 0);
        let n = (res[0] * res[1] * res[2]) as usize;
        let data = (0..n)
            .map(|_| if r.f32() < 0.4 { 0.0 } else { r.f32() * 3.0 })
            .collect();
        Grid::from_data(res, data, bbox).unwrap()
    }

    /// The exact set of cells a ray overlaps by more than `eps` of its length, by testing the
    /// ray against every cell's box, sorted by entry.
    fn brute_force(
        m: &MajorantGrid,
        o: Vec3,
        d: Vec3,
        t0: f32,
        t1: f32,
        eps: f32,
    ) -> Vec<[u32; 3]> {
        let r = m.res();
        let mut hits = Vec::new();
        for z in 0..r[2] {
            for y in 0..r[1] {
                for x in 0..r[0] {
                    let b = m.cell_box([x, y, z]);
                    if let Some((a, bb)) = b.intersect(o, d) {
                        let (a, bb) = (a.max(t0), bb.min(t1));
                        if bb - a > eps {
                            hits.push((a, [x, y, z]));
                        }
                    }
                }
            }
        }
        hits.sort_by(|p, q| p.0.total_cmp(&q.0));
        hits.into_iter().map(|h| h.1).collect()
    }

    /// On random rays (from outside and inside, any direction, including axis-parallel ones),
    /// the DDA visits exactly the cells a brute-force test of every cell finds, in the same
    /// order, and its segments tile the ray's interval in the box.
    #[test]
    fn dda_visits_exactly_the_cells_brute_force_finds() {
        let bbox = WorldBox::new(Vec3::new(-1.0, -0.5, 0.2), Vec3::new(1.5, 1.0, 1.4)).unwrap();
        let g = noise_grid([10, 7, 5], bbox);
        let m = MajorantGrid::build(&g, [7, 5, 3], 1.0);
        let mut r = Stream::new(9, 1, 0);
        let mut rays = 0;
        for i in 0..3000 {
            let o = bbox.centre()
                + (Vec3::new(r.f32(), r.f32(), r.f32()) - 0.5)
                    * bbox.extent()
                    * if i % 2 == 0 { 3.0 } else { 0.9 };
            let mut d = uniform_sphere(r.f32(), r.f32());
            if i % 7 == 0 {
                d = [
                    Vec3::X,
                    -Vec3::Y,
                    Vec3::Z,
                    Vec3::new(1.0, 1.0, 0.0).normalize(),
                ][i % 4];
            }
            let Some((t0, t1)) = bbox.intersect(o, d) else {
                continue;
            };
            rays += 1;
            let eps = 1e-4;
            let segs: Vec<Segment> = m.dda(o, d, t0, t1).collect();
            // The segments are contiguous and cover [t0, t1].
            assert_eq!(segs[0].t0, t0);
            assert!((segs.last().unwrap().t1 - t1).abs() < 1e-5);
            for w in segs.windows(2) {
                assert_eq!(w[0].t1, w[1].t0);
            }
            let dda: Vec<[u32; 3]> = segs
                .iter()
                .filter(|s| s.t1 - s.t0 > eps)
                .map(|s| s.cell)
                .collect();
            let want = brute_force(&m, o, d, t0, t1, eps);
            assert_eq!(dda, want, "ray {o} {d}");
            // Cells of near-zero segments (corner grazes) still touch the ray.
            for s in &segs {
                let b = m.cell_box(s.cell);
                let p = o + d * (0.5 * (s.t0 + s.t1));
                let grown = WorldBox {
                    min: b.min - 1e-4,
                    max: b.max + 1e-4,
                };
                assert!(
                    grown.contains(p),
                    "segment midpoint {p} outside cell {:?}",
                    s.cell
                );
            }
        }
        assert!(rays > 1500);
    }

    /// Every trilinear lookup inside a cell lies within its bounds.
    #[test]
    fn cell_bounds_hold_for_every_lookup() {
        let bbox = WorldBox::new(Vec3::ZERO, Vec3::new(2.0, 1.0, 1.0)).unwrap();
        let g = noise_grid([13, 6, 9], bbox);
        let m = MajorantGrid::build(&g, [4, 3, 2], 2.0);
        let mut r = Stream::new(3, 3, 3);
        for _ in 0..20_000 {
            let p = bbox.min + Vec3::new(r.f32(), r.f32(), r.f32()) * bbox.extent();
            let c = ((p - bbox.min) * m.to_cell).floor();
            let c = [c.x as u32, c.y as u32, c.z as u32];
            let v = 2.0 * g.trilinear(p);
            let b = m.bounds(c);
            assert!(
                v <= b.max * (1.0 + 1e-6) && v >= b.min * (1.0 - 1e-6),
                "{v} outside {b:?}"
            );
        }
        let gl = MajorantGrid::global(&g, 2.0);
        assert_eq!(gl.bounds([0, 0, 0]).max, 2.0 * g.max_value());
    }
}
