//! The GPU renderer (lavapipe on a machine without a GPU) against the CPU renderer: both demos
//! at 64x48 agree on at least 99% of pixels, and an animation frame rewrites only parameters.

use fathom_core::frame::Frame;
use fathom_micro::gpu::MicroGpu;
use fathom_micro::request::{Prepared, Request};
use fathom_trace::post::to_rgb8;
use std::sync::{LazyLock, Mutex};

/// One renderer per test binary: lavapipe compiles the pipeline on first use, slowly.
static GPU: LazyLock<Mutex<MicroGpu>> = LazyLock::new(|| {
    Mutex::new(MicroGpu::headless().unwrap_or_else(|e| {
        panic!("GPU tests need a Vulkan adapter: {e}\n(run scripts/setup.sh to install Mesa's lavapipe)")
    }))
});

/// Largest per-channel difference of the 8-bit output that counts as the same colour.
const COLOUR_TOL: u8 = 8;

/// (fraction of pixels within COLOUR_TOL, hit/miss disagreements).
fn compare(a: &Frame, b: &Frame) -> (f64, usize) {
    let (ca, cb) = (to_rgb8(a), to_rgb8(b));
    let same = (0..a.len())
        .filter(|&i| (0..3).all(|c| ca[3 * i + c].abs_diff(cb[3 * i + c]) <= COLOUR_TOL))
        .count();
    let hits = (0..a.len()).filter(|&i| a.is_hit(i) != b.is_hit(i)).count();
    (same as f64 / a.len() as f64, hits)
}

fn prepared(demo: &str) -> Prepared {
    prepared_at(demo, None)
}

/// A demo, optionally animated towards the keyframe scene `to` and taken at that keyframe.
fn prepared_at(demo: &str, to: Option<std::path::PathBuf>) -> Prepared {
    let mut r = Request::new();
    r.demo = Some(demo.into());
    (r.width, r.height) = (64, 48);
    r.time = 0.5 * r.period; // the animation's weight is 1 at half a period
    r.texture_to = to;
    r.prepare().unwrap()
}

#[test]
fn cpu_and_gpu_agree_on_both_demos() {
    let mut g = GPU.lock().unwrap_or_else(|e| e.into_inner());
    let mut report = Vec::new();
    let mut ok = true;
    for demo in ["teapot", "bush"] {
        let Prepared::Shell { scene, options, .. } = prepared(demo) else {
            unreachable!()
        };
        let (c, cs) = fathom_micro::render(&scene, &options, &|_, _| {}).unwrap();
        let tape = scene.texture.tape().unwrap();
        let (gf, gs) = g.render(&scene, tape, &options).unwrap();
        let (same, hit_diff) = compare(&c, &gf);
        report.push(format!(
            "{demo}: {:.2}% of pixels within {COLOUR_TOL}/255, {hit_diff} hit/miss disagreements; hits cpu {} gpu {}",
            same * 100.0,
            cs.hits,
            gs.hits
        ));
        ok &= same >= 0.99 && cs.hits > 300 && gs.base_hits + gs.texture_hits == gs.hits;
    }
    eprintln!("{}", report.join("\n"));
    assert!(ok, "{}", report.join("\n"));
}

#[test]
fn a_refused_texture_and_an_oversized_image_are_clear_errors() {
    let mut g = GPU.lock().unwrap_or_else(|e| e.into_inner());
    let Prepared::Shell {
        scene, mut options, ..
    } = prepared("teapot")
    else {
        unreachable!()
    };
    let tape = scene.texture.tape().unwrap().clone();
    options.width = 20000;
    let e = g.render(&scene, &tape, &options).unwrap_err().to_string();
    assert!(e.contains("20000x48") || e.contains("image size"), "{e}");
}

#[test]
fn an_animation_frame_rewrites_only_parameters_and_matches_the_cpu() {
    let mut g = GPU.lock().unwrap_or_else(|e| e.into_inner());
    let Prepared::Shell {
        scene: still,
        options,
        ..
    } = prepared("teapot")
    else {
        unreachable!()
    };
    // The second keyframe: the teapot's texture, its sponge shrunk and recoloured (same tree).
    let dir = std::env::temp_dir().join(format!("fathom-micro-anim-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let to = dir.join("to.ron");
    let text = include_str!("../demos/teapot-sponge.ron");
    let (scale, albedo) = ("Scale(factor: 0.9)", "albedo: (0.85, 0.62, 0.38)");
    assert!(
        text.contains(scale) && text.contains(albedo),
        "the demo changed: update this test"
    );
    let moved_text = text
        .replace(scale, "Scale(factor: 0.6)")
        .replace(albedo, "albedo: (0.2, 0.45, 0.9)");
    std::fs::write(&to, moved_text).unwrap();
    let Prepared::Shell { scene: moved, .. } = prepared_at("teapot", Some(to)) else {
        unreachable!()
    };
    std::fs::remove_dir_all(&dir).ok();

    let (first, _) = g
        .render(&still, still.texture.tape().unwrap(), &options)
        .unwrap();
    let before = g.tape_uploads();
    let (second, _) = g
        .render(&moved, moved.texture.tape().unwrap(), &options)
        .unwrap();
    let after = g.tape_uploads();
    assert_eq!(
        after.tapes_created, before.tapes_created,
        "an animation frame must not upload a new instruction stream"
    );
    assert_eq!(after.params_rewritten, before.params_rewritten + 1);

    let (same_as_still, _) = compare(&first, &second);
    assert!(
        same_as_still < 0.95,
        "the animated frame should differ from the still one ({:.1}% of pixels equal)",
        same_as_still * 100.0
    );
    let (cpu, _) = fathom_micro::render(&moved, &options, &|_, _| {}).unwrap();
    let (same, hit_diff) = compare(&cpu, &second);
    assert!(
        same >= 0.99,
        "GPU animation frame vs CPU: {:.2}% within {COLOUR_TOL}/255, {hit_diff} hit/miss disagreements",
        same * 100.0
    );
}
