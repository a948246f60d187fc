//! The whole explorer headless: egui_kittest drives the real app (the eframe `App`, egui drawn
//! by egui-wgpu on lavapipe, the render worker and its session) in a 320x240 window, through
//! its widgets as a user would, found by their labels. No display is needed.
//!
//! The viewport is compared with an offline render of the same state through
//! `fathom_render::Session` (the CPU tracer, which the window also uses on a software adapter
//! such as lavapipe). Tolerance, stated once for every comparison here: after refinement the
//! viewport shows the supersampled frame texel for texel (the viewport rectangle is snapped to
//! whole pixels), so the only differences come from the sRGB texture being decoded to linear
//! and encoded again by egui's renderer: at most [`MAX_LEVEL_DIFF`] levels of 255 per channel,
//! on every pixel but a one-pixel border (where egui may feather the image's edge).

use egui::accesskit::Role;
use egui_kittest::Harness;
use egui_kittest::kittest::Queryable;
use fathom_app::{ExploreOptions, ExplorerApp};
use fathom_core::presets;
use fathom_core::registry::Family;
use fathom_render::{Backend, RenderRequest, Session};
use std::time::{Duration, Instant};

/// Largest per-channel difference (of 255) between the viewport and the offline render.
const MAX_LEVEL_DIFF: u8 = 2;

/// The tests of this file one at a time (each drives a window and a render worker; the CI
/// machine has two cores).
static SERIAL: std::sync::Mutex<()> = std::sync::Mutex::new(());

/// How long a view may take to settle (dev build, 2 shared cores, lavapipe drawing the UI).
const SETTLE: Duration = Duration::from_secs(180);

fn harness(preset: &str) -> Harness<'static, ExplorerApp> {
    let scene = presets::load(preset).unwrap();
    let opts = ExploreOptions::new(scene, format!("preset {preset}"));
    Harness::builder()
        .with_size(egui::vec2(320.0, 240.0))
        .with_pixels_per_point(1.0)
        // The synthetic mouse cursor would be drawn over the viewport.
        .with_render_cursor(false)
        .wgpu()
        .build_eframe(move |cc| ExplorerApp::new(cc, opts).expect("the window starts"))
}

/// Steps the window until the viewport shows the final refinement of the current view.
fn settle(h: &mut Harness<'static, ExplorerApp>) {
    let start = Instant::now();
    while !h.state().settled() {
        assert!(
            start.elapsed() < SETTLE,
            "the view did not settle within {SETTLE:?}; notes: {:?}",
            h.state().notes()
        );
        h.step();
        std::thread::sleep(Duration::from_millis(5));
    }
}

/// The viewport's pixels as RGB, from a render of the whole window.
fn viewport_pixels(h: &mut Harness<'static, ExplorerApp>) -> (u32, u32, Vec<u8>) {
    let img = h.render().expect("the harness renders");
    let r = h.state().viewport_rect;
    let (x0, y0) = (r.min.x as u32, r.min.y as u32);
    let (w, ht) = (r.width() as u32, r.height() as u32);
    assert!(w >= 16 && ht >= 16, "viewport {r:?}");
    let mut out = Vec::with_capacity((w * ht * 3) as usize);
    for y in y0..y0 + ht {
        for x in x0..x0 + w {
            out.extend_from_slice(&img.get_pixel(x, y).0[..3]);
        }
    }
    (w, ht, out)
}

/// The offline render of the window's current state (scene, camera, settings) at `w` x `h`,
/// refined as the viewport refines, as 8-bit sRGB.
fn offline(app: &ExplorerApp, w: u32, h: u32) -> Vec<u8> {
    let req = RenderRequest {
        width: w,
        height: h,
        supersample: app.viewport.refine_supersample,
        ..app.settings.base_request()
    };
    let mut s = Session::new(app.scene.clone()).unwrap();
    let r = s.render(&app.view_camera(), &req).unwrap();
    fathom_trace::post::to_rgb8(&r.frame)
}

/// (largest channel difference, channels differing by more than `MAX_LEVEL_DIFF`) over every
/// pixel but a one-pixel border.
fn compare(w: u32, h: u32, a: &[u8], b: &[u8]) -> (u8, usize) {
    let mut max = 0u8;
    let mut over = 0;
    for y in 1..h - 1 {
        for x in 1..w - 1 {
            let i = ((y * w + x) * 3) as usize;
            for c in 0..3 {
                let d = a[i + c].abs_diff(b[i + c]);
                max = max.max(d);
                over += (d > MAX_LEVEL_DIFF) as usize;
            }
        }
    }
    (max, over)
}

