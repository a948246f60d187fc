//! A direct recursive evaluation of the scene tree, independent of the tape compiler and
//! interpreter. It defines what the tape must compute; property tests compare the two.

use crate::eval::{NO_TRAP, Point};
use crate::registry::Family;
use crate::scene::{DomainOp, Node, Scene, Shape};
use crate::value::Value;
use crate::vec3::V3;

/// Evaluates `scene` at `p` by walking the tree (f64).
pub fn eval_tree(scene: &Scene, p: [f64; 3]) -> Value<f64> {
    let mut pt = Point {
        p: V3::new(p[0], p[1], p[2]),
        k: 1.0,
        trap: NO_TRAP,
    };
    if let Some(ifs) = &scene.ifs {
        for _ in 0..ifs.iterations {
            for t in &ifs.ops {
                t.kind
                    .apply(&mut pt.p, &mut pt.k, &baked(t.kind.def(), &t.params));
            }
            pt.trap = pt.trap.min(pt.p.length());
        }
    }
    let mut next_id = 0;
    eval_node(&scene.root, pt, &mut next_id)
}

fn baked(def: &crate::registry::Def, user: &[f64]) -> Vec<f64> {
    let mut out = Vec::new();
    def.bake_into(user, &mut out);
    out
}

fn eval_node(n: &Node, mut pt: Point<f64>, next_id: &mut u32) -> Value<f64> {
    let id = *next_id as f64;
    *next_id += 1;
    for op in &n.ops {
        if let DomainOp::Transform(t) = op.kind {
            t.apply(&mut pt.p, &mut pt.k, &baked(op.kind.def(), &op.params));
        }
    }
    let a = baked(n.shape.kind.def(), &n.shape.params);
    let mut v = match n.shape.kind {
        Shape::Primitive(prim) => Value::solid(prim.distance(pt.p, &a) * pt.k, id, pt.trap),
        Shape::Fractal(f) => {
            let (d, trap) = f.estimate(pt.p, &a);
            Value::solid(d * pt.k, id, trap.min(pt.trap))
        }
    };
    for c in &n.children {
        let cv = eval_node(c, pt, next_id);
        v = c
            .combine
            .kind
            .combine(v, cv, pt.k, &baked(c.combine.kind.def(), &c.combine.params));
    }
    for op in &n.ops {
        if let DomainOp::Modifier(m) = op.kind {
            v.d = m.modify(v.d, pt.k, &baked(op.kind.def(), &op.params));
        }
    }
    v
}
