//! The CPU tape interpreter, generic over [`Real`]: `f64` for the exact scalar path (deep zoom,
//! reference), [`F32x8`] for eight points at once (throughput), [`crate::dd::Dd`] (double-double)
//! past f64 precision. Also the gradient (normal) helper.

use crate::combine::Combine;
use crate::fractals::Fractal;
use crate::modifiers::Modifier;
use crate::primitives::Primitive;
use crate::real::{F32x8, Real};
use crate::tape::{Tape, control, family};
use crate::transforms::Transform;
use crate::value::Value;
use crate::vec3::V3;

/// The evaluation point with its distance scale and orbit trap.
#[derive(Clone, Copy, Debug)]
pub struct Point<S> {
    /// Position in the current (transformed) frame.
    pub p: V3<S>,
    /// Multiplies a distance measured in this frame to give world units.
    pub k: S,
    /// Smallest `|p|` seen at the end of an IFS loop iteration (or `NO_TRAP`).
    pub trap: S,
}

/// Orbit-trap value of a point no loop has touched.
pub use crate::shared::NO_TRAP;

/// What the value stack holds: the whole [`Value`] (materials, trap) or only the distance.
///
/// Keeping only the distance lets the optimiser drop the material bookkeeping of combines,
/// which the sphere tracer's marching loop never reads.
pub trait Slot<S: Real>: Copy {
    /// The slot for a value.
    fn from_value(v: Value<S>) -> Self;
    /// The value in the slot (a distance-only slot fills the rest with zeros).
    fn to_value(self) -> Value<S>;
    /// The distance, to change in place.
    fn d_mut(&mut self) -> &mut S;
}

impl<S: Real> Slot<S> for Value<S> {
    #[inline(always)]
    fn from_value(v: Value<S>) -> Self {
        v
    }
    #[inline(always)]
    fn to_value(self) -> Value<S> {
        self
    }
    #[inline(always)]
    fn d_mut(&mut self) -> &mut S {
        &mut self.d
    }
}

/// Distance-only slot.
#[derive(Clone, Copy, Debug)]
pub struct Dist<S>(pub S);

impl<S: Real> Slot<S> for Dist<S> {
    #[inline(always)]
    fn from_value(v: Value<S>) -> Self {
        Dist(v.d)
    }
    #[inline(always)]
    fn to_value(self) -> Value<S> {
        Value::solid(self.0, S::zero(), S::zero())
    }
    #[inline(always)]
    fn d_mut(&mut self) -> &mut S {
        &mut self.0
    }
}

/// Reusable interpreter state (the point and value stacks) for one thread.
pub struct Evaluator<S> {
    points: Vec<Point<S>>,
    values: Vec<Value<S>>,
    dists: Vec<Dist<S>>,
}

impl<S: Real> Default for Evaluator<S> {
    fn default() -> Self {
        Self::new()
    }
}

impl<S: Real> Evaluator<S> {
    /// An evaluator with its stacks allocated to the limits.
    pub fn new() -> Self {
        Evaluator {
            points: Vec::with_capacity(crate::limits::MAX_POINT_STACK),
            values: Vec::with_capacity(crate::limits::MAX_VALUE_STACK),
            dists: Vec::with_capacity(crate::limits::MAX_VALUE_STACK),
        }
    }

    /// Runs the tape at `p` (world coordinates): distance, materials and orbit trap.
    #[inline]
    pub fn eval(&mut self, tape: &Tape, p: V3<S>) -> Value<S> {
        let mut values = std::mem::take(&mut self.values);
        let v = run(tape, p, &mut self.points, &mut values);
        self.values = values;
        v
    }

    /// Distance only (the material bookkeeping is optimised away).
    #[inline]
    pub fn distance(&mut self, tape: &Tape, p: V3<S>) -> S {
        let mut dists = std::mem::take(&mut self.dists);
        let v = run(tape, p, &mut self.points, &mut dists);
        self.dists = dists;
        v.0
    }

    /// Outward unit normal by the tetrahedron technique (four evaluations at offsets `h`).
    pub fn normal(&mut self, tape: &Tape, p: V3<S>, h: S) -> V3<S> {
        let k = [
            V3::c(1.0, -1.0, -1.0),
            V3::c(-1.0, -1.0, 1.0),
            V3::c(-1.0, 1.0, -1.0),
            V3::c(1.0, 1.0, 1.0),
        ];
        let mut n = V3::zero();
        for e in k {
            n += e * self.distance(tape, p + e * h);
        }
        let len = n.length().max(S::splat(1e-30));
        n / len
    }
}

impl Tape {
    /// Evaluates one point on the exact f64 path (allocates an evaluator; use [`Evaluator`] in
    /// loops).
    pub fn eval_f64(&self, p: [f64; 3]) -> Value<f64> {
        Evaluator::<f64>::new().eval(self, V3::new(p[0], p[1], p[2]))
    }

    /// Evaluates one point in double-double (~1e-32 relative; see [`crate::dd`] for which
    /// functions are only f64-accurate). Allocates an evaluator; use [`Evaluator`] in loops.
    pub fn eval_dd(&self, p: V3<crate::dd::Dd>) -> Value<crate::dd::Dd> {
        Evaluator::<crate::dd::Dd>::new().eval(self, p)
    }

    /// Evaluates eight points on the f32 packet path.
    pub fn eval_x8(&self, p: &[[f64; 3]; 8]) -> Value<F32x8> {
        let xs: Vec<f64> = p.iter().map(|q| q[0]).collect();
        let ys: Vec<f64> = p.iter().map(|q| q[1]).collect();
        let zs: Vec<f64> = p.iter().map(|q| q[2]).collect();
        Evaluator::<F32x8>::new().eval(
            self,
            V3::new(
                F32x8::from_lanes(&xs),
                F32x8::from_lanes(&ys),
                F32x8::from_lanes(&zs),
            ),
        )
    }
}

