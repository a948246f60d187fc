//! The bounding volume hierarchy over a shell's tetrahedra, from `obvhs` (PLOC build with
//! reinsertion, a well-kept crate that takes glam types and any boundable primitive). The CPU
//! renderer asks it for every tetrahedron whose box a ray crosses and clips each exactly in
//! f64; boxes are padded so f32 rounding never drops a tetrahedron the ray touches.

use crate::shell::Shell;
use crate::tet::Span;
use glam::{DVec3, Vec3A};
use obvhs::aabb::Aabb;
use obvhs::bvh2::Bvh2;
use obvhs::ray::Ray;

struct Bounded(Aabb);

impl obvhs::Boundable for Bounded {
    fn aabb(&self) -> Aabb {
        self.0
    }
}

/// A BVH over the tetrahedra of one shell.
pub struct ShellBvh {
    bvh: Bvh2,
}

fn v3a(p: DVec3) -> Vec3A {
    Vec3A::new(p.x as f32, p.y as f32, p.z as f32)
}

impl ShellBvh {
    /// Builds the hierarchy (deterministic: obvhs builds single-threaded without its
    /// `parallel` feature).
    pub fn build(shell: &Shell) -> ShellBvh {
        let (lo, hi) = shell.bounds;
        let pad = 1e-5 * (hi - lo).length().max(1e-30) as f32;
        let prims: Vec<Bounded> = shell
            .tets
            .iter()
            .map(|t| {
                let (a, b) = t
                    .verts
                    .iter()
                    .fold((DVec3::INFINITY, DVec3::NEG_INFINITY), |(a, b), &p| {
                        (a.min(p), b.max(p))
                    });
                Bounded(Aabb::new(
                    v3a(a) - Vec3A::splat(pad),
                    v3a(b) + Vec3A::splat(pad),
                ))
            })
            .collect();
        let bvh = obvhs::bvh2::builder::build_bvh2(
            &prims,
            obvhs::BvhBuildParams::medium_build(),
            &mut std::time::Duration::default(),
        );
        ShellBvh { bvh }
    }

    /// Every tetrahedron the ray `o + t d`, `t` in [0, `t_max`], passes through, with its
    /// exact span (entry clamped to 0), in order of entry (ties by index, so the order does not
    /// depend on the traversal). `out` is cleared first.
    pub fn spans(&self, shell: &Shell, o: DVec3, d: DVec3, t_max: f64, out: &mut Vec<(Span, u32)>) {
        out.clear();
        let ray = Ray::new(v3a(o), v3a(d), 0.0, t_max as f32);
        self.bvh.ray_traverse_anyhit(ray, |_, id| {
            let ti = self.bvh.primitive_indices[id];
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
        });
        out.sort_by(|a, b| a.0.t_in.total_cmp(&b.0.t_in).then(a.1.cmp(&b.1)));
    }
}
