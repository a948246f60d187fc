//! The CPU tape interpreter, generic over [`Real`]: `f64` for the exact scalar path (deep zoom,
//! reference), [`F32x8`] for eight points at once (throughput). Also the gradient (normal)
//! helper.

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
pub const NO_TRAP: f64 = 1e3;

/// Reusable interpreter state (the point and value stacks) for one thread.
pub struct Evaluator<S> {
    points: Vec<Point<S>>,
    values: Vec<Value<S>>,
}

impl<S: Real> Default for Evaluator<S> {
    fn default() -> Self {
        Self::new()
    }
}

impl<S: Real> Evaluator<S> {
    pub fn new() -> Self {
        Evaluator {
            points: Vec::with_capacity(crate::limits::MAX_POINT_STACK),
            values: Vec::with_capacity(crate::limits::MAX_VALUE_STACK),
        }
    }

    /// Runs the tape at `p` (world coordinates).
    #[inline]
    pub fn eval(&mut self, tape: &Tape, p: V3<S>) -> Value<S> {
        let instrs = tape.instrs();
        let params = tape.params();
        self.points.clear();
        self.values.clear();
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
                    control::PUSH_POINT => self.points.push(cur),
                    control::POP_POINT => {
                        cur = self.points.pop().expect("tape: point stack underflow")
                    }
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
                    self.values
                        .push(Value::solid(d * cur.k, S::splat(ins.arg as f64), cur.trap));
                }
                family::FRACTAL => {
                    let (d, trap) = Fractal::ALL[i].estimate(cur.p, a);
                    self.values.push(Value::solid(
                        d * cur.k,
                        S::splat(ins.arg as f64),
                        trap.min(cur.trap),
                    ));
                }
                family::TRANSFORM => Transform::ALL[i].apply(&mut cur.p, &mut cur.k, a),
                family::MODIFIER => {
                    let v = self.values.last_mut().expect("tape: value stack underflow");
                    v.d = Modifier::ALL[i].modify(v.d, cur.k, a);
                }
                family::COMBINE => {
                    let b = self.values.pop().expect("tape: value stack underflow");
                    let va = self.values.pop().expect("tape: value stack underflow");
                    self.values.push(Combine::ALL[i].combine(va, b, a));
                }
                f => unreachable!("tape: bad opcode family {f}"),
            }
        }
        self.values.pop().expect("tape: no result")
    }

    /// Distance only.
    #[inline]
    pub fn distance(&mut self, tape: &Tape, p: V3<S>) -> S {
        self.eval(tape, p).d
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
