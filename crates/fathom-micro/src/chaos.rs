//! Chaos-game point clouds of iterated function systems (Barnsley 1988; Hart 1991): affine maps
//! picked at random by their probabilities, an optional 3D shear of every point and a small
//! deterministic jitter ("noise"), for a fern and a tree; and their distance field.
//!
//! The seed baked such clouds into a distance grid and lost their detail. Here a [`Cloud`]
//! answers the distance to the union of small spheres around the points exactly, through a k-d
//! tree (`kiddo`), wherever that distance is small; far from the points a coarse grid of exact
//! node distances gives a lower bound `d(node) - |q - node|` (the distance is 1-Lipschitz), so
//! rays skip empty space without a tree query. Zooming in therefore shows the points
//! themselves, down to the sphere radius, instead of a grid's blur.

use crate::cell::Cell;
use crate::error::{MicroError, check_range};
use crate::grid::Grid;
use crate::limits;
use fathom_core::rng::SplitMix64 as Rng;
use glam::{DMat3, DVec3};
use kiddo::{ImmutableKdTree, SquaredEuclidean};

/// One affine map `p -> linear p + offset`, chosen with `probability`.
#[derive(Clone, Debug)]
pub struct Map {
    /// The linear part.
    pub linear: DMat3,
    /// The translation.
    pub offset: DVec3,
    /// How often the chaos game picks this map (the maps' probabilities sum to 1).
    pub probability: f64,
}

/// An iterated function system for the chaos game.
#[derive(Clone, Debug)]
pub struct Ifs {
    /// The name `--texture cloud:NAME` takes.
    pub name: &'static str,
    /// The affine maps.
    pub maps: Vec<Map>,
    /// Applied to every output point (a lean or a twist of the whole attractor).
    pub shear: DMat3,
    /// Jitter of each output point, relative to the attractor's size.
    pub noise: f64,
}

fn rows(r: [[f64; 3]; 3]) -> DMat3 {
    DMat3::from_cols_array_2d(&r).transpose()
}

/// The built-in systems, by name.
pub const SYSTEMS: &[&str] = &["fern", "tree"];

impl Ifs {
    /// A built-in system by name; unknown names list the valid ones.
    pub fn named(name: &str) -> Result<Ifs, MicroError> {
        match name {
            "fern" => Ok(Ifs::fern()),
            "tree" => Ok(Ifs::tree()),
            _ => Err(MicroError::Texture {
                origin: name.into(),
                msg: format!(
                    "unknown chaos-game system; expected one of: {}",
                    SYSTEMS.join(", ")
                ),
            }),
        }
    }

    /// Barnsley's fern, its leaflets turned out of the plane (a z shear on the leaflet maps)
    /// and the frond curling as it grows.
    pub fn fern() -> Ifs {
        let curl = DMat3::from_rotation_y(0.12);
        Ifs {
            name: "fern",
            maps: vec![
                Map {
                    linear: rows([[0.0, 0.0, 0.0], [0.0, 0.16, 0.0], [0.0, 0.0, 0.0]]),
                    offset: DVec3::ZERO,
                    probability: 0.01,
                },
                Map {
                    linear: curl * rows([[0.85, 0.04, 0.0], [-0.04, 0.85, 0.0], [0.0, 0.0, 0.85]]),
                    offset: DVec3::new(0.0, 1.6, 0.0),
                    probability: 0.85,
                },
                Map {
                    linear: rows([[0.2, -0.26, 0.0], [0.23, 0.22, 0.0], [0.25, 0.0, 0.24]]),
                    offset: DVec3::new(0.0, 1.6, 0.0),
                    probability: 0.07,
                },
                Map {
                    linear: rows([[-0.15, 0.28, 0.0], [0.26, 0.24, 0.0], [-0.25, 0.0, 0.24]]),
                    offset: DVec3::new(0.0, 0.44, 0.0),
                    probability: 0.07,
                },
            ],
            shear: rows([[1.0, 0.08, 0.0], [0.0, 1.0, 0.0], [0.0, 0.05, 1.0]]),
            noise: 0.0015,
        }
    }

