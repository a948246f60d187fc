use super::*;
use crate::binding::{Lfo, OscInput, Source, Wave};
use crate::scene_file;
use crate::scenes;

fn key(eye: DVec3, target: DVec3) -> Keyframe {
    Keyframe {
        eye,
        target,
        up: DVec3::Y,
        fov: 45.0,
        time: None,
        scale: None,
        params: BTreeMap::new(),
    }
}

fn tour(scene: &Scene) -> FlightPath {
    let mut keys = vec![
        key(DVec3::new(3.0, 2.0, 3.0), DVec3::ZERO),
        key(DVec3::new(3.0, 1.0, -2.0), DVec3::new(0.2, 0.0, 0.0)),
        key(DVec3::new(-2.0, 0.5, -2.0), DVec3::ZERO),
        key(DVec3::new(-2.5, 0.3, 1.5), DVec3::new(0.0, 0.5, 0.0)),
        key(DVec3::new(0.0, 0.2, 1.6), DVec3::ZERO),
    ];
    keys[1].fov = 60.0;
    keys[2].time = Some(4.0);
    keys[0].params.insert("root.shape.radius".into(), 1.0);
    keys[3].params.insert("root.shape.radius".into(), 0.5);
    let p = FlightPath {
        ease_in: 1.0,
        ease_out: 2.0,
        ..FlightPath::new("tour", 10.0, keys)
    };
    p.validate(scene).unwrap();
    p
}

#[test]
fn the_spline_passes_through_every_keyframe() {
    let scene = scenes::sphere(1.0);
    let tape = Tape::compile(&scene).unwrap();
    let p = tour(&scene);
    for aware in [true, false] {
        let p = FlightPath {
            scale_aware: aware,
            ..p.clone()
        };
        let f = p.prepare(&scene, Some(&tape)).unwrap();
        let times = f.key_times();
        assert_eq!(times.len(), p.keys.len());
        assert_eq!(times[0], 0.0);
        assert_eq!(*times.last().unwrap(), 10.0);
        assert!((times[2] - f.unease(4.0)).abs() < 1e-12, "pinned key");
        assert!(times.windows(2).all(|w| w[0] < w[1]), "{times:?}");
        for (k, &t) in p.keys.iter().zip(&times) {
            let c = f.sample(t).camera;
            let want = k.camera().frame();
            let got = c.frame();
            assert!((c.eye - k.eye).length() < 1e-9, "{aware}: eye at {t}");
            assert!(
                (got.forward - want.forward).length() < 1e-6,
                "forward at {t}"
            );
            assert!((got.up - want.up).length() < 1e-6, "up at {t}");
            assert!((c.fov - k.fov).abs() < 1e-9, "fov at {t}");
            assert!(((c.target - c.eye).length() - (k.target - k.eye).length()).abs() < 1e-9);
            c.validate().unwrap();
        }
        // The parameter track passes through the keys that set it and holds after the last.
        let radius = |t: f64| f.sample(t).params[0];
        assert_eq!(f.params(), ["root.shape.radius"]);
        assert!((radius(times[0]) - 1.0).abs() < 1e-12);
        assert!((radius(times[3]) - 0.5).abs() < 1e-12);
        assert_eq!(radius(10.0), 0.5);
    }
}

#[test]
fn scale_aware_timing_gives_equal_log_scale_steps_on_a_pure_zoom() {
    // Dive straight at the top of a unit sphere: the distance estimate at each key is its
    // distance to the surface point, from 1 down to 1e-6 over three segments of unequal
    // depth (1e-1, then 1e-2, then 1e-3).
    let scene = scenes::sphere(1.0);
    let tape = Tape::compile(&scene).unwrap();
    let top = DVec3::new(0.0, 1.0, 0.0);
    let keys: Vec<Keyframe> = [1.0, 1e-1, 1e-3, 1e-6]
        .iter()
        .map(|&d| Keyframe {
            up: DVec3::Z,
            ..key(top + DVec3::Y * d, DVec3::ZERO)
        })
        .collect();
    let p = FlightPath::new("dive", 6.0, keys);
    let f = p.prepare(&scene, Some(&tape)).unwrap();
    let frames = 61;
    let logs: Vec<f64> = (0..frames)
        .map(|i| {
            let c = f.sample(6.0 * i as f64 / (frames - 1) as f64).camera;
            (c.eye - top).length().log10()
        })
        .collect();
    let step = -6.0 / (frames - 1) as f64;
    let worst = logs
        .windows(2)
        .map(|w| ((w[1] - w[0]) / step - 1.0).abs())
        .fold(0.0, f64::max);
    assert!(
        worst < 1e-3,
        "log10 steps differ from {step} by up to {worst:.2e}"
    );
    // Plain distance pacing spends nearly all its time at the large end.
    let plain = FlightPath {
        scale_aware: false,
        ..p.clone()
    }
    .prepare(&scene, Some(&tape))
    .unwrap();
    let half = (plain.sample(3.0).camera.eye - top).length();
    assert!(half > 0.3, "plain pacing at half time: {half}");
    assert!(((f.sample(3.0).camera.eye - top).length().log10() + 3.0).abs() < 1e-3);
}

