//! The Utah teapot: Martin Newell's 32 bicubic Bezier patches (public domain, shipped as
//! `data/teapot.txt`), tessellated here into `divisions` x `divisions` quads per patch.
//!
//! Patches share their boundary control points, and a Bernstein evaluation at u = 0 or 1 reads
//! only that boundary row with exact weights, so neighbouring patches produce bit-identical
//! seam vertices, which [`super::TriangleMesh::build`] welds. The collapsed rows at the lid's knob and
//! the bottom's centre give degenerate triangles, skipped (and counted) there. UVs run over each
//! patch with a whole number of tiles per side, about `tile` world units each, so tiles meet
//! at patch seams. The teapot is turned y-up, scaled by 0.5 and centred on the origin.

use super::RawMesh;
use glam::{DVec2, DVec3};

/// Quads per patch side of the built-in `teapot` mesh.
pub const DEFAULT_DIVISIONS: usize = 14;
/// Tile size in world units of the built-in `teapot` mesh.
pub const DEFAULT_TILE: f64 = 0.12;

const DATA: &str = include_str!("../../data/teapot.txt");

/// The 32 patches as 16 control points each (z up, as published).
pub fn patches() -> Vec<[DVec3; 16]> {
    let mut lines = DATA
        .lines()
        .filter(|l| !l.starts_with('#') && !l.trim().is_empty());
    let mut header = |want: &str| -> usize {
        let l = lines.next().expect("teapot data: header");
        let (w, n) = l.split_once(' ').expect("teapot data: header");
        assert_eq!(w, want, "teapot data");
        n.trim().parse().expect("teapot data: count")
    };
    let np = header("patches");
    let idx: Vec<Vec<usize>> = (0..np)
        .map(|_| {
            lines
                .next()
                .expect("teapot data: patch")
                .split_whitespace()
                .map(|w| w.parse::<usize>().expect("teapot data: index") - 1)
                .collect()
        })
        .collect();
    let nv = {
        let l = lines.next().expect("teapot data: points");
        l.trim_start_matches("points")
            .trim()
            .parse::<usize>()
            .expect("teapot data")
    };
    let pts: Vec<DVec3> = (0..nv)
        .map(|_| {
            let v: Vec<f64> = lines
                .next()
                .expect("teapot data: point")
                .split_whitespace()
                .map(|w| w.parse().expect("teapot data: coordinate"))
                .collect();
            DVec3::new(v[0], v[1], v[2])
        })
        .collect();
    idx.iter()
        .map(|p| std::array::from_fn(|k| pts[p[k]]))
        .collect()
}

fn bernstein(t: f64) -> [f64; 4] {
    let s = 1.0 - t;
    [s * s * s, 3.0 * s * s * t, 3.0 * s * t * t, t * t * t]
}

/// The point of patch `p` at (u, v): u runs over the rows of control points, v along them.
pub fn eval(p: &[DVec3; 16], u: f64, v: f64) -> DVec3 {
    let (bu, bv) = (bernstein(u), bernstein(v));
    let mut acc = DVec3::ZERO;
    for i in 0..4 {
        for j in 0..4 {
            acc += p[4 * i + j] * (bu[i] * bv[j]);
        }
    }
    acc
}

/// Published (z up) to ours (y up, half size, centred).
fn to_world(q: DVec3) -> DVec3 {
    DVec3::new(q.x, q.z - 1.575, -q.y) * 0.5
}

/// The tessellated teapot.
pub fn raw(divisions: usize, tile: f64) -> RawMesh {
    let n = divisions.max(1);
    let mut raw = RawMesh::default();
    let mut uvs = Vec::new();
    for p in patches() {
        let base = raw.positions.len() as u32;
        let grid: Vec<DVec3> = (0..=n)
            .flat_map(|i| (0..=n).map(move |j| (i, j)))
            .map(|(i, j)| to_world(eval(&p, i as f64 / n as f64, j as f64 / n as f64)))
            .collect();
        let at = |i: usize, j: usize| grid[i * (n + 1) + j];
        // Mean lengths of the isolines give a whole number of tiles per side.
        let len = |along_u: bool| -> f64 {
            (0..=n)
                .map(|k| {
                    (0..n)
                        .map(|m| {
                            if along_u {
                                (at(m + 1, k) - at(m, k)).length()
                            } else {
                                (at(k, m + 1) - at(k, m)).length()
                            }
                        })
                        .sum::<f64>()
                })
                .sum::<f64>()
                / (n + 1) as f64
        };
        let tu = (len(true) / tile).round().max(1.0);
        let tv = (len(false) / tile).round().max(1.0);
        raw.positions.extend(&grid);
        let id = |i: usize, j: usize| base + (i * (n + 1) + j) as u32;
        let uv =
            |i: usize, j: usize| DVec2::new(i as f64 / n as f64 * tu, j as f64 / n as f64 * tv);
        for i in 0..n {
            for j in 0..n {
                // Outward is Pv x Pu for this data set.
                raw.triangles.push([id(i, j), id(i, j + 1), id(i + 1, j)]);
                uvs.push([uv(i, j), uv(i, j + 1), uv(i + 1, j)]);
                raw.triangles
                    .push([id(i + 1, j), id(i, j + 1), id(i + 1, j + 1)]);
                uvs.push([uv(i + 1, j), uv(i, j + 1), uv(i + 1, j + 1)]);
            }
        }
    }
    raw.corner_uvs = Some(uvs);
    raw
}
