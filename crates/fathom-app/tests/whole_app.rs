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
    harness_with(
        ExploreOptions::new(scene, format!("preset {preset}")),
        egui::vec2(320.0, 240.0),
    )
}

fn harness_with(opts: ExploreOptions, size: egui::Vec2) -> Harness<'static, ExplorerApp> {
    Harness::builder()
        .with_size(size)
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
    fathom_image::post::to_rgb8(&r.frame)
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
    let other = fathom_image::post::to_rgb8(
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
        fathom_image::post::to_rgb8(&r.frame)
    };
    let (_, over) = compare(w, ht, &solid, &cloud);
    assert!(
        over > (w * ht / 20) as usize,
        "the cloud differs from the solid render in only {over} channels"
    );
}

// ---------------------------------------------------------------------------------------------
// Live modulation and flight paths in the window (issue 12).

/// A binding read from its scene-file form.
#[test]
fn the_path_tracer_accumulates_while_the_view_is_still_and_moving_shows_the_preview() {
    let _serial = SERIAL.lock().unwrap_or_else(|e| e.into_inner());
    let mut h = harness("menger");
    settle(&mut h);
    {
        let app = h.state_mut();
        app.settings.backend = Backend::Path;
        app.settings.path.spp = 6;
    }
    h.key_press(egui::Key::F2);
    h.key_press(egui::Key::F3);
    h.step();
    // The samples arrive in more than one frame: the picture refines on screen.
    let mut seen = Vec::new();
    let start = Instant::now();
    while !h.state().settled() {
        assert!(start.elapsed() < SETTLE, "notes: {:?}", h.state().notes());
        h.step();
        std::thread::sleep(Duration::from_millis(5));
        if let Some(p) = h.state().viewport.shown.as_ref().and_then(|s| s.stats.path)
            && seen.last() != Some(&p.samples_per_pixel)
        {
            seen.push(p.samples_per_pixel);
        }
    }
    assert!(
        seen.len() >= 2 && seen.windows(2).all(|w| w[0] < w[1]) && *seen.last().unwrap() == 6,
        "samples on screen: {seen:?}"
    );
    // The accumulated viewport is the offline render of all six samples at once.
    let (w, ht, shown) = viewport_pixels(&mut h);
    let want = {
        let req = RenderRequest {
            width: w,
            height: ht,
            ..h.state().settings.base_request()
        };
        let mut s = Session::new(h.state().scene.clone()).unwrap();
        let r = s.render(&h.state().view_camera(), &req).unwrap();
        assert_eq!(r.stats.path.unwrap().samples_per_pixel, 6);
        fathom_image::post::to_rgb8(&r.frame)
    };
    let (max, over) = compare(w, ht, &shown, &want);
    assert_eq!(over, 0, "largest difference {max}");
    // Moving shows the preview tracer, then starts accumulating anew.
    h.key_down(egui::Key::D);
    let mut preview = false;
    for _ in 0..40 {
        h.step();
        std::thread::sleep(Duration::from_millis(20));
        preview |= h
            .state()
            .viewport
            .shown
            .as_ref()
            .is_some_and(|s| s.stats.renderer == "trace");
        if preview {
            break;
        }
    }
    h.key_up(egui::Key::D);
    assert!(
        preview,
        "a moving path-traced view shows the preview tracer"
    );
    settle(&mut h);
    let s = h.state().viewport.shown.as_ref().unwrap();
    assert_eq!(s.stats.path.map(|p| p.samples_per_pixel), Some(6));
}

fn binding(text: &str) -> fathom_core::binding::Binding {
    ron::from_str(text).unwrap()
}

/// Steps the window until `done` holds (at most [`SETTLE`]); returns the frames stepped.
fn step_until(
    h: &mut Harness<'static, ExplorerApp>,
    what: &str,
    done: impl Fn(&ExplorerApp) -> bool,
) -> u64 {
    let start = Instant::now();
    let mut frames = 0;
    while !done(h.state()) {
        assert!(
            start.elapsed() < SETTLE,
            "{what}: not within {SETTLE:?}; notes: {:?}",
            h.state().notes()
        );
        h.step();
        frames += 1;
        std::thread::sleep(Duration::from_millis(5));
    }
    frames
}