#[test]
fn a_flight_zoom_is_the_camera_path_zoom() {
    use crate::camera_path::CameraPath;
    let (target, dir, start, depth) =
        (DVec3::ONE, DVec3::new(1.0, 0.8, 0.6).normalize(), 1.5, 1e10);
    let z = CameraPath::zoom(target, dir, start);
    let f = FlightPath::zoom(target, dir, start, depth, 50.0)
        .prepare(&scenes::sphere(1.0), None)
        .unwrap();
    let frames = 101;
    for i in 0..frames {
        let a = z.camera(i, frames, depth, 50.0);
        let pose = f.sample(i as f64 / (frames - 1) as f64);
        let b = pose.camera;
        let (da, db) = ((a.eye - target).length(), (b.eye - target).length());
        // Equal up to the rounding of coordinates near 1 (a few 1e-16).
        assert!(
            (db - da).abs() < 1e-9 * da + 2e-15,
            "frame {i}: {da:e} vs {db:e}"
        );
        // The orientation is exact; a look-at 1e-10 away only resolves directions to ~1e-6.
        assert!((pose.forward + dir).length() < 1e-12);
        assert!(((b.target - b.eye).normalize() - (a.target - a.eye).normalize()).length() < 1e-5);
    }
}

#[test]
fn easing_starts_and_ends_at_rest_and_retiming_stretches_time() {
    let scene = scenes::sphere(1.0);
    let p = tour(&scene);
    let f = p.prepare(&scene, None).unwrap();
    let dist = |a: f64, b: f64| (f.sample(a).camera.eye - f.sample(b).camera.eye).length();
    let dt = 1e-3;
    // Eased ends move much slower than the middle.
    assert!(dist(0.0, dt) < 0.05 * dist(5.0, 5.0 + dt));
    assert!(dist(10.0 - dt, 10.0) < 0.05 * dist(5.0, 5.0 + dt));
    for t in [0.0, 0.5, 1.0, 3.0, 8.5, 9.99] {
        assert!((f.unease(f.ease(t)) - t).abs() < 1e-9, "{t}");
    }
    let mut slow = p.clone();
    slow.retime(20.0);
    assert_eq!(slow.keys[2].time, Some(8.0));
    let g = slow.prepare(&scene, None).unwrap();
    for t in [0.0, 1.3, 4.0, 7.7, 10.0] {
        let (a, b) = (f.sample(t).camera, g.sample(2.0 * t).camera);
        assert!((a.eye - b.eye).length() < 1e-9, "{t}");
    }
    // Pinning out of order is refused and changes nothing.
    let mut q = p.clone();
    let e = q.pin(1, Some(5.0), &scene).unwrap_err();
    assert!(
        e.contains("keys[2].time") && e.contains("after the previous"),
        "{e}"
    );
    assert_eq!(q, p);
    q.pin(3, Some(6.0), &scene).unwrap();
    let h = q.prepare(&scene, None).unwrap();
    assert!((h.key_times()[3] - h.unease(6.0)).abs() < 1e-12);
    assert_eq!(h.insert_index(h.key_times()[3] + 0.01), 4);
}

fn with_paths() -> Scene {
    let mut s = scenes::sphere(1.0);
    s.paths.push(tour(&s));
    s.bindings.push(Binding {
        param: "root.shape.radius".into(),
        source: Source::Lfo(Lfo {
            wave: Wave::Sine,
            rate: 0.5,
            phase: 0.25,
            depth: 0.5,
            seed: 3,
        }),
        to: (0.8, 1.2),
        smoothing: 0.0,
    });
    s.bindings.push(Binding {
        param: "lights[0].intensity".into(),
        source: Source::Osc(OscInput {
            address: "/eeg/alpha".into(),
            arg: 2,
            from: (0.0, 40.0),
        }),
        to: (0.2, 1.5),
        smoothing: 0.25,
    });
    s
}

use crate::binding::Binding;

#[test]
fn saving_and_loading_keeps_paths_and_bindings() {
    let s = with_paths();
    s.validate().unwrap();
    s.validate_animation().unwrap();
    let text = scene_file::to_string(&s);
    let back = scene_file::parse(&text, "t.ron").unwrap();
    assert_eq!(back, s);
    assert!(
        text.contains("paths:") && text.contains("bindings:"),
        "{text}"
    );
    // A scene without any writes neither field (old files stay as they were).
    let plain = scene_file::to_string(&scenes::sphere(1.0));
    assert!(!plain.contains("paths") && !plain.contains("bindings"));
}

/// The scene file of [`with_paths`] with `from` replaced by `to` once.
fn edited(from: &str, to: &str) -> String {
    let text = scene_file::to_string(&with_paths());
    assert!(text.contains(from), "{from} not in\n{text}");
    text.replacen(from, to, 1)
}

fn error_at(text: &str) -> (usize, usize, String) {
    let e = scene_file::parse(text, "t.ron").unwrap_err();
    let (line, col) = e.position().unwrap_or_else(|| panic!("not located: {e}"));
    (line, col, e.to_string())
}

