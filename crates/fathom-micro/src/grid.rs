//! Baked textures: a distance field sampled once on an `n`^3 grid over a box, then read back
//! with trilinear interpolation (the seed's "precomputed distance fields"), with the error
//! against the exact field measured rather than assumed.

use crate::cell::Cell;
use crate::error::{MicroError, check_range};
use crate::limits;
use fathom_core::{Evaluator, Tape, V3};
use glam::DVec3;
use rayon::prelude::*;

/// A sampled distance field over a box, with the nearest sample's material id.
#[derive(Clone, Debug)]
pub struct Grid {
    /// Samples per axis.
    pub n: u32,
    /// The box sampled.
    pub cell: Cell,
    step: DVec3,
    dist: Vec<f32>,
    ids: Vec<u16>,
}

/// The baked grid's error against the exact field at random points of its box.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct GridError {
    /// Random points measured.
    pub samples: usize,
    /// Mean absolute error over all samples.
    pub mean_abs: f64,
    /// Largest absolute error over all samples.
    pub max_abs: f64,
    /// Mean absolute error over samples within two grid spacings of the surface (where it
    /// decides what is drawn).
    pub near_surface_mean_abs: f64,
    /// Samples within two grid spacings of the surface.
    pub near_surface_samples: usize,
}

impl Grid {
    /// Samples `f` (distance, material id) at the `n`^3 nodes spanning `cell`. Rows run in
    /// parallel; the result does not depend on the thread count.
    pub fn bake_with<F>(cell: Cell, n: u32, f: F) -> Result<Grid, MicroError>
    where
        F: Fn(&mut Evaluator<f64>, DVec3) -> (f64, u16) + Sync,
    {
        check_range(
            "grid resolution",
            n as f64,
            2.0,
            limits::MAX_GRID as f64,
            "[2, 512] samples per axis",
        )?;
        let step = cell.size() / (n - 1) as f64;
        let nn = n as usize;
        let rows: Vec<(Vec<f32>, Vec<u16>)> = (0..nn * nn)
            .into_par_iter()
            .map_init(Evaluator::<f64>::new, |ev, r| {
                let (y, z) = (r % nn, r / nn);
                (0..nn)
                    .map(|x| {
                        let p = cell.min + DVec3::new(x as f64, y as f64, z as f64) * step;
                        let (d, id) = f(ev, p);
                        (d as f32, id)
                    })
                    .unzip()
            })
            .collect();
        let (mut dist, mut ids) = (Vec::with_capacity(nn.pow(3)), Vec::with_capacity(nn.pow(3)));
        for (d, i) in rows {
            dist.extend(d);
            ids.extend(i);
        }
        Ok(Grid {
            n,
            cell,
            step,
            dist,
            ids,
        })
    }

    /// Bakes a tape's distances and material ids.
    pub fn bake(tape: &Tape, cell: Cell, n: u32) -> Result<Grid, MicroError> {
        Grid::bake_with(cell, n, |ev, p| {
            let v = ev.eval(tape, V3::new(p.x, p.y, p.z));
            (v.d, v.id.clamp(0.0, u16::MAX as f64) as u16)
        })
    }

    /// Bytes held by the samples (distances and ids).
    pub fn memory_bytes(&self) -> usize {
        self.dist.len() * 4 + self.ids.len() * 2
    }

    #[inline]
    fn at(&self, x: usize, y: usize, z: usize) -> f64 {
        let n = self.n as usize;
        self.dist[(z * n + y) * n + x] as f64
    }

    /// Trilinear interpolation at `q`; outside the box, the value at the nearest box point
    /// plus the distance to it.
    pub fn sample(&self, q: DVec3) -> f64 {
        let c = q.clamp(self.cell.min, self.cell.max);
        let outside = (q - c).length();
        let g = (c - self.cell.min) / self.step;
        let m = (self.n - 2) as f64;
        let i = g.floor().clamp(DVec3::ZERO, DVec3::splat(m));
        let f = g - i;
        let (x, y, z) = (i.x as usize, i.y as usize, i.z as usize);
        let l = |a: f64, b: f64, t: f64| a + (b - a) * t;
        let c00 = l(self.at(x, y, z), self.at(x + 1, y, z), f.x);
        let c10 = l(self.at(x, y + 1, z), self.at(x + 1, y + 1, z), f.x);
        let c01 = l(self.at(x, y, z + 1), self.at(x + 1, y, z + 1), f.x);
        let c11 = l(self.at(x, y + 1, z + 1), self.at(x + 1, y + 1, z + 1), f.x);
        l(l(c00, c10, f.y), l(c01, c11, f.y), f.z) + outside
    }

