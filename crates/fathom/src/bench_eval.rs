//! `fathom bench eval`: throughput of the tape interpreter on one thread, per preset, for the
//! exact f64 scalar path, the f32x8 packet path and the double-double path (the deep-zoom
//! estimator: ns per evaluation and its cost relative to f64), plus the cost of compiling a
//! 100-node tree and of a parameter-only update; with `--primitives`, each primitive alone on
//! the f64 and f32x8 paths. Prints JSON.

use clap::Args;
use fathom_core::dd::{Dd, dd3};
use fathom_core::dd4::Dd4;
use fathom_core::presets::PRESETS;
use fathom_core::{Evaluator, F32x8, Real, Scene, Tape, V3};
use serde_json::json;
use std::hint::black_box;
use std::time::{Duration, Instant};

#[derive(Args)]
pub struct EvalArgs {
    /// Seconds spent measuring each figure.
    #[arg(long, default_value_t = 0.5)]
    seconds: f64,
    /// Only these presets (comma-separated); default: all.
    #[arg(long, value_delimiter = ',')]
    presets: Vec<String>,
    /// Also measure each primitive alone (ns a point on the f64 and f32x8 paths).
    #[arg(long)]
    primitives: bool,
}

/// Deterministic sample points in a cube around the camera target, sized by the view distance,
/// so each preset is measured where its camera looks.
fn sample_points(scene: &Scene, n: usize) -> Vec<[f64; 3]> {
    let c = scene.camera.target;
    let half = 0.6 * (scene.camera.eye - c).length();
    let mut state = 0x9e37_79b9_7f4a_7c15u64;
    let mut next = || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        (state >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
    };
    (0..n)
        .map(|_| {
            [
                c.x + half * next(),
                c.y + half * next(),
                c.z + half * next(),
            ]
        })
        .collect()
}

/// Runs `f` repeatedly for about `secs` seconds; returns calls per second.
fn rate(secs: f64, mut f: impl FnMut()) -> f64 {
    f(); // warm up
    let budget = Duration::from_secs_f64(secs);
    let start = Instant::now();
    let mut calls = 0u64;
    while start.elapsed() < budget {
        f();
        calls += 1;
    }
    calls as f64 / start.elapsed().as_secs_f64()
}

/// Evaluations per second on the f64 scalar, f32x8 packet, double-double and four-lane
/// double-double paths.
fn eval_rates(tape: &Tape, pts: &[[f64; 3]], secs: f64) -> (f64, f64, f64, f64) {
    let mut e64 = Evaluator::<f64>::new();
    let scalar = rate(secs, || {
        for p in pts {
            black_box(e64.distance(tape, V3::new(p[0], p[1], p[2])));
        }
    }) * pts.len() as f64;
    let packets: Vec<V3<F32x8>> = pts
        .chunks_exact(8)
        .map(|c| {
            let lane = |k: usize| F32x8::from_lanes(&c.iter().map(|p| p[k]).collect::<Vec<_>>());
            V3::new(lane(0), lane(1), lane(2))
        })
        .collect();
    let mut e32 = Evaluator::<F32x8>::new();
    let packet = rate(secs, || {
        for p in &packets {
            black_box(e32.distance(tape, *p));
        }
    }) * (packets.len() * 8) as f64;
    let dd_pts: Vec<V3<Dd>> = pts
        .iter()
        .map(|p| dd3(glam::DVec3::from_array(*p)))
        .collect();
    let mut edd = Evaluator::<Dd>::new();
    let dd = rate(secs, || {
        for p in &dd_pts {
            black_box(edd.distance(tape, *p));
        }
    }) * pts.len() as f64;
    let dd4_pts: Vec<V3<Dd4>> = dd_pts
        .chunks_exact(4)
        .map(|c| Dd4::pack(&[c[0], c[1], c[2], c[3]]))
        .collect();
    let mut edd4 = Evaluator::<Dd4>::new();
    let dd4 = rate(secs, || {
        for p in &dd4_pts {
            black_box(edd4.distance(tape, *p));
        }
    }) * (dd4_pts.len() * 4) as f64;
    (scalar, packet, dd, dd4)
}

/// Nanoseconds a point of each primitive at its default parameters, on the f64 scalar path
/// and the f32x8 packet path, over 4096 points in the cube [-2, 2]^3.
fn primitive_costs(secs: f64) -> Vec<serde_json::Value> {
    use fathom_core::primitives::Primitive;
    use fathom_core::registry::Family;
    let mut state = 0x2545_f491_4f6c_dd1du64;
    let mut next = || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        (state >> 11) as f64 / (1u64 << 53) as f64 * 4.0 - 2.0
    };
    let pts: Vec<V3<f64>> = (0..4096).map(|_| V3::new(next(), next(), next())).collect();
    let packets: Vec<V3<F32x8>> = pts
        .chunks_exact(8)
        .map(|c| {
            let lanes =
                |f: fn(&V3<f64>) -> f64| F32x8::from_lanes(&c.iter().map(f).collect::<Vec<_>>());
            V3::new(lanes(|p| p.x), lanes(|p| p.y), lanes(|p| p.z))
        })
        .collect();
    let mut rows = Vec::new();
    for &k in Primitive::ALL {
        let def = k.def();
        let mut a = Vec::new();
        def.bake_into(&def.defaults(), &mut a);
        let f64_rate = rate(secs, || {
            for p in &pts {
                black_box(k.distance::<f64>(*black_box(p), &a));
            }
        }) * pts.len() as f64;
        let x8_rate = rate(secs, || {
            for p in &packets {
                black_box(k.distance::<F32x8>(*black_box(p), &a));
            }
        }) * pts.len() as f64;
        eprintln!(
            "{:>18}: f64 {:>6.2} ns  f32x8 {:>6.2} ns a point",
            def.name,
            1e9 / f64_rate,
            1e9 / x8_rate
        );
        rows.push(json!({
            "primitive": def.name,
            "f64_ns_per_point": (1e11 / f64_rate).round() / 100.0,
            "f32x8_ns_per_point": (1e11 / x8_rate).round() / 100.0,
        }));
    }
    rows
}

