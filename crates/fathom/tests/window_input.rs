//! The shipped explorer in a real window under Xvfb, driven by real X input (xdotool), read
//! back through its own per-frame log and captures of the screen (fathom-xdrive). egui's test
//! harness calls the app directly, so these are the tests that catch a window freezing on a
//! drag or a widget stealing a click. Each test starts its own X server and stops it by PID;
//! a missing Xvfb, xdotool or ImageMagick fails the test (scripts/setup.sh installs them).

use fathom_core::testing::scratch_dir;
use fathom_xdrive::{Display, Window, now_ms};
use serde_json::Value;
use std::path::Path;
use std::time::Duration;

/// One window at a time: the machine has two cores, and a window renders on both.
static SERIAL: std::sync::Mutex<()> = std::sync::Mutex::new(());

fn fathom() -> &'static Path {
    Path::new(env!("CARGO_BIN_EXE_fathom"))
}

/// The places (where widgets were drawn) in the newest line that has them.
fn places(log: &[Value]) -> Vec<Value> {
    log.iter()
        .rev()
        .find_map(|l| l["places"].as_array().cloned())
        .unwrap_or_default()
}

/// The rectangle (window pixels) of the widget `kind` `name`.
fn rect(log: &[Value], kind: &str, name: &str) -> [f64; 4] {
    let p = places(log);
    let r = p
        .iter()
        .find(|p| p["kind"] == kind && p["name"] == name)
        .unwrap_or_else(|| panic!("no {kind} `{name}` in the window's places: {p:?}"));
    let v: Vec<f64> = r["rect"]
        .as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_f64().unwrap())
        .collect();
    [v[0], v[1], v[2], v[3]]
}

fn centre(r: [f64; 4]) -> (f64, f64) {
    (r[0] + 0.5 * r[2], r[1] + 0.5 * r[3])
}

fn vec3(v: &Value) -> [f64; 3] {
    let a = v.as_array().unwrap();
    [
        a[0].as_f64().unwrap(),
        a[1].as_f64().unwrap(),
        a[2].as_f64().unwrap(),
    ]
}

/// The unit view direction of a logged camera.
fn direction(cam: &Value) -> [f64; 3] {
    let (e, t) = (vec3(&cam["eye"]), vec3(&cam["target"]));
    let d = [t[0] - e[0], t[1] - e[1], t[2] - e[2]];
    let n = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
    [d[0] / n, d[1] / n, d[2] / n]
}

fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

fn dist(a: [f64; 3], b: [f64; 3]) -> f64 {
    let d = [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
    dot(d, d).sqrt()
}

/// The value of the selected node's shape parameter `name` in a log line.
fn param(line: &Value, name: &str) -> f64 {
    line["selected_params"]
        .as_array()
        .unwrap()
        .iter()
        .find(|p| p[0] == name)
        .unwrap_or_else(|| panic!("no parameter {name} in {}", line["selected_params"]))[1][0]
        .as_f64()
        .unwrap()
}

/// Milliseconds between the motion events of a drag: a hand's pace, slower than a frame of a
/// test build on a loaded machine (egui sees a drag only across frames).
const STEP_MS: u64 = 100;

/// Waits until the view on screen is the final refinement (nothing renders any more).
fn settled(w: &mut Window) -> Vec<Value> {
    w.wait_for("the view to settle", 120.0, |log| {
        log.last().is_some_and(|l| l["settled"] == true)
    })
    .unwrap_or_else(|e| panic!("{e}"))
}

fn launch<'d>(display: &'d Display, dir: &Path, args: &[&str]) -> Window<'d> {
    let mut w = Window::launch(display, fathom(), args, &dir.join("frames.jsonl"))
        .unwrap_or_else(|e| panic!("{e}"));
    w.wait_for("a first picture", 180.0, |log| {
        log.iter().any(|l| !l["shown"].is_null()) && !places(log).is_empty()
    })
    .unwrap_or_else(|e| panic!("{e}"));
    w
}

/// Waits until the window has drawn a line after `t` (ms) for which `ok` holds; returns it.
fn line_after(w: &mut Window, what: &str, t: f64, ok: impl Fn(&Value) -> bool) -> Value {
    let log = w
        .wait_for(what, 60.0, |log| {
            log.iter().any(|l| l["t_ms"].as_f64().unwrap() > t && ok(l))
        })
        .unwrap_or_else(|e| panic!("{e}"));
    log.into_iter()
        .find(|l| l["t_ms"].as_f64().unwrap() > t && ok(l))
        .unwrap()
}

