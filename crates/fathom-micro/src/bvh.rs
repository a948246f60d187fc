//! The bounding volume hierarchy over a shell's tetrahedra: built top-down, each node's
//! tetrahedra split at the median of their centres along the widest axis. That bounds the
//! depth by log2 of the count and the build time by n log n whatever the mesh: a bottom-up
//! PLOC build (`obvhs`) degenerated into a chain on one vertex shared by 40,000 triangles (a
//! fan, or one big OBJ face triangulated as one), quadratic in time and deep enough to
//! overflow the stack. The renderer asks it for every tetrahedron whose box a ray crosses and
//! clips each exactly; boxes are in f64 and padded, so rounding never drops a tetrahedron.

use crate::shell::Shell;
use crate::tet::Span;
use glam::DVec3;

/// Most tetrahedra in a leaf.
const LEAF: usize = 4;

/// A node's box; a leaf holds `order[first..first + count]`, an inner node (`count` 0) has
/// its children at `first` and `first + 1`.
#[derive(Clone, Copy, Debug)]
struct Node {
    lo: DVec3,
    hi: DVec3,
    first: u32,
    count: u32,
}

/// A BVH over the tetrahedra of one shell.
pub struct ShellBvh {
    nodes: Vec<Node>,
    order: Vec<u32>,
    boxes: Vec<(DVec3, DVec3)>,
}

impl ShellBvh {
    /// Builds the hierarchy (deterministic: ties in the median split go by index).
    pub fn build(shell: &Shell) -> ShellBvh {
        let (lo, hi) = shell.bounds;
        let pad = 1e-9 * (hi - lo).length().max(1e-300);
        let boxes: Vec<(DVec3, DVec3)> = shell
            .tets
            .iter()
            .map(|t| {
                let (a, b) = t
                    .verts
                    .iter()
                    .fold((DVec3::INFINITY, DVec3::NEG_INFINITY), |(a, b), &p| {
                        (a.min(p), b.max(p))
                    });
                (a - DVec3::splat(pad), b + DVec3::splat(pad))
            })
            .collect();
        let centre: Vec<DVec3> = boxes.iter().map(|(a, b)| 0.5 * (*a + *b)).collect();
        let mut order: Vec<u32> = (0..boxes.len() as u32).collect();
        let empty = Node {
            lo: DVec3::INFINITY,
            hi: DVec3::NEG_INFINITY,
            first: 0,
            count: 0,
        };
        let mut nodes = vec![empty];
        let mut work = vec![(0usize, 0usize, order.len())];
        while let Some((ni, s, e)) = work.pop() {
            let ids = &mut order[s..e];
            let (blo, bhi) = ids.iter().fold((empty.lo, empty.hi), |(a, b), &i| {
                (a.min(boxes[i as usize].0), b.max(boxes[i as usize].1))
            });
            let (clo, chi) = ids.iter().fold((empty.lo, empty.hi), |(a, b), &i| {
                (a.min(centre[i as usize]), b.max(centre[i as usize]))
            });
            let ext = chi - clo;
            nodes[ni].lo = blo;
            nodes[ni].hi = bhi;
            let spread = ext.max_element().partial_cmp(&0.0) == Some(std::cmp::Ordering::Greater);
            if e - s <= LEAF || !spread {
                nodes[ni].first = s as u32;
                nodes[ni].count = (e - s) as u32;
                continue;
            }
            let axis = if ext.x >= ext.y && ext.x >= ext.z {
                0
            } else if ext.y >= ext.z {
                1
            } else {
                2
            };
            let mid = (e - s) / 2;
            ids.select_nth_unstable_by(mid, |&a, &b| {
                centre[a as usize][axis]
                    .total_cmp(&centre[b as usize][axis])
                    .then(a.cmp(&b))
            });
            let left = nodes.len();
            nodes.extend([empty, empty]);
            nodes[ni].first = left as u32;
            work.push((left, s, s + mid));
            work.push((left + 1, s + mid, e));
        }
        ShellBvh {
            nodes,
            order,
            boxes,
        }
    }

    /// Whether the ray `o + t d` (`inv` = 1 / d per axis) meets the box for some t in
    /// [0, t_max].
    fn hits(lo: DVec3, hi: DVec3, o: DVec3, d: DVec3, inv: DVec3, t_max: f64) -> bool {
        let (mut t0, mut t1) = (0.0f64, t_max);
        for k in 0..3 {
            if d[k] == 0.0 {
                if o[k] < lo[k] || o[k] > hi[k] {
                    return false;
                }
                continue;
            }
            let (a, b) = ((lo[k] - o[k]) * inv[k], (hi[k] - o[k]) * inv[k]);
            t0 = t0.max(a.min(b));
            t1 = t1.min(a.max(b));
            // f64::min and max pass over a NaN, so none reaches t0 or t1.
            if t0 > t1 {
                return false;
            }
        }
        true
    }

