//! GPU-vs-CPU conformance of every registry entry: each primitive, fractal, domain operator,
//! distance modifier and combine operator is compiled into a small scene and evaluated at 10,000
//! random points (10 random parameter sets x 1,000 points) on the GPU and on the CPU's f64 path.
//!
//! Tolerance: `|gpu - cpu| <= 1e-4 * |cpu| + floor`. The relative term is the 1e-4; the
//! absolute floor (`FLOOR`, 2e-5 world units at point magnitudes up to ~3) covers values near
//! zero, where f32 cannot do better than the rounding of its inputs: a coordinate of 2.0 is
//! already rounded by 1.2e-7, and a distance that is a difference of two such lengths (a torus,
//! a box edge) loses relative precision as it approaches 0 however it is computed.
//! Fractals iterate a chaotic map: inside the set the orbit never escapes, and after 12
//! iterations f32 and f64 orbits have parted (at about 1 point in 1,000 the CPU's own f32 path
//! is off from f64 by more than 1e-4). There the GPU may differ from f64 by `CHAOS` times the
//! CPU's f32 error at that point on top of the tolerance (see `agrees`).

mod common;

use common::{Rng, renderer};
use fathom_core::combine::Combine;
use fathom_core::fractals::Fractal;
use fathom_core::modifiers::Modifier;
use fathom_core::primitives::Primitive;
use fathom_core::registry::{Def, Family, ParamKind};
use fathom_core::scene::{Call, Ifs, Node, Scene};
use fathom_core::transforms::Transform;
use fathom_core::{Evaluator, F32x8, Real, Tape, V3};

const POINTS_PER_SET: usize = 1000;
const SETS: usize = 10;
const REL: f64 = 1e-4;
/// The orbit trap only picks a palette colour (with the default palette a relative change of
/// 1e-3 in a trap near 1 moves a channel by at most about half an 8-bit step), so it is held
/// to 1e-3.
const TRAP_REL: f64 = 1e-3;
const FLOOR: f64 = 2e-5;
/// How many times the CPU's own f32 error a fractal point may be off on the GPU.
const CHAOS: f64 = 4.0;

/// A random parameter value near the default (the declared ranges reach 1e6, far outside any
/// useful shape), clamped to the declared range.
fn random_params(def: &Def, rng: &mut Rng, set: usize) -> Vec<f64> {
    let mut out = Vec::new();
    for p in def.params {
        for &d in p.default_values() {
            let v = if set == 0 {
                d
            } else {
                match p.kind {
                    ParamKind::Int => d,
                    _ if d == 0.0 => rng.range(-1.0, 1.0),
                    _ => d * rng.range(0.6, 1.4),
                }
            };
            let v = v.clamp(p.min, p.max);
            out.push(if p.kind == ParamKind::Int {
                v.round()
            } else {
                v
            });
        }
    }
    out
}

fn call<K: Family>(kind: K, params: Vec<f64>) -> Call<K> {
    Call { kind, params }
}

/// A box with unequal sides: sensitive to every rotation, fold and translation.
fn probe() -> Node {
    Node::new(call(
        fathom_core::scene::Shape::Primitive(Primitive::Box),
        vec![0.6, 0.4, 0.5],
    ))
}

struct Case {
    name: String,
    scene: Scene,
    box_half: f64,
    fractal: bool,
}

fn cases(rng: &mut Rng) -> Vec<Case> {
    let mut v = Vec::new();
    for set in 0..SETS {
        for &p in Primitive::ALL {
            let params = random_params(p.def(), rng, set);
            v.push(Case {
                name: format!("primitive {} {params:?}", p.def().name),
                scene: Scene::new(Node::new(call(
                    fathom_core::scene::Shape::Primitive(p),
                    params,
                ))),
                box_half: 2.0,
                fractal: false,
            });
        }
        for &f in Fractal::ALL {
            let params = random_params(f.def(), rng, set);
            v.push(Case {
                name: format!("fractal {} {params:?}", f.def().name),
                scene: Scene::new(Node::new(call(
                    fathom_core::scene::Shape::Fractal(f),
                    params,
                ))),
                box_half: 1.5,
                fractal: true,
            });
        }
        for &t in Transform::ALL {
            let params = random_params(t.def(), rng, set);
            let mut root = probe();
            root.ops.push(call(
                fathom_core::scene::DomainOp::Transform(t),
                params.clone(),
            ));
            v.push(Case {
                name: format!("domain operator {} {params:?}", t.def().name),
                scene: Scene::new(root),
                box_half: 2.0,
                fractal: false,
            });
            // The same operator inside a 3-iteration IFS loop (exercises the loop opcodes).
            let mut s = Scene::new(probe());
            s.ifs = Some(Ifs {
                iterations: 3,
                ops: vec![call(t, params.clone())],
            });
            v.push(Case {
                name: format!("IFS loop of {} {params:?}", t.def().name),
                scene: s,
                box_half: 2.0,
                fractal: false,
            });
        }
        for &m in Modifier::ALL {
            let params = random_params(m.def(), rng, set);
            let mut root = probe();
            // A scale first, so the modifier sees k != 1.
            root.ops.push(call(
                fathom_core::scene::DomainOp::Transform(Transform::Scale),
                vec![1.3],
            ));
            root.ops.push(call(
                fathom_core::scene::DomainOp::Modifier(m),
                params.clone(),
            ));
            v.push(Case {
                name: format!("distance modifier {} {params:?}", m.def().name),
                scene: Scene::new(root),
                box_half: 2.0,
                fractal: false,
            });
        }
        for &c in Combine::ALL {
            let params = random_params(c.def(), rng, set);
            let mut child = Node::new(call(
                fathom_core::scene::Shape::Primitive(Primitive::Sphere),
                vec![0.5],
            ));
            child.ops.push(call(
                fathom_core::scene::DomainOp::Transform(Transform::Translate),
                vec![0.5, 0.3, 0.1],
            ));
            child.combine = call(c, params.clone());
            v.push(Case {
                name: format!("combine operator {} {params:?}", c.def().name),
                scene: Scene::new(probe().child(child)),
                box_half: 2.0,
                fractal: false,
            });
        }
    }
    v
}