    /// A tree: a trunk and three branches, each a smaller copy of the tree turned 120 degrees
    /// about the trunk from the last and tilted 35 degrees out.
    pub fn tree() -> Ifs {
        let mut maps = vec![Map {
            linear: DMat3::from_diagonal(DVec3::new(0.04, 0.55, 0.04)),
            offset: DVec3::ZERO,
            probability: 0.1,
        }];
        for k in 0..3 {
            let turn = DMat3::from_rotation_y(k as f64 * std::f64::consts::TAU / 3.0 + 0.3);
            let tilt = DMat3::from_rotation_z(35f64.to_radians());
            maps.push(Map {
                linear: turn * tilt * DMat3::from_diagonal(DVec3::splat(0.58)),
                offset: DVec3::new(0.0, 0.5, 0.0),
                probability: 0.3,
            });
        }
        Ifs {
            name: "tree",
            maps,
            shear: DMat3::IDENTITY,
            noise: 0.002,
        }
    }

    /// Runs the chaos game for `n` points (after 32 discarded ones) from `seed`.
    pub fn points(&self, n: u64, seed: u64) -> Result<Vec<DVec3>, MicroError> {
        check_range(
            "cloud points",
            n as f64,
            1.0,
            limits::MAX_CLOUD_POINTS as f64,
            "[1, 16777216]",
        )?;
        let total: f64 = self.maps.iter().map(|m| m.probability).sum();
        if !(total > 0.0 && total.is_finite()) || self.maps.iter().any(|m| m.probability < 0.0) {
            return Err(MicroError::Texture {
                origin: self.name.into(),
                msg: "map probabilities must be non-negative and sum to more than 0".into(),
            });
        }
        let mut rng = Rng(seed);
        let mut p = DVec3::ZERO;
        let mut out = Vec::with_capacity(n as usize);
        let mut jitter = Vec::with_capacity(n as usize);
        for i in 0..n + 32 {
            let mut r = rng.unit() * total;
            let m = self
                .maps
                .iter()
                .find(|m| {
                    r -= m.probability;
                    r < 0.0
                })
                .unwrap_or(&self.maps[self.maps.len() - 1]);
            p = m.linear * p + m.offset;
            let j = DVec3::new(rng.unit(), rng.unit(), rng.unit()) * 2.0 - 1.0;
            if i >= 32 {
                out.push(self.shear * p);
                jitter.push(j);
            }
        }
        let (lo, hi) = bounds(&out);
        let size = (hi - lo).max_element();
        for (q, j) in out.iter_mut().zip(jitter) {
            *q += j * (self.noise * size);
        }
        Ok(out)
    }
}

fn bounds(p: &[DVec3]) -> (DVec3, DVec3) {
    p.iter()
        .fold((DVec3::INFINITY, DVec3::NEG_INFINITY), |(a, b), &q| {
            (a.min(q), b.max(q))
        })
}

/// Scales and moves `points` uniformly so they stand in `cell`: centred across, base on the
/// floor, 95% of the cell's height or width, whichever binds.
pub fn fit_to_cell(points: &mut [DVec3], cell: Cell) {
    let (lo, hi) = bounds(points);
    let ext = (hi - lo).max(DVec3::splat(1e-12));
    let room = cell.size() * 0.95;
    let s = (room / ext).min_element();
    let centre = 0.5 * (lo + hi);
    let target = DVec3::new(
        0.5 * (cell.min.x + cell.max.x),
        cell.min.y,
        0.5 * (cell.min.z + cell.max.z),
    );
    for p in points.iter_mut() {
        let q = (*p - centre) * s;
        *p = DVec3::new(
            target.x + q.x,
            cell.min.y + (p.y - lo.y) * s,
            target.z + q.z,
        );
    }
}

/// The distance field of a point cloud: spheres of `radius` around every point.
pub struct Cloud {
    tree: ImmutableKdTree<f32, 3>,
    /// Points in the cloud.
    pub points: usize,
    /// Radius of the sphere around each point, texture-scene units.
    pub radius: f64,
    coarse: Grid,
    /// Below this coarse bound the k-d tree is asked.
    near: f64,
}

