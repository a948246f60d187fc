//! Sphere tracing of one ray through the scene's distance field on the tape's exact f64
//! path, with the conventions of fathom-trace's tracer:
//!
//! - over-relaxed steps (factor `fathom_core::shared::OMEGA`) with Keinert et al.'s fallback
//!   when consecutive unbounding spheres do not overlap ("Enhanced Sphere Tracing", 2014);
//! - a hit threshold that grows with the distance travelled, `eps(t) = eps0 + slope t`: the
//!   pixel's footprint (half the pixel angle times `pixel_epsilon`), so detail below a pixel
//!   is not chased. Secondary rays start with `eps0` = the footprint where they leave;
//! - a ray that runs out of steps short of `t_max` counts as a hit (it is stuck against the
//!   surface), one whose distance is not finite or that passes `t_max` as a miss.
//!
//! Inside a transmissive object the ray marches on the negated field (the distance to the
//! way out). Fractal estimates are tiny inside their sets, so such rays mostly run out of
//! steps there; primitives and CSG have exact interiors.
//!
//! Normals are the normalised central-difference gradient (six evaluations at +-h along the
//! axes), with h the hit epsilon, as fathom-trace offsets its gradient by the footprint.

use fathom_core::shared::OMEGA;
use fathom_core::{Evaluator, Tape, V3};
use glam::DVec3;

/// How rays march.
#[derive(Clone, Copy, Debug)]
pub struct MarchParams {
    /// Step limit per ray.
    pub max_steps: u32,
    /// Rays stop (miss) beyond this distance.
    pub t_max: f64,
    /// Hit threshold per unit of distance travelled.
    pub eps_slope: f64,
}

/// The outcome of one march.
#[derive(Clone, Copy, Debug)]
pub struct MarchHit {
    /// Distance along the ray.
    pub t: f64,
    /// Whether a surface was found.
    pub hit: bool,
    /// Distance evaluations spent.
    pub steps: u32,
    /// The hit threshold at `t`.
    pub eps: f64,
}

/// The field at `p` as a [`DVec3`] call.
#[inline]
pub fn distance(ev: &mut Evaluator<f64>, tape: &Tape, p: DVec3) -> f64 {
    ev.distance(tape, V3::new(p.x, p.y, p.z))
}

/// A ray to march.
#[derive(Clone, Copy, Debug)]
pub struct Ray {
    /// Origin.
    pub o: DVec3,
    /// Unit direction.
    pub d: DVec3,
    /// Farthest distance of interest (capped by [`MarchParams::t_max`]).
    pub t_max: f64,
    /// Hit threshold at the origin.
    pub eps0: f64,
    /// March the negated field (inside a transmissive object).
    pub inside: bool,
}

/// Marches `ray`.
pub fn march(ev: &mut Evaluator<f64>, tape: &Tape, ray: &Ray, p: &MarchParams) -> MarchHit {
    let Ray {
        o,
        d,
        t_max,
        eps0,
        inside,
    } = *ray;
    let sign = if inside { -1.0 } else { 1.0 };
    let mut t = 0.0;
    let mut omega = OMEGA;
    let mut prev_d = 0.0f64;
    let mut prev_step = 0.0f64;
    let t_max = t_max.min(p.t_max);
    let mut steps = 0;
    while steps < p.max_steps {
        let dist = sign * distance(ev, tape, o + d * t);
        steps += 1;
        if !dist.is_finite() {
            return MarchHit {
                t,
                hit: false,
                steps,
                eps: eps0 + p.eps_slope * t,
            };
        }
        let fail = omega > 1.0 && (dist.abs() + prev_d < prev_step || dist < 0.0);
        let eps = eps0 + p.eps_slope * t;
        if !fail && dist < eps {
            return MarchHit {
                t,
                hit: true,
                steps,
                eps,
            };
        }
        if fail {
            // Back to the last point known to be safe, without over-relaxation.
            t = t - prev_step + prev_d;
            prev_step = prev_d;
            omega = 1.0;
        } else {
            let step = dist * omega;
            t += step;
            prev_step = step;
            prev_d = dist;
        }
        if t >= t_max {
            return MarchHit {
                t: t_max,
                hit: false,
                steps,
                eps,
            };
        }
    }
    MarchHit {
        t,
        hit: true,
        steps,
        eps: eps0 + p.eps_slope * t,
    }
}

/// Outward unit normal at `p` by central differences with offset `h`.
pub fn normal(ev: &mut Evaluator<f64>, tape: &Tape, p: DVec3, h: f64) -> DVec3 {
    let mut g = DVec3::ZERO;
    for (i, e) in [DVec3::X, DVec3::Y, DVec3::Z].into_iter().enumerate() {
        let a = distance(ev, tape, p + e * h);
        let b = distance(ev, tape, p - e * h);
        g[i] = a - b;
    }
    let n = g.normalize_or_zero();
    if n == DVec3::ZERO { DVec3::Y } else { n }
}

#[cfg(test)]
mod tests {
    use super::*;
    use fathom_core::primitives::Primitive;
    use fathom_core::{Node, Scene};

    fn params() -> MarchParams {
        MarchParams {
            max_steps: 256,
            t_max: 100.0,
            eps_slope: 1e-4,
        }
    }

    #[test]
    fn rays_stop_just_outside_a_sphere_and_inside_rays_find_the_way_out() {
        let tape = Tape::compile(&Scene::new(Node::new(Primitive::Sphere))).unwrap();
        let mut ev = Evaluator::new();
        let o = DVec3::new(0.2, 0.1, 3.0);
        let d = (DVec3::new(0.0, 0.0, 0.0) - o).normalize();
        let m = march(
            &mut ev,
            &tape,
            &Ray {
                o,
                d,
                t_max: 100.0,
                eps0: 0.0,
                inside: false,
            },
            &params(),
        );
        let r = (o + d * m.t).length() - 1.0;
        assert!(m.hit && r >= -1e-9 && r <= m.eps, "{m:?} r {r}");
        let n = normal(&mut ev, &tape, o + d * m.t, m.eps);
        assert!((n - (o + d * m.t).normalize()).length() < 1e-6);
        // From just inside the surface, marching the negated field reaches the far side.
        let p = o + d * m.t + d * 2.0 * m.eps;
        let inner = march(
            &mut ev,
            &tape,
            &Ray {
                o: p,
                d,
                t_max: 100.0,
                eps0: m.eps,
                inside: true,
            },
            &params(),
        );
        let q = p + d * inner.t;
        assert!(
            inner.hit && (q.length() - 1.0).abs() <= 2.0 * inner.eps,
            "{inner:?}"
        );
        assert!(q.z < 0.0);
        // Misses leave at t_max.
        let miss = march(
            &mut ev,
            &tape,
            &Ray {
                o,
                d: DVec3::Z,
                t_max: 100.0,
                eps0: 0.0,
                inside: false,
            },
            &params(),
        );
        assert!(!miss.hit);
    }
}
