//! Marching one ray through the shell (the CPU path; `gpu/micro.wgsl` mirrors it constant for
//! constant).
//!
//! Inside a tetrahedron the world-to-shell map is affine, so the ray's shell coordinates are
//! linear in `t`. The ray's span in the tetrahedron is cut where u or v cross a whole number
//! (a tile wall); each piece is sphere traced in its tile with steps of
//! `texture distance / L`, `L` the prism's Lipschitz factor, a safe world-space bound. A piece
//! that ends without a hit hands the ray to the next piece, then to the next tetrahedron along
//! the ray, never past the shell's surface: detail outside the shell cannot be drawn.
//!
//! Shading normals: the texture's gradient, mapped to the world by the transpose Jacobian
//! (the true normal of the warped detail), then rotated by the rotation taking the
//! tetrahedron's height gradient to the interpolated vertex normal (the seed's fix, which
//! removes the facets of the base mesh: a flat texture layer gets exactly the smooth normal).

use crate::shell::Shell;
use crate::tet::{Span, Tet};
use crate::texture::Texture;
use fathom_core::Evaluator;
use glam::DVec3;

/// Half a hundred-thousandth of a tile: how far past a tile wall a piece starts.
pub const TILE_EPS: f64 = 1e-4;

/// Marching limits and the hit threshold.
#[derive(Clone, Copy, Debug)]
pub struct MarchParams {
    /// Distance evaluations per ray (all tetrahedra together).
    pub max_steps: u32,
    /// Hit threshold per unit of ray distance (half the pixel footprint times the quality).
    pub eps_slope: f64,
    /// Hit threshold floor (world units).
    pub eps_min: f64,
}

/// What a ray hit.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum HitKind {
    /// The texture, in tile (`cu`, `cv`).
    Texture {
        /// The hit's position across the tile, along u.
        cu: f64,
        /// The hit's position across the tile, along v.
        cv: f64,
    },
    /// The base mesh (the prism's bottom face).
    Base,
}

/// A hit: distance, tetrahedron, kind.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hit {
    /// Distance along the ray.
    pub t: f64,
    /// The tetrahedron the hit is in.
    pub tet: u32,
    /// Texture or base mesh.
    pub kind: HitKind,
}

/// Marches `[t0, t1]` of the ray inside `tet`. Returns (t, cu, cv) of a hit.
#[allow(clippy::too_many_arguments)]
pub fn march_span(
    tex: &Texture,
    shell: &Shell,
    ev: &mut Evaluator<f64>,
    tet: &Tet,
    o: DVec3,
    d: DVec3,
    t0: f64,
    t1: f64,
    p: &MarchParams,
    steps: &mut u32,
) -> Option<(f64, f64, f64)> {
    if t1.partial_cmp(&t0) != Some(std::cmp::Ordering::Greater) {
        return None;
    }
    let s0 = tet.shell_at(&tet.bary(o + d * t0));
    let ds = (tet.shell_at(&tet.bary(o + d * t1)) - s0) / (t1 - t0);
    let l = tet.lipschitz.max(1e-300);
    let tiling = &shell.tiling;
    let mut t = t0;
    while t < t1 {
        let s = s0 + ds * (t - t0);
        let cu = (s.x + TILE_EPS * ds.x.signum() * (ds.x != 0.0) as u8 as f64).floor();
        let cv = (s.z + TILE_EPS * ds.z.signum() * (ds.z != 0.0) as u8 as f64).floor();
        let mut end = t1;
        if ds.x > 0.0 {
            end = end.min(t0 + (cu + 1.0 - s0.x) / ds.x);
        } else if ds.x < 0.0 {
            end = end.min(t0 + (cu - s0.x) / ds.x);
        }
        if ds.z > 0.0 {
            end = end.min(t0 + (cv + 1.0 - s0.z) / ds.z);
        } else if ds.z < 0.0 {
            end = end.min(t0 + (cv - s0.z) / ds.z);
        }
        if end <= t {
            end = t1.min(t + 1e-6 * (t1 - t0));
        }
        loop {
            let q = tiling.scene_point(s0 + ds * (t - t0), cu, cv);
            let dist = tex.distance(ev, q) / l;
            *steps += 1;
            if dist < p.eps_slope * t + p.eps_min || *steps >= p.max_steps {
                return Some((t, cu, cv));
            }
            t += dist;
            if t >= end {
                break;
            }
        }
        t = end;
    }
    None
}