fn line_of(text: &str, needle: &str) -> usize {
    1 + text[..text.find(needle).unwrap()].matches('\n').count()
}

#[test]
fn bad_paths_and_bindings_are_located_errors() {
    // A path of one key.
    let s = with_paths();
    let mut one = s.clone();
    one.paths[0].keys.truncate(1);
    let text = scene_file::to_string(&one);
    let (line, _, msg) = error_at(&text);
    assert!(msg.contains("at least 2"), "{msg}");
    assert_eq!(line, line_of(&text, "keys:"), "{msg}");
    // A parameter that does not exist, on a key and in a binding.
    let text = edited("\"root.shape.radius\": 1.0", "\"root.shape.radios\": 1.0");
    let (line, _, msg) = error_at(&text);
    assert!(msg.contains("did you mean `radius`"), "{msg}");
    assert!(msg.contains("paths[0].keys[0].params"), "{msg}");
    assert_eq!(line, line_of(&text, "params:"), "{msg}");
    let text = edited(
        "param: \"lights[0].intensity\"",
        "param: \"lights[4].intensity\"",
    );
    let (line, _, msg) = error_at(&text);
    assert!(
        msg.contains("bindings[1].param") && msg.contains("1 lights"),
        "{msg}"
    );
    assert_eq!(line, line_of(&text, "param: \"lights[4]"), "{msg}");
    // NaN anywhere is refused by the lexer with its position.
    let text = edited("fov: 60.0", "fov: NaN");
    let (line, _, msg) = error_at(&text);
    assert!(msg.contains("finite"), "{msg}");
    assert_eq!(line, line_of(&text, "fov: NaN"));
    // Out-of-range mapping and an LFO too fast.
    let text = edited("to: (0.2, 1.5)", "to: (0.2, 1500.0)");
    let (_, _, msg) = error_at(&text);
    assert!(
        msg.contains("bindings[1].to") && msg.contains("[0, 1000]"),
        "{msg}"
    );
    let text = edited("rate: 0.5", "rate: 5000.0");
    assert!(error_at(&text).2.contains("rate = 5000"));
    // A pinned time on the last key, and out of order.
    let mut bad = s.clone();
    bad.paths[0].keys[4].time = Some(10.0);
    let msg = bad.validate_animation().unwrap_err().to_string();
    assert!(msg.starts_with("paths[0].keys[4].time"), "{msg}");
    let mut bad = s.clone();
    bad.paths[0].keys[3].time = Some(3.0);
    assert!(
        bad.validate_animation()
            .unwrap_err()
            .to_string()
            .contains("after the previous")
    );
    let mut dup = s.clone();
    dup.paths.push(dup.paths[0].clone());
    assert!(
        dup.validate_animation()
            .unwrap_err()
            .to_string()
            .contains("unique")
    );
    assert!(
        s.path("tuor")
            .unwrap_err()
            .to_string()
            .contains("did you mean `tour`")
    );
}

#[test]
fn the_example_dive_parses_and_stays_outside_the_bulb() {
    let text = include_str!("../../../../../docs/examples/mandelbulb-dive.ron");
    let scene = scene_file::parse(text, "mandelbulb-dive.ron").unwrap();
    let tape = Tape::compile(&scene).unwrap();
    let f = scene
        .path("dive")
        .unwrap()
        .prepare(&scene, Some(&tape))
        .unwrap();
    assert_eq!(f.params(), ["root.material.trap_colour"]);
    for i in 0..=120 {
        let t = f.duration() * i as f64 / 120.0;
        let eye = f.sample(t).camera.eye;
        let d = tape.eval_f64([eye.x, eye.y, eye.z]).d;
        assert!(d > 0.0, "t {t}: the eye is inside (estimate {d:e})");
    }
}

#[test]
fn tiny_key_scales_fly_without_overflow() {
    // Scales of 1e-200 and below passed validation and made the pacing table infinite,
    // then indexed past the fov knots.
    let scene = scenes::sphere(1.0);
    for tiny in [1e-200, 1e-300, 5e-324] {
        let mut p = tour(&scene);
        p.keys[1].scale = Some(tiny);
        p.keys[3].scale = Some(1e200);
        p.validate(&scene).unwrap();
        let f = p.prepare(&scene, None).unwrap();
        let times = f.key_times();
        assert!(times.iter().all(|t| t.is_finite()), "{tiny}: {times:?}");
        assert!(times.windows(2).all(|w| w[0] <= w[1]), "{tiny}: {times:?}");
        for k in 0..=40 {
            let c = f.sample(k as f64 * 0.25).camera;
            assert!(c.eye.is_finite() && c.fov.is_finite(), "{tiny} at {k}");
        }
    }
}

#[test]
fn the_scalar_spline_never_indexes_past_its_knots() {
    let knots = [(0.0, 1.0), (1.0, 2.0), (2.0, 4.0)];
    for x in [
        f64::NAN,
        f64::INFINITY,
        f64::NEG_INFINITY,
        0.5,
        1.5,
        -1.0,
        3.0,
    ] {
        let v = spline::scalar_at(&knots, x);
        assert!(v.is_finite(), "{x}: {v}");
    }
}