#[test]
fn a_drag_turns_the_camera_and_the_window_keeps_drawing_and_reading_keys() {
    let _serial = SERIAL.lock().unwrap_or_else(|e| e.into_inner());
    let display = Display::start(1280, 800).unwrap();
    let dir = scratch_dir("input-drag");
    let mut w = launch(
        &display,
        &dir,
        &["explore", "--preset", "menger", "--renderer", "trace"],
    );
    let log = settled(&mut w);
    let before = log.last().unwrap().clone();
    let vp = rect(&log, "viewport", "viewport");
    let t = w.drag(centre(vp), &[(5.0, 2.0); 10], STEP_MS).unwrap();
    let after = line_after(&mut w, "frames after the drag", now_ms() + 300.0, |_| true);
    let turn = dot(direction(&before["camera"]), direction(&after["camera"]))
        .clamp(-1.0, 1.0)
        .acos();

    // 50 px across and 20 down at 0.004 rad per point: about 0.2 rad (less what egui takes
    // to decide that a press is a drag).
    assert!(
        (0.08..0.4).contains(&turn),
        "the drag turned the view by {turn} rad"
    );
    assert_eq!(
        vec3(&before["camera"]["eye"]),
        vec3(&after["camera"]["eye"]),
        "mouse look turns the camera in place"
    );
    // The window still draws the new view and reads keys: W flies forward.
    let moved = line_after(&mut w, "a frame of the dragged view", t, |l| {
        l["shown_view"] == l["view"] && l["view"] != before["view"]
    });
    let t = now_ms();
    w.hold("w", 600).unwrap();
    let flown = line_after(&mut w, "a frame after holding W", t + 650.0, |_| true);
    let step =
        [0, 1, 2].map(|i| vec3(&flown["camera"]["eye"])[i] - vec3(&moved["camera"]["eye"])[i]);
    assert!(
        dot(step, direction(&moved["camera"])) > 0.05,
        "holding W did not fly forward: {step:?}"
    );
    // No edits: Ctrl+Q closes at once.
    w.key("ctrl+q").unwrap();
    let status = w
        .wait_exit(20.0)
        .expect("Ctrl+Q without edits closes the window");
    assert!(status.success(), "{status}: {}", w.stderr());
}

#[test]
fn a_click_on_the_surface_orbits_it_and_a_drag_moves_around_the_pivot() {
    let _serial = SERIAL.lock().unwrap_or_else(|e| e.into_inner());
    let display = Display::start(1280, 800).unwrap();
    let dir = scratch_dir("input-orbit");
    let mut w = launch(
        &display,
        &dir,
        &["explore", "--preset", "menger", "--renderer", "svo"],
    );
    let log = w.frames();
    let vp = rect(&log, "viewport", "viewport");
    let t = now_ms();
    w.click(centre(vp)).unwrap();
    let orbit = line_after(&mut w, "orbit mode after a click on the sponge", t, |l| {
        l["mode"] == "orbit"
    });
    let pivot = vec3(&orbit["pivot"]);
    let eye0 = vec3(&orbit["camera"]["eye"]);
    let t = w.drag(centre(vp), &[(8.0, 0.0); 8], STEP_MS).unwrap();
    let after = line_after(
        &mut w,
        "frames after the orbit drag",
        now_ms() + 300.0,
        |_| true,
    );
    let eye1 = vec3(&after["camera"]["eye"]);
    assert!(
        dist(eye0, eye1) > 0.05 * dist(eye0, pivot),
        "the orbit drag did not move the eye: {eye0:?} -> {eye1:?}"
    );
    assert!(
        (dist(eye1, pivot) - dist(eye0, pivot)).abs() < 1e-6 * dist(eye0, pivot).max(1.0),
        "orbiting keeps the distance to the pivot"
    );
    line_after(&mut w, "an octree frame of the orbited view", t, |l| {
        l["shown_view"] == l["view"] && l["renderer"] == "svo"
    });
}

#[test]
fn clicking_each_row_of_the_tree_selects_its_node() {
    let _serial = SERIAL.lock().unwrap_or_else(|e| e.into_inner());
    let display = Display::start(1280, 800).unwrap();
    let dir = scratch_dir("input-rows");
    let mut w = launch(
        &display,
        &dir,
        &["explore", "--preset", "model-tree", "--renderer", "trace"],
    );
    let rows: Vec<(String, [f64; 4])> = places(&w.frames())
        .iter()
        .filter(|p| p["kind"] == "tree")
        .map(|p| {
            let r: Vec<f64> = p["rect"]
                .as_array()
                .unwrap()
                .iter()
                .map(|x| x.as_f64().unwrap())
                .collect();
            (
                p["name"].as_str().unwrap().to_string(),
                [r[0], r[1], r[2], r[3]],
            )
        })
        .collect();
    assert!(rows.len() >= 9, "the model tree has 9 nodes: {rows:?}");
    // Bottom up, so the root (selected at the start) is clicked last.
    for (name, r) in rows.iter().rev() {
        let t = now_ms();
        w.click(centre(*r)).unwrap();
        line_after(&mut w, &format!("{name} to be selected"), t, |l| {
            l["selected"] == name.as_str()
        });
    }
}