fn menger_scale(app: &ExplorerApp) -> f64 {
    let def = app.scene.root.shape.kind.def();
    let i = def.params.iter().position(|p| p.name == "scale").unwrap();
    app.scene.root.shape.params[i]
}

#[test]
fn a_scripted_session_ends_with_the_viewport_equal_to_an_offline_render() {
    let _serial = SERIAL.lock().unwrap_or_else(|e| e.into_inner());
    let mut h = harness("sierpinski");
    h.run_steps(2);
    assert_eq!(
        h.state().settings.backend,
        Backend::Trace,
        "lavapipe is a CPU"
    );

    // Open the menger preset from the picker.
    h.get_by_label("preset").click();
    h.run_steps(2);
    h.get_by_label("menger").click();
    h.run_steps(2);
    let preset = presets::load("menger").unwrap();
    assert_eq!(
        h.state().scene.root,
        preset.root,
        "the menger preset is open"
    );

    // Fly forward for a few frames.
    let eye0 = h.state().view_camera().eye;
    h.key_down(egui::Key::W);
    for _ in 0..6 {
        h.step();
        std::thread::sleep(Duration::from_millis(20));
    }
    h.key_up(egui::Key::W);
    h.run_steps(2);
    let eye1 = h.state().view_camera().eye;
    let moved = (eye1 - eye0).length();
    assert!(moved > 1e-3, "the camera moved {moved}");
    assert!(
        (eye1 - eye0).normalize().dot(h.state().camera.forward()) > 0.99,
        "W flies forward"
    );

    // Edit the root's `scale` through its slider: a parameter edit compiles nothing.
    let compiles = {
        settle(&mut h);
        h.state().compiles
    };
    h.get_by_role_and_label(Role::Slider, "scale")
        .set_value_accesskit(2.6);
    h.run_steps(2);
    assert_eq!(menger_scale(h.state()), 2.6);
    let edited = h.state().scene.clone();
    settle(&mut h);
    assert_eq!(h.state().compiles, compiles, "a slider edit recompiled");

    // Add a node in the tree, then undo it (Ctrl+Z).
    h.get_by_label("Add child").click();
    h.run_steps(2);
    assert_eq!(h.state().scene.root.children.len(), 1, "a child was added");
    h.key_press_modifiers(egui::Modifiers::COMMAND, egui::Key::Z);
    h.run_steps(2);
    assert_eq!(h.state().scene, edited, "undo restored the edited scene");

    // Hide the panels and the stats overlay (F2, F3) to see the whole viewport, refine.
    h.key_press(egui::Key::F2);
    h.key_press(egui::Key::F3);
    h.run_steps(2);
    assert!(!h.state().show_panels && !h.state().show_overlay);
    settle(&mut h);

    let (w, ht, shown) = assert_viewport_is_offline_render(&mut h);

    // The comparison can fail: the same view before the slider edit differs clearly.
    let mut before = h.state().scene.clone();
    let def = before.root.shape.kind.def();
    let i = def.params.iter().position(|p| p.name == "scale").unwrap();
    before.root.shape.params[i] = 3.0;
    let req = RenderRequest {
        width: w,
        height: ht,
        supersample: h.state().viewport.refine_supersample,
        ..h.state().settings.base_request()
    };
    let other = fathom_trace::post::to_rgb8(
        &Session::new(before)
            .unwrap()
            .render(&h.state().view_camera(), &req)
            .unwrap()
            .frame,
    );
    let (_, over) = compare(w, ht, &shown, &other);
    assert!(
        over > (w * ht / 20) as usize,
        "the unedited scene differs in only {over} channels"
    );
}

/// Asserts the viewport equals the offline render of the window's state (see the module
/// doc for the tolerance); returns its size and pixels.
fn assert_viewport_is_offline_render(h: &mut Harness<'static, ExplorerApp>) -> (u32, u32, Vec<u8>) {
    let (w, ht, shown) = viewport_pixels(h);
    assert_eq!(
        (w, ht),
        {
            let s = h.state().viewport.shown.as_ref().unwrap();
            (s.request.width, s.request.height)
        },
        "the final frame is the viewport's size"
    );
    let want = offline(h.state(), w, ht);
    let (max, over) = compare(w, ht, &shown, &want);
    eprintln!("viewport {w}x{ht}: largest difference {max}, {over} channels over {MAX_LEVEL_DIFF}");
    assert_eq!(
        over, 0,
        "{over} channels differ by more than {MAX_LEVEL_DIFF} (largest {max})"
    );

    (w, ht, shown)
}

