//! f64 scalar evaluation against four f64 lanes ([`F64x4`]), and double-double scalar ([`Dd`])
//! against four double-double lanes ([`Dd4`]), on the zoom presets' scenes at points within
//! 1e-3 of their zoom targets (where the octree's subdivision evaluates; the double-double
//! points carry a trailing part below an f64 ulp, as on deep frames): ns per evaluation, the
//! speedups and the largest relative differences, as JSON lines.
//!
//! `cargo run --release -p fathom-core --example packet64`
use fathom_core::camera_path::path_preset;
use fathom_core::dd::Dd;
use fathom_core::dd4::Dd4;
use fathom_core::real::F64x4;
use fathom_core::{Evaluator, Real, Tape, V3};
use std::time::Instant;

/// Four points as one packet (lane `k` is point `k`), without allocating: the timed loop
/// measures the evaluation, as the scalar loop does.
fn pack(c: &[[f64; 3]]) -> V3<F64x4> {
    let lanes = |a: usize| F64x4::from(std::array::from_fn::<f64, 4, _>(|k| c[k][a]));
    V3::new(lanes(0), lanes(1), lanes(2))
}

/// Nanoseconds per point of `f` run over `n` points `reps` times.
fn time(reps: usize, n: usize, mut f: impl FnMut()) -> f64 {
    let t0 = Instant::now();
    for _ in 0..reps {
        f();
    }
    t0.elapsed().as_secs_f64() * 1e9 / (reps * n) as f64
}

fn main() {
    for name in ["mandelbulb", "menger"] {
        let p = path_preset(name).unwrap();
        let tape = Tape::compile(&p.scene).unwrap();
        let t = p.path.target().unwrap();
        let mut pts = Vec::new();
        let mut s = 12345u64;
        let mut rnd = || {
            s = s
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (s >> 11) as f64 / (1u64 << 53) as f64 - 0.5
        };
        for _ in 0..4096 {
            let sc = 1e-3;
            pts.push([t.x + sc * rnd(), t.y + sc * rnd(), t.z + sc * rnd()]);
        }
        let mut e1 = Evaluator::<f64>::new();
        let mut e4 = Evaluator::<F64x4>::new();
        let reps = 20;
        let t0 = Instant::now();
        let mut sum1 = 0.0;
        for _ in 0..reps {
            for q in &pts {
                sum1 += e1.distance(&tape, V3::new(q[0], q[1], q[2]));
            }
        }
        let d1 = t0.elapsed().as_secs_f64() * 1e9 / (reps * pts.len()) as f64;
        let t0 = Instant::now();
        let mut sum4 = 0.0;
        for _ in 0..reps {
            for c in pts.chunks_exact(4) {
                let v = e4.distance(&tape, pack(c));
                sum4 += (0..4).map(|i| v.lane(i)).sum::<f64>();
            }
        }
        let d4 = t0.elapsed().as_secs_f64() * 1e9 / (reps * pts.len()) as f64;
        let mut worst: f64 = 0.0;
        for c in pts.chunks_exact(4) {
            let v = e4.distance(&tape, pack(c));
            for (i, q) in c.iter().enumerate() {
                let s = e1.distance(&tape, V3::new(q[0], q[1], q[2]));
                worst = worst.max((v.lane(i) - s).abs() / s.abs().max(1e-300));
            }
        }
        // Deep points: the same points with a trailing part a few 1e-20 wide.
        let deep: Vec<V3<Dd>> = pts
            .iter()
            .map(|q| {
                let lo = 1e-20 * rnd();
                V3::new(
                    Dd::new(q[0], lo),
                    Dd::new(q[1], -lo),
                    Dd::new(q[2], 2.0 * lo),
                )
            })
            .collect();
        let mut ed1 = Evaluator::<Dd>::new();
        let mut ed4 = Evaluator::<Dd4>::new();
        let mut dsum1 = 0.0;
        let dd1 = time(reps / 4, deep.len(), || {
            for q in &deep {
                dsum1 += ed1.distance(&tape, *q).hi;
            }
        });
        let mut dsum4 = 0.0;
        let dd4 = time(reps / 4, deep.len(), || {
            for c in deep.chunks_exact(4) {
                let v = ed4.distance(&tape, Dd4::pack(&[c[0], c[1], c[2], c[3]]));
                dsum4 += (0..4).map(|i| v.lane(i)).sum::<f64>();
            }
        });
        let mut dworst: f64 = 0.0;
        for c in deep.chunks_exact(4) {
            let v = ed4.distance(&tape, Dd4::pack(&[c[0], c[1], c[2], c[3]]));
            for (i, q) in c.iter().enumerate() {
                let s = ed1.distance(&tape, *q).hi;
                dworst = dworst.max((v.lane(i) - s).abs() / s.abs().max(1e-300));
            }
        }
        println!(
            "{{\"preset\":\"{name}\",\"f64_ns_per_eval\":{d1:.1},\"f64x4_ns_per_eval\":{d4:.1},\"speedup\":{:.2},\"max_rel_diff\":{worst:.3e},\"check\":{:.3e},\"dd_ns_per_eval\":{dd1:.1},\"dd4_ns_per_eval\":{dd4:.1},\"dd_speedup\":{:.2},\"dd_max_rel_diff\":{dworst:.3e},\"dd_over_f64\":{:.2},\"dd4_over_f64x4\":{:.2}}}",
            d1 / d4,
            (sum1 - sum4).abs() / sum1.abs(),
            dd1 / dd4,
            dd1 / d1,
            dd4 / d4,
        );
    }
}