pub fn run(a: EvalArgs) -> Result<(), String> {
    if !(a.seconds > 0.0 && a.seconds <= 60.0) {
        return Err(format!("--seconds = {} is out of range (0, 60]", a.seconds));
    }
    for name in &a.presets {
        fathom_core::presets::find(name).map_err(|e| e.to_string())?;
    }
    let mut rows = Vec::new();
    for p in PRESETS
        .iter()
        .filter(|p| a.presets.is_empty() || a.presets.iter().any(|n| n == p.name))
    {
        let scene = fathom_core::presets::load(p.name).map_err(|e| e.to_string())?;
        let tape = Tape::compile(&scene).map_err(|e| format!("{}: {e}", p.name))?;
        let pts = sample_points(&scene, 4096);
        let (scalar, packet, dd, dd4) = eval_rates(&tape, &pts, a.seconds);
        eprintln!(
            "{:>18}: f64 {:>10.0}/s  f32x8 {:>11.0}/s  x{:.2}  dd {:>8.1} ns  x{:.2} of f64  \
             dd x4 {:>8.1} ns a lane  x{:.2} of f64",
            p.name,
            scalar,
            packet,
            packet / scalar,
            1e9 / dd,
            scalar / dd,
            1e9 / dd4,
            scalar / dd4
        );
        rows.push(json!({
            "preset": p.name,
            "tape_len": tape.instrs().len(),
            "f64_scalar_evals_per_s": scalar.round(),
            "f32_packet_evals_per_s": packet.round(),
            "packet_over_scalar": (packet / scalar * 100.0).round() / 100.0,
            "f64_ns_per_eval": (1e10 / scalar).round() / 10.0,
            "dd_ns_per_eval": (1e10 / dd).round() / 10.0,
            "dd_over_f64": (scalar / dd * 100.0).round() / 100.0,
            "dd4_ns_per_lane": (1e10 / dd4).round() / 10.0,
            "dd4_over_f64": (scalar / dd4 * 100.0).round() / 100.0,
        }));
    }
    let scene = fathom_core::scenes::hundred_node_scene();
    let nodes = scene.root.count();
    let tape = Tape::compile(&scene).map_err(|e| e.to_string())?;
    let compile = 1e6
        / rate(a.seconds, || {
            black_box(Tape::compile(black_box(&scene)).ok());
        });
    let mut edited = scene.clone();
    let mut t2 = tape.clone();
    let update = 1e6
        / rate(a.seconds, || {
            edited.root.shape.params[0] += 1e-9;
            black_box(t2.update_params(&edited).ok());
        });
    // The same edits through the render session, as the window makes them: a parameter edit
    // (re-bakes the parameter buffer) and a structure edit (alternating between two trees, so
    // every call recompiles). Each call includes the copy of the scene handed to the session.
    let mut session = fathom_render::Session::new(scene.clone()).map_err(|e| e.to_string())?;
    let mut edited = scene.clone();
    let set_params = 1e6
        / rate(a.seconds, || {
            edited.root.shape.params[0] += 1e-9;
            black_box(session.set_scene(edited.clone()).ok());
        });
    let params_only = session.counters().compiles == 1;
    let mut smaller = scene.clone();
    smaller.root.children.pop();
    let shapes = [scene.clone(), smaller];
    let mut k = 0;
    let set_structure = 1e6
        / rate(a.seconds, || {
            k += 1;
            black_box(session.set_scene(shapes[k % 2].clone()).ok());
        });
    let mut out = json!({
        "bench": "eval",
        "threads": 1,
        "points_per_measurement": 4096,
        "presets": rows,
        "compile": {
            "nodes": nodes,
            "tape_len": tape.instrs().len(),
            "compile_us": (compile * 10.0).round() / 10.0,
            "update_params_us": (update * 10.0).round() / 10.0,
            "session_set_scene_params_us": (set_params * 10.0).round() / 10.0,
            "session_set_scene_params_compiled_nothing": params_only,
            "session_set_scene_structure_us": (set_structure * 10.0).round() / 10.0,
        },
    });
    if a.primitives {
        out["primitives"] = json!(primitive_costs(a.seconds));
    }
    println!(
        "{}",
        serde_json::to_string_pretty(&out).map_err(|e| e.to_string())?
    );
    Ok(())
}