/// Scratch space of one thread.
#[derive(Default)]
pub struct Scratch {
    /// The texture's evaluator.
    pub ev: Evaluator<f64>,
    /// The ray's spans through the shell, each with its tetrahedron.
    pub spans: Vec<(Span, u32)>,
}

/// The outcome of one ray.
#[derive(Clone, Copy, Debug, Default)]
pub struct RayResult {
    /// What the ray hit, if anything.
    pub hit: Option<Hit>,
    /// Texture distance evaluations.
    pub steps: u32,
    /// Tetrahedra whose spans were marched.
    pub tets_visited: u32,
}

/// Traces one ray through the shell: the tetrahedra it crosses in order of entry, each
/// marched until a hit; a tetrahedron entered after the best hit so far is not visited (it
/// cannot be nearer), which also makes overlapping shells (a spout through a body) come out as
/// the rasteriser's depth test would.
#[allow(clippy::too_many_arguments)]
pub fn trace(
    shell: &Shell,
    bvh: &crate::bvh::ShellBvh,
    tex: &Texture,
    show_base: bool,
    s: &mut Scratch,
    o: DVec3,
    d: DVec3,
    t_max: f64,
    p: &MarchParams,
) -> RayResult {
    bvh.spans(shell, o, d, t_max, &mut s.spans);
    let mut r = RayResult::default();
    let mut best = t_max;
    for &(span, ti) in &s.spans {
        if span.t_in >= best {
            break;
        }
        r.tets_visited += 1;
        let tet = &shell.tets[ti as usize];
        if show_base && span.face_in == tet.bottom_face {
            best = span.t_in;
            r.hit = Some(Hit {
                t: span.t_in,
                tet: ti,
                kind: HitKind::Base,
            });
            continue;
        }
        let end = span.t_out.min(best);
        if let Some((t, cu, cv)) = march_span(
            tex,
            shell,
            &mut s.ev,
            tet,
            o,
            d,
            span.t_in,
            end,
            p,
            &mut r.steps,
        ) {
            best = t;
            r.hit = Some(Hit {
                t,
                tet: ti,
                kind: HitKind::Texture { cu, cv },
            });
        } else if show_base && span.face_out == tet.bottom_face && span.t_out < best {
            best = span.t_out;
            r.hit = Some(Hit {
                t: span.t_out,
                tet: ti,
                kind: HitKind::Base,
            });
        }
        if r.steps >= p.max_steps {
            break;
        }
    }
    r
}

/// The rotation taking unit `a` to unit `b` (Rodrigues), applied to `x`; identity when they
/// are opposite or degenerate.
pub fn rotate_between(a: DVec3, b: DVec3, x: DVec3) -> DVec3 {
    let v = a.cross(b);
    let c = a.dot(b);
    if c <= -0.999_999 || !c.is_finite() {
        return x;
    }
    x * c + v.cross(x) + v * (v.dot(x) / (1.0 + c))
}

/// The shading normal and material id at a hit (and the evaluations spent).
#[allow(clippy::too_many_arguments)]
pub fn surface(
    shell: &Shell,
    tex: &Texture,
    ev: &mut Evaluator<f64>,
    hit: &Hit,
    o: DVec3,
    d: DVec3,
    footprint: f64,
    rotate: bool,
) -> (DVec3, u32, u32) {
    let tet = &shell.tets[hit.tet as usize];
    let p = o + d * hit.t;
    let b = tet.bary(p);
    let n_i = tet.vertex_normal_at(&b);
    match hit.kind {
        HitKind::Base => (n_i, u32::MAX, 0),
        HitKind::Texture { cu, cv } => {
            let q = shell.tiling.scene_point(tet.shell_at(&b), cu, cv);
            let h = 0.5 * footprint * tet.lipschitz;
            let n_s = tex.normal(ev, q, h.max(1e-9));
            let id = tex.material_id(ev, q);
            let jt = tet.jac.transpose();
            let n_g = (jt * n_s).normalize_or(n_i);
            let n = if rotate {
                let n_h = (jt * DVec3::Y).normalize_or(n_i);
                rotate_between(n_h, n_i, n_g).normalize_or(n_i)
            } else {
                n_g
            };
            (n, id, 5)
        }
    }
}