/// The interpreter loop, generic over what the value stack keeps.
#[inline(always)]
fn run<S: Real, T: Slot<S>>(
    tape: &Tape,
    p: V3<S>,
    points: &mut Vec<Point<S>>,
    values: &mut Vec<T>,
) -> T {
    let instrs = tape.instrs();
    let params = tape.params();
    points.clear();
    values.clear();
    let mut cur = Point {
        p,
        k: S::one(),
        trap: S::splat(NO_TRAP),
    };
    let mut loops: [(u32, usize); 4] = [(0, 0); 4];
    let mut depth = 0usize;
    let mut pc = 0usize;
    loop {
        let ins = instrs[pc];
        pc += 1;
        let a = &params[ins.param as usize..];
        let i = ins.index();
        match ins.family() {
            family::CONTROL => match i as u32 {
                control::END => break,
                control::PUSH_POINT => points.push(cur),
                control::POP_POINT => cur = points.pop().expect("tape: point stack underflow"),
                control::LOOP_BEGIN => {
                    let n = a[0] as u32;
                    if n == 0 {
                        pc = ins.arg as usize;
                    } else {
                        loops[depth] = (n, pc);
                        depth += 1;
                    }
                }
                control::LOOP_END => {
                    cur.trap = cur.trap.min(cur.p.length());
                    let l = &mut loops[depth - 1];
                    l.0 -= 1;
                    if l.0 > 0 {
                        pc = ins.arg as usize;
                    } else {
                        depth -= 1;
                    }
                }
                _ => unreachable!("tape: bad control op {i}"),
            },
            family::PRIMITIVE => {
                let d = Primitive::ALL[i].distance(cur.p, a);
                values.push(T::from_value(Value::solid(
                    d * cur.k,
                    S::splat(ins.arg as f64),
                    cur.trap,
                )));
            }
            family::FRACTAL => {
                let (d, trap) = Fractal::ALL[i].estimate(cur.p, a);
                values.push(T::from_value(Value::solid(
                    d * cur.k,
                    S::splat(ins.arg as f64),
                    trap.min(cur.trap),
                )));
            }
            family::TRANSFORM => Transform::ALL[i].apply(&mut cur.p, &mut cur.k, a),
            family::MODIFIER => {
                let v = values.last_mut().expect("tape: value stack underflow");
                let d = *v.d_mut();
                *v.d_mut() = Modifier::ALL[i].modify(d, cur.k, a);
            }
            family::COMBINE => {
                let b = values.pop().expect("tape: value stack underflow");
                let va = values.pop().expect("tape: value stack underflow");
                values.push(T::from_value(Combine::ALL[i].combine(
                    va.to_value(),
                    b.to_value(),
                    cur.k,
                    a,
                )));
            }
            f => unreachable!("tape: bad opcode family {f}"),
        }
    }
    values.pop().expect("tape: no result")
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::presets::{PRESETS, load};

    fn points(n: usize, half: f64) -> Vec<[f64; 3]> {
        let mut s = 0x2545_f491_4f6c_dd1du64;
        let mut next = move || {
            s ^= s << 13;
            s ^= s >> 7;
            s ^= s << 17;
            ((s >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0) * half
        };
        (0..n).map(|_| [next(), next(), next()]).collect()
    }

    #[test]
    fn distance_only_matches_full_evaluation() {
        for p in PRESETS {
            let tape = Tape::compile(&load(p.name).unwrap()).unwrap();
            let mut e = Evaluator::<f64>::new();
            for q in points(200, 2.0) {
                let v = V3::new(q[0], q[1], q[2]);
                assert_eq!(
                    e.distance(&tape, v),
                    e.eval(&tape, v).d,
                    "{} at {q:?}",
                    p.name
                );
            }
        }
    }

    #[test]
    fn packet_path_agrees_with_f64_path_on_presets() {
        for p in PRESETS {
            let tape = Tape::compile(&load(p.name).unwrap()).unwrap();
            for chunk in points(512, 2.0).chunks_exact(8) {
                let chunk: &[[f64; 3]; 8] = chunk.try_into().unwrap();
                let x = tape.eval_x8(chunk);
                for (lane, q) in chunk.iter().enumerate() {
                    let want = tape.eval_f64(*q);
                    let got = x.d.lane(lane);
                    // f32 inputs and transcendental approximations: relative 1e-3 plus an absolute
                    // floor for distances near zero.
                    let tol = 1e-3 * want.d.abs() + 2e-4;
                    assert!(
                        (got - want.d).abs() <= tol,
                        "{} at {q:?}: f64 {} f32 {got}",
                        p.name,
                        want.d
                    );
                    assert_eq!(x.id.lane(lane), want.id, "{} material id at {q:?}", p.name);
                }
            }
        }
    }

    #[test]
    fn normals_of_a_sphere_point_outward() {
        let tape = Tape::compile(&crate::Scene::new(crate::Node::new(
            crate::primitives::Primitive::Sphere,
        )))
        .unwrap();
        let mut e = Evaluator::<f64>::new();
        for q in points(50, 3.0) {
            let p = V3::new(q[0], q[1], q[2]);
            if p.length() < 0.1 {
                continue;
            }
            let n = e.normal(&tape, p, 1e-5);
            let want = p.normalize();
            // The tetrahedron stencil is first-order accurate on curved surfaces: error O(h / r).
            assert!((n - want).length() < 10.0 * 1e-5, "{q:?}: {n:?}");
        }
    }
}