impl Cloud {
    /// Indexes `points`; `coarse_n` samples per axis of `cell` for the far-field bound.
    pub fn new(
        points: &[DVec3],
        radius: f64,
        cell: Cell,
        coarse_n: u32,
    ) -> Result<Cloud, MicroError> {
        check_range(
            "cloud radius",
            radius,
            1e-9,
            1e3,
            "[1e-9, 1000] texture units",
        )?;
        let pts: Vec<[f32; 3]> = points
            .iter()
            .map(|p| [p.x as f32, p.y as f32, p.z as f32])
            .collect();
        let tree =
            ImmutableKdTree::<f32, 3>::new_from_slice(&pts).map_err(|e| MicroError::Texture {
                origin: "point cloud".into(),
                msg: format!("cannot index the points: {e:?}"),
            })?;
        let exact = |q: DVec3| nearest(&tree, q) - radius;
        let coarse = Grid::bake_with(cell, coarse_n, |_, q| (exact(q), 0))?;
        let near = 1.5 * coarse.cell.size().max_element() / (coarse_n - 1) as f64;
        Ok(Cloud {
            tree,
            points: pts.len(),
            radius,
            coarse,
            near,
        })
    }

    /// The exact distance to the spheres (one k-d tree query).
    pub fn exact(&self, q: DVec3) -> f64 {
        nearest(&self.tree, q) - self.radius
    }

    /// A distance bound: the coarse grid's lower bound where it is large, else exact.
    pub fn distance(&self, q: DVec3) -> f64 {
        let lower = self.coarse.nearest_node_bound(q);
        if lower > self.near {
            lower
        } else {
            self.exact(q)
        }
    }
}

fn nearest(tree: &ImmutableKdTree<f32, 3>, q: DVec3) -> f64 {
    let r = tree
        .query(&[q.x as f32, q.y as f32, q.z as f32])
        .nearest_one::<SquaredEuclidean<f32>>()
        .execute();
    (r.distance as f64).sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn chaos_game_is_deterministic_and_stays_in_the_attractor_box() {
        for ifs in [Ifs::fern(), Ifs::tree()] {
            let a = ifs.points(5000, 7).unwrap();
            assert_eq!(a, ifs.points(5000, 7).unwrap());
            assert_ne!(a, ifs.points(5000, 8).unwrap());
            let (lo, hi) = bounds(&a);
            assert!(
                (hi - lo).max_element() < 20.0 && a.iter().all(|p| p.is_finite()),
                "{}",
                ifs.name
            );
            // Not flat: the shear and the 3D maps give depth.
            assert!(
                (hi - lo).min_element() > 0.05 * (hi - lo).max_element(),
                "{}: {:?}",
                ifs.name,
                hi - lo
            );
        }
        assert!(
            Ifs::named("elm")
                .unwrap_err()
                .to_string()
                .contains("fern, tree")
        );
        assert!(Ifs::fern().points(0, 1).is_err());
    }

    #[test]
    fn cloud_distance_is_the_exact_distance_to_the_nearest_sphere() {
        let mut pts = Ifs::fern().points(3000, 3).unwrap();
        fit_to_cell(&mut pts, Cell::UNIT);
        let (lo, hi) = bounds(&pts);
        assert!(lo.cmpge(DVec3::splat(-1.0)).all() && hi.cmple(DVec3::splat(1.0)).all());
        let cloud = Cloud::new(&pts, 0.01, Cell::UNIT, 24).unwrap();
        let mut rng = Rng(11);
        for _ in 0..300 {
            let q = DVec3::new(rng.unit(), rng.unit(), rng.unit()) * 2.0 - 1.0;
            let brute = pts
                .iter()
                .map(|p| (*p - q).length())
                .fold(f64::MAX, f64::min)
                - 0.01;
            // f32 coordinates in the tree.
            assert!((cloud.exact(q) - brute).abs() < 1e-5, "{q:?}");
            let d = cloud.distance(q);
            assert!(
                d <= brute + 1e-5,
                "the bound exceeds the distance at {q:?}: {d} > {brute}"
            );
            assert!(
                d > brute - 0.2,
                "the bound is useless at {q:?}: {d} vs {brute}"
            );
        }
    }
}