/// The first bound value of the frame on screen, and the viewport's mean level (of 255),
/// read so that both belong to the same frame, rendered at the viewport's full size (so two
/// such frames of the same view differ only by what the scene's numbers change; a coarse
/// interactive frame loses much of a fractal's fine detail, and so its mean level).
fn shown_value_and_mean(h: &mut Harness<'static, ExplorerApp>) -> (f64, f64, Vec<u8>) {
    loop {
        let r = h.state().viewport_rect;
        let coarse = h.state().viewport.shown.as_ref().is_none_or(|s| {
            s.request.width as f32 != r.width() || s.request.height as f32 != r.height()
        });
        if coarse {
            h.step();
            std::thread::sleep(Duration::from_millis(5));
            continue;
        }
        let before = h.state().shown_values().and_then(|v| v[0]);
        let (_, _, px) = viewport_pixels(h);
        let after = h.state().shown_values().and_then(|v| v[0]);
        if let (Some(a), Some(b)) = (before, after)
            && a == b
        {
            let mean = px.iter().map(|&x| x as f64).sum::<f64>() / px.len() as f64;
            return (a, mean, px);
        }
        h.step();
    }
}

#[test]
fn an_lfo_binding_animates_the_viewport_with_no_recompiles() {
    let _serial = SERIAL.lock().unwrap_or_else(|e| e.into_inner());
    let mut scene = presets::load("menger").unwrap();
    let light = scene.lights[0].intensity;
    scene.bindings.push(binding(
        r#"Binding(param: "lights[0].intensity", source: Lfo(wave: Sine, rate: 0.5), to: (0.1, 2.5))"#,
    ));
    scene.validate().unwrap();
    let mut h = harness_with(ExploreOptions::new(scene, "lfo"), egui::vec2(320.0, 240.0));
    h.run_steps(2);
    // The whole viewport: no side panels, overlay or live panels.
    h.key_press(egui::Key::F2);
    h.key_press(egui::Key::F3);
    h.key_press(egui::Key::F4);
    // The keys take effect in the next frame; a first frame can already be on screen before
    // it (slower builds deliver one within the first steps), laid out beside the panels.
    step_until(&mut h, "the panels hidden and a first frame", |a| {
        !a.show_panels && !a.show_overlay && !a.show_live && a.shown_values().is_some()
    });
    let compiles = h.state().compiles;
    let (v0, m0, px0) = shown_value_and_mean(&mut h);
    // Frames keep coming with new values and no input at all.
    step_until(&mut h, "a frame with a different light", |a| {
        a.shown_values()
            .and_then(|v| v[0])
            .is_some_and(|v| (v - v0).abs() > 0.6)
    });
    let (v1, m1, px1) = shown_value_and_mean(&mut h);
    assert_eq!(px0.len(), px1.len(), "both frames fill the same viewport");
    let changed = px0
        .iter()
        .zip(&px1)
        .filter(|(a, b)| a.abs_diff(**b) > MAX_LEVEL_DIFF)
        .count() as f64
        / px0.len() as f64;
    eprintln!(
        "light {v0:.3} -> mean level {m0:.2}; light {v1:.3} -> mean level {m1:.2}; {:.1} % of \
         channels changed",
        changed * 100.0
    );
    assert!((v1 - v0).abs() > 0.6);
    assert!(
        changed > 0.2,
        "only {:.1} % of channels changed",
        changed * 100.0
    );
    assert!(
        (m1 - m0) * (v1 - v0) > 0.0 && (m1 - m0).abs() > 1.0,
        "the viewport did not follow the light: {m0:.2} -> {m1:.2}"
    );
    assert_eq!(h.state().compiles, compiles, "modulation recompiled");
    assert_eq!(compiles, 1, "only the first compile");
    let app = h.state();
    assert_eq!(
        app.scene.lights[0].intensity, light,
        "the document is not modulated"
    );
    assert!(app.notes().iter().all(|n| !n.1), "{:?}", app.notes());
}