    /// Every tetrahedron the ray `o + t d`, `t` in [0, `t_max`], passes through, with its
    /// exact span (entry clamped to 0), in order of entry (ties by index, so the order does not
    /// depend on the traversal). `out` is cleared first.
    pub fn spans(&self, shell: &Shell, o: DVec3, d: DVec3, t_max: f64, out: &mut Vec<(Span, u32)>) {
        out.clear();
        if self.order.is_empty() {
            return;
        }
        let inv = d.recip();
        let mut stack = vec![0u32];
        while let Some(ni) = stack.pop() {
            let n = self.nodes[ni as usize];
            if !Self::hits(n.lo, n.hi, o, d, inv, t_max) {
                continue;
            }
            if n.count == 0 {
                stack.extend([n.first, n.first + 1]);
                continue;
            }
            for &ti in &self.order[n.first as usize..(n.first + n.count) as usize] {
                let (lo, hi) = self.boxes[ti as usize];
                if !Self::hits(lo, hi, o, d, inv, t_max) {
                    continue;
                }
                if let Some(mut s) = shell.tets[ti as usize].clip(o, d)
                    && s.t_out > 0.0
                    && s.t_in < t_max
                {
                    if s.t_in < 0.0 {
                        s.t_in = 0.0;
                        s.face_in = 4;
                    }
                    out.push((s, ti));
                }
            }
        }
        out.sort_by(|a, b| a.0.t_in.total_cmp(&b.0.t_in).then(a.1.cmp(&b.1)));
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::{RawMesh, TriangleMesh, UvProjection};
    use crate::texture::Tiling;

    /// `n` triangles around one vertex: the shape that made the bottom-up build quadratic.
    fn fan(n: usize) -> Shell {
        let mut positions = vec![DVec3::ZERO];
        for i in 0..=n {
            let a = 6.0 * i as f64 / n as f64;
            positions.push(DVec3::new(a.cos(), 0.0, a.sin()));
        }
        let triangles = (0..n as u32).map(|i| [0, i + 2, i + 1]).collect();
        let raw = RawMesh {
            positions,
            triangles,
            corner_normals: None,
            corner_uvs: None,
        };
        let (m, _) = TriangleMesh::build(raw, Some(UvProjection::Planar), "fan").unwrap();
        Shell::build(&m, 0.01, &Tiling::default()).unwrap()
    }

    fn depth(b: &ShellBvh) -> usize {
        let mut deepest = 0;
        let mut stack = vec![(0u32, 1usize)];
        while let Some((ni, d)) = stack.pop() {
            deepest = deepest.max(d);
            let n = b.nodes[ni as usize];
            if n.count == 0 {
                stack.extend([(n.first, d + 1), (n.first + 1, d + 1)]);
            }
        }
        deepest
    }

    #[test]
    fn a_40k_triangle_fan_builds_shallow() {
        let shell = fan(40_000);
        let b = ShellBvh::build(&shell);
        // 120,000 tetrahedra, 4 a leaf: 15 levels of halving.
        assert!(depth(&b) <= 17, "depth {}", depth(&b));
    }

    #[test]
    fn spans_are_what_clipping_every_tetrahedron_finds() {
        let shell = fan(300);
        let b = ShellBvh::build(&shell);
        let mut got = Vec::new();
        let mut found = 0;
        for k in 0..200 {
            let a = k as f64 * 0.37;
            let o = DVec3::new(a.cos() * 2.0, 0.5 + (k % 7) as f64 * 0.1, a.sin() * 2.0);
            let d = (DVec3::new((k % 5) as f64 * 0.1, -0.05, 0.0) - o).normalize();
            b.spans(&shell, o, d, 10.0, &mut got);
            let mut want: Vec<u32> = (0..shell.tets.len() as u32)
                .filter(|&i| {
                    shell.tets[i as usize]
                        .clip(o, d)
                        .is_some_and(|s| s.t_out > 0.0 && s.t_in < 10.0)
                })
                .collect();
            want.sort_unstable();
            let mut ids: Vec<u32> = got.iter().map(|g| g.1).collect();
            ids.sort_unstable();
            assert_eq!(ids, want, "ray {k}");
            found += ids.len();
        }
        assert!(found > 100, "the rays should cross the shell: {found}");
    }
}
