//! Checks of a finished mesh: is it a closed, consistently oriented 2-manifold (every edge in
//! exactly two triangles, once in each direction), its enclosed volume, and two-sided
//! Hausdorff distances to a known surface.

use crate::IsoMesh;
use glam::{DVec3, Vec3};
use std::collections::HashMap;

/// How the edges of a triangle mesh are shared.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct EdgeReport {
    /// Distinct undirected edges.
    pub edges: u64,
    /// Edges in exactly one triangle (holes).
    pub boundary: u64,
    /// Edges in more than two triangles.
    pub non_manifold: u64,
    /// Edges in two triangles that run the same way (inconsistent orientation).
    pub misoriented: u64,
    /// Triangles with a repeated vertex.
    pub degenerate: u64,
}

impl EdgeReport {
    /// Closed, oriented and 2-manifold.
    pub fn is_closed_manifold(&self) -> bool {
        self.boundary == 0
            && self.non_manifold == 0
            && self.misoriented == 0
            && self.degenerate == 0
    }
}

/// Counts how every edge is shared.
pub fn edges(tris: &[[u32; 3]]) -> EdgeReport {
    let mut count: HashMap<(u32, u32), (u32, u32)> = HashMap::with_capacity(tris.len() * 2);
    let mut r = EdgeReport::default();
    for t in tris {
        if t[0] == t[1] || t[1] == t[2] || t[0] == t[2] {
            r.degenerate += 1;
            continue;
        }
        for i in 0..3 {
            let (a, b) = (t[i], t[(i + 1) % 3]);
            let e = count.entry((a.min(b), a.max(b))).or_default();
            if a < b {
                e.0 += 1;
            } else {
                e.1 += 1;
            }
        }
    }
    r.edges = count.len() as u64;
    for &(f, b) in count.values() {
        match f + b {
            1 => r.boundary += 1,
            2 if f != 1 => r.misoriented += 1,
            2 => {}
            _ => r.non_manifold += 1,
        }
    }
    r
}

/// The enclosed volume (positive when the triangles face outward).
pub fn volume(m: &IsoMesh) -> f64 {
    m.tris
        .iter()
        .map(|t| {
            let [a, b, c] = t.map(|i| Vec3::from(m.verts[i as usize].p).as_dvec3());
            a.dot(b.cross(c)) / 6.0
        })
        .sum()
}

/// Distance from `p` to the triangle `abc` (Ericson, Real-Time Collision Detection 5.1.5).
pub fn point_triangle(p: DVec3, a: DVec3, b: DVec3, c: DVec3) -> f64 {
    let (ab, ac, ap) = (b - a, c - a, p - a);
    let (d1, d2) = (ab.dot(ap), ac.dot(ap));
    if d1 <= 0.0 && d2 <= 0.0 {
        return (p - a).length();
    }
    let bp = p - b;
    let (d3, d4) = (ab.dot(bp), ac.dot(bp));
    if d3 >= 0.0 && d4 <= d3 {
        return (p - b).length();
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        let v = d1 / (d1 - d3);
        return (p - (a + ab * v)).length();
    }
    let cp = p - c;
    let (d5, d6) = (ab.dot(cp), ac.dot(cp));
    if d6 >= 0.0 && d5 <= d6 {
        return (p - c).length();
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        let w = d2 / (d2 - d6);
        return (p - (a + ac * w)).length();
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
        let w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
        return (p - (b + (c - b) * w)).length();
    }
    let denom = 1.0 / (va + vb + vc);
    let (v, w) = (vb * denom, vc * denom);
    (p - (a + ab * v + ac * w)).length()
}

/// Nearest-triangle queries through a uniform hash of triangle bounding boxes.
pub struct TriangleIndex<'a> {
    mesh: &'a IsoMesh,
    cell: f64,
    buckets: HashMap<[i64; 3], Vec<u32>>,
}

impl<'a> TriangleIndex<'a> {
    /// Buckets of side `cell` (about the mesh's edge length).
    pub fn new(mesh: &'a IsoMesh, cell: f64) -> Self {
        let mut buckets: HashMap<[i64; 3], Vec<u32>> = HashMap::new();
        for (i, t) in mesh.tris.iter().enumerate() {
            let ps = t.map(|v| Vec3::from(mesh.verts[v as usize].p).as_dvec3());
            let lo = ps[0].min(ps[1]).min(ps[2]);
            let hi = ps[0].max(ps[1]).max(ps[2]);
            let (a, b) = (key(lo, cell), key(hi, cell));
            for x in a[0]..=b[0] {
                for y in a[1]..=b[1] {
                    for z in a[2]..=b[2] {
                        buckets.entry([x, y, z]).or_default().push(i as u32);
                    }
                }
            }
        }
        TriangleIndex {
            mesh,
            cell,
            buckets,
        }
    }

    /// Distance from `p` to the mesh, searching at most `reach` buckets out (`None` beyond).
    pub fn distance(&self, p: DVec3, reach: i64) -> Option<f64> {
        let k = key(p, self.cell);
        let mut best = f64::INFINITY;
        for x in -reach..=reach {
            for y in -reach..=reach {
                for z in -reach..=reach {
                    if let Some(ts) = self.buckets.get(&[k[0] + x, k[1] + y, k[2] + z]) {
                        for &t in ts {
                            let [a, b, c] = self.mesh.tris[t as usize]
                                .map(|v| Vec3::from(self.mesh.verts[v as usize].p).as_dvec3());
                            best = best.min(point_triangle(p, a, b, c));
                        }
                    }
                }
            }
        }
        (best <= reach as f64 * self.cell).then_some(best)
    }
}

fn key(p: DVec3, cell: f64) -> [i64; 3] {
    (p / cell).floor().as_i64vec3().to_array()
}

/// Two-sided Hausdorff distance between a mesh and the surface of the exact signed distance
/// `sdf`: the largest `|sdf|` over vertices and triangle centroids, and the largest distance
/// to the mesh over `samples` points on the true surface. Returns (mesh to surface, surface to
/// mesh).
pub fn hausdorff(
    mesh: &IsoMesh,
    sdf: &dyn Fn(DVec3) -> f64,
    samples: &[DVec3],
    voxel: f64,
) -> (f64, f64) {
    let mut to_surface: f64 = 0.0;
    for t in &mesh.tris {
        let ps = t.map(|v| Vec3::from(mesh.verts[v as usize].p).as_dvec3());
        for p in ps.into_iter().chain([(ps[0] + ps[1] + ps[2]) / 3.0]) {
            to_surface = to_surface.max(sdf(p).abs());
        }
    }
    let index = TriangleIndex::new(mesh, 2.0 * voxel);
    let to_mesh = samples
        .iter()
        .map(|&p| index.distance(p, 3).unwrap_or(f64::INFINITY))
        .fold(0.0, f64::max);
    (to_surface, to_mesh)
}

/// Moves `p` onto the zero set of an exact signed distance (a few Newton steps along the
/// numerical gradient).
pub fn project(sdf: &dyn Fn(DVec3) -> f64, mut p: DVec3) -> DVec3 {
    for _ in 0..8 {
        let d = sdf(p);
        let e = 1e-7;
        let g = DVec3::new(
            sdf(p + DVec3::X * e) - sdf(p - DVec3::X * e),
            sdf(p + DVec3::Y * e) - sdf(p - DVec3::Y * e),
            sdf(p + DVec3::Z * e) - sdf(p - DVec3::Z * e),
        ) / (2.0 * e);
        let g = if g.length_squared() > 0.0 {
            g.normalize()
        } else {
            DVec3::X
        };
        p -= g * d;
    }
    p
}
