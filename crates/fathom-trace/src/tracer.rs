//! Sphere tracing of a packet of rays (eight f32 lanes, or one f64 lane on the deep-zoom path).
//!
//! Every lane marches its own ray; a lane that has hit or left the scene is parked (its state no
//! longer changes) while the others go on, so one evaluation of the tape advances all live rays.
//!
//! Two step rules:
//! - **basic** (Hart 1996): step by the distance bound `d`;
//! - **enhanced** (Keinert et al. 2014, "Enhanced Sphere Tracing"): over-relax, stepping
//!   `omega * d`; if the unbounding sphere at the new point does not overlap the previous one
//!   (`|d| + d_prev < step`), the step may have skipped a surface, so the lane goes back to the
//!   safe point `t_prev + d_prev` and continues with `omega = 1`. Landing inside the surface
//!   (`d < 0`) after an over-relaxed step counts as a failure too.
//!
//! The same loop marches cones for the prepass: with a cone slope `c`, a lane steps by
//! `d - c t - c0` (`c0`: the cone's radius at the start, when its rays leave from different
//! points), which keeps every ray inside the cone outside the surface (triangle inequality).
//!
//! The hit test uses a pixel-footprint epsilon that grows with distance: a lane hits when
//! `d - c t < eps_slope * t + eps_min`.

use fathom_core::real::{Mask, Real};
use fathom_core::{Evaluator, Tape, V3};

/// Which step rule the primary rays use.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Method {
    /// Step by the distance bound.
    Basic,
    /// Over-relaxed steps with the safe fallback of Keinert et al.
    Enhanced,
}

/// Over-relaxation factor of the enhanced tracer (shared with the WGSL tracer).
pub use fathom_core::shared::OMEGA;

/// How one march behaves.
#[derive(Clone, Copy, Debug)]
pub struct MarchParams {
    /// Rays stop (miss) beyond this distance.
    pub t_max: f64,
    /// Step limit; lanes still marching when it runs out count as hits.
    pub max_steps: u32,
    /// Hit threshold per unit of distance (the pixel footprint times the quality knob).
    pub eps_slope: f64,
    /// Hit threshold floor, in world units.
    pub eps_min: f64,
    /// Radius of the cone per unit of distance (0 for a ray).
    pub cone_slope: f64,
    /// Radius of the cone at distance 0 (the spread of its rays' origins; 0 for a ray).
    pub cone_base: f64,
    /// Over-relaxation factor (1 for basic sphere tracing).
    pub omega: f64,
}

/// The outcome of marching a packet.
#[derive(Clone, Copy, Debug)]
pub struct March<S: Real> {
    /// Distance reached along each ray.
    pub t: S,
    /// Lanes that found a surface (or ran out of steps short of `t_max`).
    pub hit: S::Mask,
    /// Distance evaluations spent per lane.
    pub steps: S,
}

/// Marches a packet of rays from `origin` along unit directions `dir`, starting at `t0`.
/// Lanes with `live` unset are not marched (they report a miss at `t0` with no steps).
#[inline]
pub fn march<S: Real>(
    ev: &mut Evaluator<S>,
    tape: &Tape,
    origin: V3<S>,
    dir: V3<S>,
    t0: S,
    live: S::Mask,
    p: &MarchParams,
) -> March<S> {
    let t_max = S::splat(p.t_max);
    let one = S::one();
    let zero = S::zero();
    let eps_slope = S::splat(p.eps_slope);
    let eps_min = S::splat(p.eps_min);
    let cone = S::splat(p.cone_slope);
    let cone0 = S::splat(p.cone_base);
    let mut t = t0;
    let mut active = live & t.lt(t_max);
    let mut hit = zero.lt(zero);
    let mut steps = zero;
    let mut omega = S::splat(p.omega);
    let mut prev_d = zero;
    let mut prev_step = zero;
    for _ in 0..p.max_steps {
        if !active.any() {
            break;
        }
        let d = ev.distance(tape, origin + dir * t);
        steps += S::select(active, one, zero);
        // Keinert's overlap test, only meaningful after an over-relaxed step; landing inside
        // (d < 0) after such a step also means it overshot.
        let fail = omega.gt(one) & ((d.abs() + prev_d).lt(prev_step) | d.lt(zero));
        let free = d - cone * t - cone0;
        let new_hit = active & !fail & free.lt(eps_slope * t + eps_min);
        hit = hit | new_hit;
        active = active & !new_hit;
        let step = free * omega;
        let t_back = t - prev_step + prev_d;
        let t_next = S::select(fail, t_back, t + step);
        prev_step = S::select(fail, prev_d, step);
        // After a failure the lane sits at t_prev + d_prev; the radius it came from is d_prev.
        prev_d = S::select(fail, prev_d, d);
        omega = S::select(fail, one, omega);
        t = S::select(active, t_next, t);
        // A ray that stops making progress (d not finite) or leaves the scene is a miss.
        let gone = t.ge(t_max) | !d.is_finite();
        active = active & !gone;
    }
    // Lanes still marching when the step budget ran out are stuck against the surface.
    hit = hit | active;
    March { t, hit, steps }
}