    /// The material id of the sample nearest to `q`.
    pub fn material_at(&self, q: DVec3) -> u16 {
        let g = ((q.clamp(self.cell.min, self.cell.max) - self.cell.min) / self.step).round();
        let n = self.n as usize;
        let (x, y, z) = (g.x as usize, g.y as usize, g.z as usize);
        self.ids[(z.min(n - 1) * n + y.min(n - 1)) * n + x.min(n - 1)]
    }

    /// Compares with the exact field `exact` at `samples` deterministic random points.
    pub fn error_against<F: Fn(&mut Evaluator<f64>, DVec3) -> f64>(
        &self,
        exact: F,
        samples: usize,
    ) -> GridError {
        let mut ev = Evaluator::<f64>::new();
        let mut rng = fathom_core::rng::SplitMix64(0x005e_ed0f_9e1d);
        let mut e = GridError {
            samples,
            ..Default::default()
        };
        let (mut sum, mut near) = (0.0, 0.0);
        let band = 2.0 * self.step.max_element();
        for _ in 0..samples {
            let u = DVec3::new(rng.unit(), rng.unit(), rng.unit());
            let p = self.cell.min + u * self.cell.size();
            let want = exact(&mut ev, p);
            let err = (self.sample(p) - want).abs();
            sum += err;
            e.max_abs = e.max_abs.max(err);
            if want.abs() < band {
                near += err;
                e.near_surface_samples += 1;
            }
        }
        e.mean_abs = sum / samples.max(1) as f64;
        e.near_surface_mean_abs = near / e.near_surface_samples.max(1) as f64;
        e
    }
}

impl Grid {
    /// `d(node) - |q - node|` at the node nearest `q`: a lower bound of any 1-Lipschitz field
    /// whose node values these are.
    pub fn nearest_node_bound(&self, q: DVec3) -> f64 {
        let g = ((q - self.cell.min) / self.step).round();
        let m = (self.n - 1) as f64;
        let i = g.clamp(DVec3::ZERO, DVec3::splat(m));
        let node = self.cell.min + i * self.step;
        self.at(i.x as usize, i.y as usize, i.z as usize) - (q - node).length()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use fathom_core::primitives::Primitive;
    use fathom_core::scene::{Call, Node, Scene};
    use fathom_core::transforms::Transform;

    fn texture() -> Tape {
        let s = Scene::new(
            Node::new(
                Call::new(Primitive::Torus)
                    .with("major", &[0.6])
                    .with("minor", &[0.15]),
            )
            .child(
                Node::new(Call::new(Primitive::Sphere).with("radius", &[0.3]))
                    .op(Call::new(Transform::Translate).with("offset", &[0.2, 0.3, -0.1])),
            ),
        );
        Tape::compile(&s).unwrap()
    }

    #[test]
    fn baked_grid_error_shrinks_as_resolution_grows() {
        let tape = texture();
        let exact = |ev: &mut Evaluator<f64>, p: DVec3| ev.distance(&tape, V3::new(p.x, p.y, p.z));
        let errs: Vec<GridError> = [8u32, 16, 32, 64]
            .iter()
            .map(|&n| {
                Grid::bake(&tape, Cell::UNIT, n)
                    .unwrap()
                    .error_against(exact, 4000)
            })
            .collect();
        for w in errs.windows(2) {
            assert!(
                w[1].mean_abs < 0.75 * w[0].mean_abs
                    && w[1].near_surface_mean_abs < w[0].near_surface_mean_abs,
                "error does not shrink: {errs:#?}"
            );
        }
        assert!(errs[3].mean_abs < 2e-3, "{:?}", errs[3]);
        // Exact at the nodes.
        let g = Grid::bake(&tape, Cell::UNIT, 5).unwrap();
        assert!(
            (g.sample(DVec3::new(0.5, 0.0, -1.0))
                - exact(&mut Evaluator::new(), DVec3::new(0.5, 0.0, -1.0)))
            .abs()
                < 1e-6
        );
        assert_eq!(g.memory_bytes(), 125 * 6);
    }

    #[test]
    fn resolutions_outside_the_range_are_refused() {
        let tape = texture();
        for n in [0, 1, limits::MAX_GRID + 1] {
            let e = Grid::bake(&tape, Cell::UNIT, n).unwrap_err().to_string();
            assert!(
                e.contains("grid resolution") && e.contains("[2, 512]"),
                "{e}"
            );
        }
    }
}
