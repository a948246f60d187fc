//! A bush-like mesh: a cube-sphere (six `n` x `n` grids pushed onto the sphere) with a few
//! smooth lobes, squashed and sat on the ground. Each face's UVs are its grid coordinates, half
//! a tile per cell, so tiles are square-ish everywhere and line up across cube edges.

use super::RawMesh;
use glam::{DVec2, DVec3};

/// Cells per cube-face side of the built-in `bush` mesh.
pub const DEFAULT_DIVISIONS: usize = 24;

/// Cube coordinate of grid line `i` of `n`, equal-angle spaced, exactly +-1 at the ends so
/// neighbouring faces' edge vertices are bit-identical.
fn coord(i: usize, n: usize) -> f64 {
    if i == 0 {
        -1.0
    } else if i == n {
        1.0
    } else {
        (std::f64::consts::FRAC_PI_4 * (2.0 * i as f64 / n as f64 - 1.0)).tan()
    }
}

/// The lobed radius in unit direction `d`.
fn radius(d: DVec3) -> f64 {
    let lobes = [
        (DVec3::new(0.6, 0.7, 0.2), 0.42),
        (DVec3::new(-0.7, 0.5, 0.4), 0.36),
        (DVec3::new(0.1, 0.6, -0.8), 0.40),
        (DVec3::new(-0.2, 1.0, -0.1), 0.30),
        (DVec3::new(0.8, 0.1, -0.6), 0.28),
    ];
    1.0 + lobes
        .iter()
        .map(|&(c, a)| a * d.dot(c.normalize()).max(0.0).powi(4))
        .sum::<f64>()
}

/// The bush mesh with `n` cells per cube-face side.
pub fn raw(n: usize) -> RawMesh {
    let n = n.max(1);
    let mut raw = RawMesh::default();
    let mut uvs = Vec::new();
    for axis in 0..3 {
        for sign in [1.0, -1.0] {
            let base = raw.positions.len() as u32;
            for i in 0..=n {
                for j in 0..=n {
                    let mut c = [0.0; 3];
                    c[axis] = sign;
                    c[(axis + 1) % 3] = coord(i, n);
                    c[(axis + 2) % 3] = coord(j, n);
                    let d = DVec3::from_array(c).normalize();
                    let p = d * radius(d);
                    raw.positions.push(DVec3::new(p.x, 0.8 * p.y + 0.1, p.z));
                }
            }
            let id = |i: usize, j: usize| base + (i * (n + 1) + j) as u32;
            let uv = |i: usize, j: usize| DVec2::new(i as f64, j as f64) * 0.5;
            for i in 0..n {
                for j in 0..n {
                    let (a, b, c, d) = ((i, j), (i + 1, j), (i, j + 1), (i + 1, j + 1));
                    let quads = if sign > 0.0 {
                        [[a, b, c], [b, d, c]]
                    } else {
                        [[a, c, b], [b, c, d]]
                    };
                    for q in quads {
                        raw.triangles.push(q.map(|(x, y)| id(x, y)));
                        uvs.push(q.map(|(x, y)| uv(x, y)));
                    }
                }
            }
        }
    }
    raw.corner_uvs = Some(uvs);
    raw
}