#[test]
fn faults_recover_a_zero_sized_viewport_an_out_of_range_value_and_a_panicked_worker() {
    let _serial = SERIAL.lock().unwrap_or_else(|e| e.into_inner());
    let mut h = harness("menger");
    h.run_steps(2);

    // A value typed outside the slider's declared range [1, 10] is clamped, and says so.
    h.get_by_role_and_label(Role::Slider, "scale")
        .set_value_accesskit(25.0);
    h.run_steps(2);
    assert_eq!(menger_scale(h.state()), 10.0);
    let note = h
        .state()
        .notes()
        .into_iter()
        .find(|n| n.0.contains("clamped"))
        .expect("a note about the clamp");
    assert!(
        note.0.contains("[1, 10]") && note.0.contains("25"),
        "{note:?}"
    );
    // Visible: the status bar shows it.
    h.get_by_label_contains("clamped to 10");

    // The window shrunk to nothing (a minimised window has no area) and back: no frame is
    // asked for while it has none, and the view settles again afterwards.
    h.set_size(egui::vec2(320.0, 0.0));
    h.run_steps(2);
    let asked = h.state().viewport.frames_asked();
    for _ in 0..5 {
        h.step();
        std::thread::sleep(Duration::from_millis(20));
    }
    assert_eq!(
        h.state().viewport.frames_asked(),
        asked,
        "frames asked for no area"
    );
    h.set_size(egui::vec2(320.0, 240.0));
    h.run_steps(2);
    h.key_press(egui::Key::F2);
    h.key_press(egui::Key::F3);
    h.run_steps(2);
    settle(&mut h);
    assert_viewport_is_offline_render(&mut h);

    // A render worker that panics is noticed and replaced; the view renders again.
    h.state().inject_worker_panic();
    let start = Instant::now();
    while h.state().worker_restarts == 0 {
        assert!(
            start.elapsed() < SETTLE,
            "the stopped worker was not replaced"
        );
        h.step();
        std::thread::sleep(Duration::from_millis(5));
    }
    let notes = h.state().notes();
    assert!(
        notes
            .iter()
            .any(|n| n.1 && n.0.contains("panicked") && n.0.contains("new render worker")),
        "{notes:?}"
    );
    h.key_down(egui::Key::D);
    for _ in 0..3 {
        h.step();
        std::thread::sleep(Duration::from_millis(20));
    }
    h.key_up(egui::Key::D);
    h.run_steps(2);
    settle(&mut h);
    assert_viewport_is_offline_render(&mut h);
}

#[test]
fn the_volume_renderer_refines_to_the_offline_cloud() {
    let _serial = SERIAL.lock().unwrap_or_else(|e| e.into_inner());
    let mut h = harness("menger");
    settle(&mut h);
    // The renderer picker's "volume (cloud)": the scene's interior path-traced as a cloud.
    {
        let app = h.state_mut();
        app.settings.backend = Backend::Volume;
        app.settings.volume.grid = 32;
        app.settings.volume.spp = 4;
    }
    // The whole viewport, without panels and overlay (F2, F3).
    h.key_press(egui::Key::F2);
    h.key_press(egui::Key::F3);
    h.step();
    settle(&mut h);
    let shown = h.state().viewport.shown.as_ref().unwrap().request.clone();
    assert_eq!(shown.backend, Backend::Volume);
    // The path tracer's streams are fixed per pixel and sample, so the refined viewport is
    // the offline render itself (same tolerance as the tracer's).
    let (w, ht, cloud) = assert_viewport_is_offline_render(&mut h);
    let solid = {
        let mut req = h.state().settings.base_request();
        req.backend = Backend::Trace;
        req.width = w;
        req.height = ht;
        let mut s = Session::new(h.state().scene.clone()).unwrap();
        let r = s.render(&h.state().view_camera(), &req).unwrap();
        fathom_trace::post::to_rgb8(&r.frame)
    };
    let (_, over) = compare(w, ht, &solid, &cloud);
    assert!(
        over > (w * ht / 20) as usize,
        "the cloud differs from the solid render in only {over} channels"
    );
}