#[test]
fn a_slider_drag_steps_sensibly_undoes_resets_and_quitting_asks_about_the_edit() {
    let _serial = SERIAL.lock().unwrap_or_else(|e| e.into_inner());
    let display = Display::start(1280, 800).unwrap();
    let dir = scratch_dir("input-slider");
    let mut w = launch(
        &display,
        &dir,
        &["explore", "--preset", "model-tree", "--renderer", "trace"],
    );
    let torus = "root.children[2]";
    let t = now_ms();
    w.click(centre(rect(&w.frames(), "tree", torus))).unwrap();
    let sel = line_after(&mut w, "the torus to be selected", t, |l| {
        l["selected"] == torus
    });
    assert_eq!(sel["selected_label"], "Torus (SmoothUnion)");
    let v0 = param(&sel, "minor");
    // Opening the colour picker (and closing it) is not an edit.
    let log = w
        .wait_for("the torus's material", 20.0, |log| {
            places(log)
                .iter()
                .any(|p| p["kind"] == "param" && p["name"] == "Material.albedo")
        })
        .unwrap();
    let t = now_ms();
    w.click(centre(rect(&log, "param", "Material.albedo")))
        .unwrap();
    std::thread::sleep(Duration::from_millis(800));
    w.key("Escape").unwrap();
    let after = line_after(&mut w, "frames after the colour picker", t + 1000.0, |_| {
        true
    });
    assert_eq!(
        after["dirty"], false,
        "opening the colour picker made an edit"
    );
    assert!(after["undo"].is_null(), "{}", after["undo"]);
    // The places of the torus's panel are logged once it is drawn.
    let log = w
        .wait_for("the torus's sliders", 20.0, |log| {
            places(log)
                .iter()
                .any(|p| p["kind"] == "param" && p["name"] == "Torus.minor")
        })
        .unwrap();
    let s = rect(&log, "param", "Torus.minor");
    // 36 px to the right, from a third of the way along the slider.
    let from = (s[0] + 30.0, s[1] + 0.5 * s[3]);
    let t = w.drag(from, &[(6.0, 0.0); 6], STEP_MS).unwrap();
    let edited = line_after(&mut w, "the slider's edit", now_ms() + 300.0, |l| {
        param(l, "minor") != v0
    });
    let v1 = param(&edited, "minor");
    // The slider covers the soft range [0, 1] of a torus tube (not the valid [0, 1e6]).
    assert!(
        (0.0..=1.0).contains(&v1) && (v1 - v0).abs() < 1.0,
        "a 36-pixel drag moved minor from {v0} to {v1}"
    );
    assert_eq!(edited["dirty"], true);
    let settled = line_after(&mut w, "the edit's undo entry", t, |l| {
        l["undo"] == "Torus (SmoothUnion): set minor"
    });
    assert!(
        settled["title"].as_str().unwrap().ends_with(" *"),
        "{}",
        settled["title"]
    );
    // Ctrl+Z undoes it.
    let t = now_ms();
    w.key("ctrl+z").unwrap();
    let undone = line_after(&mut w, "the undo", t, |l| param(l, "minor") == v0);
    assert_eq!(undone["dirty"], false);
    // A double-click on the slider resets the parameter to its default (0.25).
    let t = now_ms();
    w.hover(from).unwrap();
    w.xdotool(&["click", "--repeat", "2", "--delay", "90", "1"])
        .unwrap();
    let reset = line_after(&mut w, "the double-click's reset", t, |l| {
        l["undo"] == "Torus (SmoothUnion): reset minor"
    });
    assert_eq!(param(&reset, "minor"), 0.25);
    // Ctrl+Q with an unsaved edit asks first; Cancel keeps the window.
    let t = now_ms();
    w.key("ctrl+q").unwrap();
    let asked = line_after(&mut w, "the unsaved-changes dialog", t, |l| {
        l["dialog"] == "unsaved changes"
    });
    std::thread::sleep(Duration::from_millis(500));
    assert!(w.running(), "Ctrl+Q with unsaved edits closed the window");
    let log = w
        .wait_for("the dialog's buttons", 20.0, |log| {
            places(log)
                .iter()
                .any(|p| p["kind"] == "button" && p["name"] == "Discard")
        })
        .unwrap();
    let _ = asked;
    let t = now_ms();
    w.click(centre(rect(&log, "button", "Cancel"))).unwrap();
    line_after(&mut w, "the dialog to close", t, |l| l["dialog"].is_null());
    assert!(w.running());
    // Again, and Discard closes.
    w.key("ctrl+q").unwrap();
    let log = w
        .wait_for("the dialog again", 20.0, |log| {
            log.last().is_some_and(|l| l["dialog"] == "unsaved changes")
                && places(log)
                    .iter()
                    .any(|p| p["kind"] == "button" && p["name"] == "Discard")
        })
        .unwrap();
    w.click(centre(rect(&log, "button", "Discard"))).unwrap();
    let status = w.wait_exit(20.0).expect("Discard closes the window");
    assert!(status.success(), "{status}: {}", w.stderr());
}