#[test]
fn an_osc_packet_reaches_the_bound_parameter_in_the_next_frames_and_the_log() {
    let _serial = SERIAL.lock().unwrap_or_else(|e| e.into_inner());
    let mut scene = presets::load("sierpinski").unwrap();
    scene.bindings.push(binding(
        r#"Binding(param: "lights[0].intensity", source: Osc(address: "/test/light"), to: (0.2, 1.6))"#,
    ));
    scene.bindings.push(binding(
        r#"Binding(param: "camera.fov", source: Osc(address: "/test/fov"), to: (30.0, 60.0))"#,
    ));
    let dir = std::env::temp_dir().join(format!("fathom-live-window-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let log = dir.join("frames.jsonl");
    let mut opts = ExploreOptions::new(scene, "osc");
    opts.osc_bind = Some("127.0.0.1:0".parse().unwrap());
    opts.log = Some(log.clone());
    let mut h = harness_with(opts, egui::vec2(480.0, 320.0));
    h.run_steps(3);
    let addr = h.state().live.modulator.osc_addr().expect("listening");
    assert_eq!(
        h.state().live.modulator.live()[0].value,
        None,
        "nothing yet"
    );
    // The panel shows the listener.
    h.get_by_label_contains(&format!("OSC on {addr}"));
    let compiles = h.state().compiles;

    let tx = fathom_live::Sender::new(addr).unwrap();
    tx.send("/test/light", &[1.0]).unwrap();
    let frames = step_until(&mut h, "the packet in the live scene", |a| {
        a.live_scene().lights[0].intensity == 1.6
    });
    eprintln!("the packet reached the live scene after {frames} frame(s)");
    assert!(frames <= 20, "{frames} frames");
    let frames = step_until(&mut h, "a frame showing it", |a| {
        a.shown_values().is_some_and(|v| v[0] == Some(1.6))
    });
    eprintln!("... and the screen {frames} frame(s) later");

    // Garbage and a NaN are counted and change nothing.
    tx.send_raw(b"not osc at all").unwrap();
    tx.send("/test/light", &[f64::NAN]).unwrap();
    step_until(&mut h, "two rejections", |a| {
        a.live.counters().rejected >= 2
    });
    h.run_steps(2);
    assert_eq!(h.state().live_scene().lights[0].intensity, 1.6);
    // A second value goes through too.
    tx.send("/test/light", &[0.0]).unwrap();
    step_until(&mut h, "the second packet", |a| {
        a.live_scene().lights[0].intensity == 0.2
    });
    // The panel (drawn before this frame's values are taken) shows it a frame later; the
    // NaN was not received by the binding.
    h.run_steps(2);
    h.get_by_label("0.2 (2 received)");
    assert_eq!(h.state().compiles, compiles, "OSC recompiled");

    // A camera binding drives the view's camera; the flown camera keeps its own.
    let flown = h.state().camera.camera().fov;
    tx.send("/test/fov", &[1.0]).unwrap();
    step_until(&mut h, "the fov packet", |a| a.view_camera().fov == 60.0);
    assert_eq!(h.state().camera.camera().fov, flown);

    // The log's last line has the counters and the value.
    let text = std::fs::read_to_string(&log).unwrap();
    let last: serde_json::Value = serde_json::from_str(text.lines().last().unwrap()).unwrap();
    assert!(last["osc"]["packets"].as_u64().unwrap() >= 4, "{last}");
    assert!(last["osc"]["rejected"].as_u64().unwrap() >= 2, "{last}");
    assert_eq!(last["bound"][0]["param"], "lights[0].intensity");
    assert_eq!(last["bound"][0]["value"].as_f64(), Some(0.2), "{last}");
    assert_eq!(last["bound"][1]["value"].as_f64(), Some(60.0), "{last}");
    assert_eq!(last["camera"]["fov"].as_f64(), Some(60.0), "{last}");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn the_timeline_scrubs_plays_and_records_a_key_at_the_view() {
    let _serial = SERIAL.lock().unwrap_or_else(|e| e.into_inner());
    use fathom_core::flight::{FlightPath, Keyframe};
    let mut scene = presets::load("sierpinski").unwrap();
    let c = scene.camera.clone();
    let doc_light = scene.lights[0].intensity;
    let key = |scale: f64, swing: f64, light: Option<f64>| {
        let mut k = Keyframe::from_camera(&c);
        k.eye = c.target + (c.eye - c.target) * scale + glam::DVec3::new(swing, 0.0, 0.0);
        if let Some(l) = light {
            k.params.insert("lights[0].intensity".into(), l);
        }
        k
    };
    scene.paths.push(FlightPath::new(
        "orbit",
        8.0,
        vec![
            key(1.0, 0.0, Some(0.5)),
            key(0.8, 0.6, None),
            key(0.6, -0.4, Some(1.5)),
        ],
    ));
    scene.validate().unwrap();
    let mut h = harness_with(
        ExploreOptions::new(scene, "timeline"),
        egui::vec2(640.0, 480.0),
    );
    h.run_steps(3);
    let flight = |app: &ExplorerApp| {
        let tape = fathom_core::Tape::compile(&app.scene).unwrap();
        app.scene.paths[0].prepare(&app.scene, Some(&tape)).unwrap()
    };
    let check_at = |app: &ExplorerApp, t: f64| {
        let pose = flight(app).sample(t);
        let view = app.view_camera();
        let d = (view.eye - pose.camera.eye).length();
        assert!(d < 1e-9, "the view is {d} from the path's eye at {t} s");
        let fwd = (view.target - view.eye).normalize();
        assert!(
            fwd.dot(pose.forward) > 1.0 - 1e-9,
            "{fwd} vs {}",
            pose.forward
        );
        assert!((view.fov - pose.camera.fov).abs() < 1e-9);
        let light = app.live_scene().lights[0].intensity;
        assert!(
            (light - pose.params[0]).abs() < 1e-12,
            "{light} vs {:?}",
            pose.params
        );
    };

    // Scrub to 5 s through the slider.
    h.get_by_role_and_label(Role::Slider, "path time")
        .set_value_accesskit(5.0);
    h.run_steps(2);
    assert_eq!(h.state().live.timeline.t, 5.0);
    check_at(h.state(), 5.0);
    let far = (h.state().view_camera().eye - c.eye).length();
    assert!(far > 0.1, "the scrub moved the camera {far}");
    // The parameter key is written into the live scene only.
    assert_eq!(h.state().scene.lights[0].intensity, doc_light);

    // Add a key at this view: it lands at 5 s.
    h.get_by_label("Add key at view").click();
    h.run_steps(2);
    let app = h.state();
    assert_eq!(app.scene.paths[0].keys.len(), 4);
    let f = flight(app);
    let i = f
        .key_times()
        .iter()
        .position(|&k| (k - 5.0).abs() < 1e-6)
        .expect("a key at 5 s");
    assert!((app.scene.paths[0].keys[i].eye - app.view_camera().eye).length() < 1e-12);

    // Play from 0 for a few frames, then pause: time moved, the view is the path's pose.
    h.get_by_role_and_label(Role::Slider, "path time")
        .set_value_accesskit(0.0);
    h.run_steps(2);
    h.get_by_label("Play").click();
    for _ in 0..8 {
        h.step();
        std::thread::sleep(Duration::from_millis(20));
    }
    h.get_by_label("Pause").click();
    h.run_steps(2);
    let t = h.state().live.timeline.t;
    assert!(t > 0.05 && t < 8.0, "played to {t} s");
    assert!(!h.state().live.timeline.playing);
    check_at(h.state(), t);
    h.run_steps(3);
    assert_eq!(h.state().live.timeline.t, t, "paused");

    // Undo removes the key.
    h.key_press_modifiers(egui::Modifiers::COMMAND, egui::Key::Z);
    h.run_steps(2);
    assert_eq!(h.state().scene.paths[0].keys.len(), 3);
}

#[test]
fn an_osc_port_in_use_is_refused_before_any_window_naming_the_port() {
    let taken = std::net::UdpSocket::bind("127.0.0.1:0").unwrap();
    let addr = taken.local_addr().unwrap();
    let mut opts = ExploreOptions::new(presets::load("sierpinski").unwrap(), "busy");
    opts.osc_bind = Some(addr);
    match fathom_app::run(opts) {
        Err(e @ fathom_app::WindowError::Osc(_)) => {
            let msg = e.to_string();
            assert!(msg.contains(&addr.to_string()), "{msg}");
            assert!(msg.contains("--osc-port"), "{msg}");
        }
        other => panic!("expected the OSC error, got {other:?}"),
    }
}

/// Percentile `p` (0-100) of `xs`, ms.
fn percentile(xs: &mut [f64], p: f64) -> f64 {
    xs.sort_by(f64::total_cmp);
    xs[((xs.len() - 1) as f64 * p / 100.0).round() as usize]
}

#[test]
fn a_flood_of_osc_packets_and_garbage_neither_stops_nor_breaks_the_window() {
    let _serial = SERIAL.lock().unwrap_or_else(|e| e.into_inner());
    let mut scene = presets::load("sierpinski").unwrap();
    scene.bindings.push(binding(
        r#"Binding(param: "lights[0].intensity", source: Osc(address: "/test/light"), to: (0.2, 1.6))"#,
    ));
    let mut opts = ExploreOptions::new(scene, "flood");
    opts.osc_bind = Some("127.0.0.1:0".parse().unwrap());
    let mut h = harness_with(opts, egui::vec2(320.0, 240.0));
    h.run_steps(3);
    let addr = h.state().live.modulator.osc_addr().expect("listening");
    let step_ms = |h: &mut Harness<'static, ExplorerApp>| {
        let t = Instant::now();
        h.step();
        t.elapsed().as_secs_f64() * 1e3
    };
    let mut quiet: Vec<f64> = (0..60).map(|_| step_ms(&mut h)).collect();

    // 100,000 datagrams as fast as one thread sends them: a third valid (some far out of
    // range), a third NaN, a third garbage.
    let sender = std::thread::spawn(move || {
        let tx = fathom_live::Sender::new(addr).unwrap();
        for i in 0..100_000u32 {
            let _ = match i % 3 {
                0 => tx.send("/test/light", &[(i % 7) as f64 - 3.0]),
                1 => tx.send("/test/light", &[f64::NAN]),
                _ => tx.send_raw(&i.to_le_bytes()),
            };
        }
    });
    let mut flood = Vec::new();
    while !sender.is_finished() {
        flood.push(step_ms(&mut h));
    }
    sender.join().unwrap();
    h.run_steps(5);
    let c = h.state().live.counters();
    let (q50, q99) = (percentile(&mut quiet, 50.0), percentile(&mut quiet, 99.0));
    let (f50, f99) = (percentile(&mut flood, 50.0), percentile(&mut flood, 99.0));
    eprintln!(
        "window frames quiet p50 {q50:.2} / p99 {q99:.2} ms; during the flood ({} frames) p50 \
         {f50:.2} / p99 {f99:.2} ms; {c:?}",
        flood.len()
    );
    // Frames kept coming during the flood; what arrived was counted; the value stayed in the
    // binding's range; nothing was reported as an error.
    assert!(flood.len() >= 3, "{} frames during the flood", flood.len());
    assert!(
        c.packets > 0 && c.malformed > 0 && c.bad_values > 0,
        "{c:?}"
    );
    assert!(c.clamped > 0, "{c:?}");
    let v = h.state().live_scene().lights[0].intensity;
    assert!((0.2..=1.6).contains(&v), "{v}");
    assert!(
        h.state().notes().iter().all(|n| !n.1),
        "{:?}",
        h.state().notes()
    );
    assert_eq!(h.state().compiles, 1, "the flood recompiled");
}