#[cfg(test)]
mod tests {
    use super::*;
    use fathom_core::primitives::Primitive;
    use fathom_core::{F32x8, Node, Scene};

    fn sphere_tape() -> Tape {
        Tape::compile(&Scene::new(Node::new(Primitive::Sphere))).unwrap()
    }

    fn params(omega: f64) -> MarchParams {
        MarchParams {
            t_max: 100.0,
            max_steps: 256,
            eps_slope: 1e-4,
            eps_min: 0.0,
            cone_slope: 0.0,
            cone_base: 0.0,
            omega,
        }
    }

    #[test]
    fn rays_hit_a_unit_sphere_at_the_analytic_distance() {
        let tape = sphere_tape();
        let mut ev = Evaluator::<F32x8>::new();
        // Eight rays from z = 3 towards the sphere, spread in x; the last four miss.
        let xs = [0.0, 0.1, 0.3, 0.6, 1.05, 1.5, 2.0, 3.0];
        let dirs: Vec<[f64; 3]> = xs
            .iter()
            .map(|&x| {
                let v = glam::DVec3::new(x, 0.0, -3.0).normalize();
                [v.x, v.y, v.z]
            })
            .collect();
        let dir = V3::new(
            F32x8::from_lanes(&dirs.iter().map(|d| d[0]).collect::<Vec<_>>()),
            F32x8::from_lanes(&dirs.iter().map(|d| d[1]).collect::<Vec<_>>()),
            F32x8::from_lanes(&dirs.iter().map(|d| d[2]).collect::<Vec<_>>()),
        );
        let origin = V3::c(0.0, 0.0, 3.0);
        for omega in [1.0, OMEGA] {
            let all = F32x8::zero().le(F32x8::zero());
            let m = march(
                &mut ev,
                &tape,
                origin,
                dir,
                F32x8::zero(),
                all,
                &params(omega),
            );
            let hits = m.hit.0.to_array();
            for (i, d) in dirs.iter().enumerate() {
                let o = glam::DVec3::new(0.0, 0.0, 3.0);
                let dv = glam::DVec3::from(*d);
                // |o + t d|^2 = 1
                let b = o.dot(dv);
                let disc = b * b - (o.length_squared() - 1.0);
                let want_hit = disc >= 0.0;
                assert_eq!(hits[i] != 0.0, want_hit, "lane {i} omega {omega}");
                if want_hit {
                    let t = -b - disc.sqrt();
                    let got = m.t.lane(i);
                    // Stopped in front of the surface, within the hit epsilon of it.
                    let r = (o + dv * got).length() - 1.0;
                    assert!(
                        got <= t + 1e-5 && r >= -1e-5 && r <= 1e-4 * got + 1e-5,
                        "lane {i} omega {omega}: t {got} want {t}, {r} off the surface"
                    );
                }
            }
        }
    }

    #[test]
    fn parked_lanes_do_not_move_and_cones_stop_early() {
        let tape = sphere_tape();
        let mut ev = Evaluator::<f64>::new();
        let o = V3::new(0.0, 0.0, 3.0);
        let d = V3::new(0.0, 0.0, -1.0);
        let m = march(&mut ev, &tape, o, d, 0.0, false, &params(1.0));
        assert!(!m.hit && m.t == 0.0 && m.steps == 0.0);
        let mut cone = params(1.0);
        cone.cone_slope = 0.1;
        // From t = 1 the ray sees the sphere 1 away; the cone (radius 0.1 there) only 0.9.
        let c = march(&mut ev, &tape, o, d, 1.0, true, &cone);
        let r = march(&mut ev, &tape, o, d, 1.0, true, &params(1.0));
        assert!(c.t < r.t - 0.05 && c.t > 1.5, "cone {} ray {}", c.t, r.t);
    }
}