/// Whether a GPU result agrees with the CPU's f64 value: within `REL` and `FLOOR`, plus, for
/// fractals only, `CHAOS` times the CPU's own f32-vs-f64 difference at that point (the point's
/// measured sensitivity to f32 rounding; zero wherever the CPU's f32 path is exact).
fn agrees(gpu: f64, cpu64: f64, cpu32: f64, fractal: bool, rel: f64) -> bool {
    let chaos = if fractal {
        CHAOS * (cpu32 - cpu64).abs()
    } else {
        0.0
    };
    (gpu - cpu64).abs() <= rel * cpu64.abs() + FLOOR + chaos
}

#[test]
fn every_registry_entry_agrees_with_the_cpu_on_10000_points() {
    let mut r = renderer();
    let mut rng = Rng(0x5eed);
    let mut failures = Vec::new();
    let mut worst: std::collections::BTreeMap<String, f64> = Default::default();
    for case in cases(&mut rng) {
        let tape = Tape::compile(&case.scene).unwrap_or_else(|e| panic!("{}: {e}", case.name));
        r.set_tape(&tape).unwrap();
        let h = case.box_half;
        let pts: Vec<[f32; 3]> = (0..POINTS_PER_SET)
            .map(|_| {
                [
                    rng.range(-h, h) as f32,
                    rng.range(-h, h) as f32,
                    rng.range(-h, h) as f32,
                ]
            })
            .collect();
        let got = r.eval_points(&pts).unwrap();
        let entry = case
            .name
            .split(" [")
            .next()
            .unwrap_or(&case.name)
            .to_string();
        let mut ev64 = Evaluator::<f64>::new();
        let mut ev32 = Evaluator::<F32x8>::new();
        let mut bad = 0;
        let mut first = None;
        for (i, (p, g)) in pts.iter().zip(&got).enumerate() {
            let pd = [p[0] as f64, p[1] as f64, p[2] as f64];
            let c = ev64.eval(&tape, V3::new(pd[0], pd[1], pd[2]));
            let c32 = ev32.eval(
                &tape,
                V3::new(
                    <F32x8 as Real>::splat(pd[0]),
                    <F32x8 as Real>::splat(pd[1]),
                    <F32x8 as Real>::splat(pd[2]),
                ),
            );
            let err = (g.d as f64 - c.d).abs() / (c.d.abs() * REL + FLOOR);
            let e = worst.entry(entry.clone()).or_default();
            *e = e.max(err);
            let d_ok = agrees(g.d as f64, c.d, c32.d.lane(0), case.fractal, REL);
            let trap_ok = agrees(
                g.trap as f64,
                c.trap,
                c32.trap.lane(0),
                case.fractal,
                TRAP_REL,
            );
            // Material ids must match one of the CPU paths exactly.
            let id_ok = g.id as f64 == c.id || g.id as f64 == c32.id.lane(0);
            if !(d_ok && trap_ok && id_ok) {
                bad += 1;
                first.get_or_insert(format!(
                    "point {i} {p:?}: gpu d={} trap={} id={}, cpu f64 d={} trap={} id={}, cpu f32 d={} trap={}",
                    g.d, g.trap, g.id, c.d, c.trap, c.id, c32.d.lane(0), c32.trap.lane(0)
                ));
            }
        }
        if bad > 0 {
            failures.push(format!(
                "{}: {bad}/{} disagree; first: {}",
                case.name,
                pts.len(),
                first.unwrap()
            ));
        }
    }
    eprintln!("worst error per entry, in units of the tolerance (<= 1 passes):");
    for (k, v) in &worst {
        eprintln!("  {k}: {v:.3}");
    }
    assert!(
        failures.is_empty(),
        "{} cases disagree:\n{}",
        failures.len(),
        failures.join("\n")
    );
}