/// The fraction of pixels brighter than `level` (of 255, any channel) in `img` within `r`.
fn bright(img: &image::RgbImage, r: [u32; 4], level: u8) -> Vec<bool> {
    let mut out = Vec::new();
    for y in r[1]..r[1] + r[3] {
        for x in r[0]..r[0] + r[2] {
            out.push(img.get_pixel(x, y).0.iter().any(|&c| c > level));
        }
    }
    out
}

fn iou(a: &[bool], b: &[bool]) -> f64 {
    let inter = a.iter().zip(b).filter(|(x, y)| **x && **y).count();
    let union = a.iter().zip(b).filter(|(x, y)| **x || **y).count();
    inter as f64 / union.max(1) as f64
}

#[test]
fn f12_writes_what_the_viewport_shows_with_the_lfo_s_value() {
    let _serial = SERIAL.lock().unwrap_or_else(|e| e.into_inner());
    let dir = scratch_dir("input-f12");
    // A white sphere of radius 0.5 on black whose LFO holds it at about 1.4 (a sine at
    // its crest, a period of 1000 s): an F12 of the document would show a far smaller disc.
    let scene = r#"Scene(
        version: 1,
        camera: Camera(eye: (0.0, 0.0, 6.0), target: (0.0, 0.0, 0.0), up: (0.0, 1.0, 0.0), fov: 40.0),
        render: RenderSettings(sky_top: (0.0, 0.0, 0.0), sky_bottom: (0.0, 0.0, 0.0), fog: 0.0, ambient: 0.6),
        root: Node(shape: Sphere(radius: 0.5), material: Material(albedo: (1.0, 1.0, 1.0))),
        bindings: [
            Binding(param: "root.shape.radius", source: Lfo(wave: Sine, rate: 0.001, phase: 0.25, depth: 1.0), to: (0.3, 1.4)),
        ],
    )"#;
    let file = dir.join("lfo.ron");
    std::fs::write(&file, scene).unwrap();
    let display = Display::start(1280, 800).unwrap();
    let mut w = launch(
        &display,
        &dir,
        &["explore", file.to_str().unwrap(), "--renderer", "trace"],
    );
    // The overlay off, then F12.
    w.key("F3").unwrap();
    std::thread::sleep(Duration::from_millis(500));
    let t = now_ms();
    w.key("F12").unwrap();
    let log = w
        .wait_for("the F12 screenshot to be written", 60.0, |log| {
            log.iter().any(|l| {
                l["t_ms"].as_f64().unwrap() > t
                    && l["status"].as_str().is_some_and(|s| {
                        s.starts_with("wrote") && s.contains("fathom-shot-001.png")
                    })
            })
        })
        .unwrap();
    let shot_path = dir.join("fathom-shot-001.png");
    let shot = image::open(&shot_path)
        .unwrap_or_else(|e| panic!("{}: {e}", shot_path.display()))
        .to_rgb8();
    let screen = dir.join("screen.png");
    w.capture(&screen).unwrap();
    let screen = image::open(&screen).unwrap().to_rgb8();
    let vp = rect(&log, "viewport", "viewport").map(|v| v.round() as u32);
    assert_eq!(
        shot.dimensions(),
        (vp[2], vp[3]),
        "F12 writes the viewport's size"
    );
    let a = bright(&shot, [0, 0, vp[2], vp[3]], 40);
    let b = bright(&screen, vp, 40);
    let score = iou(&a, &b);
    let covered = a.iter().filter(|x| **x).count() as f64 / a.len() as f64;
    eprintln!("F12 against the screen: IoU {score:.3}, sphere covers {covered:.3}");
    assert!(
        covered > 0.1,
        "the shot shows the LFO's large sphere: {covered}"
    );
    assert!(
        score > 0.9,
        "the F12 shot differs from the viewport: IoU {score}"
    );
}
