//! Tests of the reference tracer: at shallow cameras its silhouettes are the ordinary tracer's;
//! at the Menger corner 3^20 and 3^31 times closer it draws the same picture with depths scaled
//! by exactly that factor, which neither the same march in f64 nor the ordinary tracer can.

use super::*;
use crate::render::{Hooks, Options, render_tape};
use fathom_core::camera_path::{CameraPath, path_preset};
use fathom_core::{Scene, presets, scenes};
use fathom_image::compare::silhouette_iou;
use glam::DVec3;

const W: u32 = 48;
const H: u32 = 36;

/// Depths of the ordinary CPU tracer (f32 packets, or its f64 path once the view is deep).
fn tracer_depths(scene: &Scene, cam: &Camera) -> Vec<Option<f64>> {
    let tape = Tape::compile(scene).unwrap();
    let opts = Options {
        width: W,
        height: H,
        geometry_only: true,
        ..Options::default()
    };
    let (frame, _) = render_tape(&tape, scene, cam, &opts, None, Hooks::NONE).unwrap();
    frame
        .depth
        .iter()
        .map(|&d| d.is_finite().then_some(d as f64))
        .collect()
}

/// Of the pixels both images hit, the fraction whose depths agree within `tol` relative after
/// scaling `a` by `s`, and the worst relative difference.
fn depth_agreement(a: &[Option<f64>], s: f64, b: &[Option<f64>], tol: f64) -> (f64, f64, usize) {
    let (mut both, mut ok, mut worst) = (0usize, 0usize, 0.0f64);
    for (x, y) in a.iter().zip(b) {
        if let (Some(x), Some(y)) = (x, y) {
            both += 1;
            let e = (x * s - y).abs() / y.abs().max(1e-300);
            worst = worst.max(e);
            ok += (e <= tol) as usize;
        }
    }
    (ok as f64 / both.max(1) as f64, worst, both)
}

fn hits(a: &[Option<f64>]) -> usize {
    a.iter().filter(|x| x.is_some()).count()
}

#[test]
fn shallow_silhouettes_match_the_ordinary_tracer() {
    for name in ["menger", "mandelbulb"] {
        let scene = presets::load(name).unwrap();
        let cam = scene.camera.clone();
        let tape = Tape::compile(&scene).unwrap();
        let scale = (cam.target - cam.eye).length();
        let deep = deep_depths(
            &tape,
            eye_of(&cam),
            &cam,
            W,
            H,
            &DeepOptions::for_scale(scale),
        );
        let ordinary = tracer_depths(&scene, &cam);
        let iou = silhouette_iou(&deep, &ordinary);
        let (within, worst, both) = depth_agreement(&deep, 1.0, &ordinary, 1e-3);
        eprintln!(
            "{name}: IoU {iou:.4} ({} deep hits, {} tracer hits); depths within 1e-3 on {:.3} of {both} (worst {worst:.1e})",
            hits(&deep),
            hits(&ordinary),
            within
        );
        assert!(
            hits(&deep) > (W * H) as usize / 10,
            "{name}: the view is nearly empty"
        );
        assert!(iou >= 0.99, "{name}: IoU {iou}");
    }
}

/// `(1, 1, 1) + off 3^-k` in double-double.
fn corner_eye(off: DVec3, k: i32) -> V3<Dd> {
    let s = 3f64.powi(k);
    let c = |x: f64| Dd::ONE + Dd::from(x) / s;
    V3::new(c(off.x), c(off.y), c(off.z))
}

/// The Menger corner path's view scaled about (1, 1, 1) by 3^-k: the eye in double-double
/// and in f64 (rounded), the orientation (the unscaled camera: exact), the f64 camera the
/// ordinary tracer gets (its orientation computed from the rounded eye) and the march options.
struct CornerView {
    eye: V3<Dd>,
    eye64: DVec3,
    camera: Camera,
    camera64: Camera,
    opts: DeepOptions,
}

fn corner_view(k: i32) -> CornerView {
    let pp = path_preset("menger").unwrap();
    let cam = pp.camera(0, 2, 1.0);
    let off = cam.eye - DVec3::ONE;
    let s = 3f64.powi(k);
    CornerView {
        eye: corner_eye(off, k),
        eye64: DVec3::ONE + off / s,
        camera64: Camera {
            eye: DVec3::ONE + off / s,
            ..cam.clone()
        },
        camera: cam,
        opts: DeepOptions::for_scale(off.length() / s),
    }
}

fn menger_tape(iterations: u32) -> Tape {
    Tape::compile(&scenes::menger(iterations)).unwrap()
}

#[test]
fn menger_corner_zooms_are_self_similar_in_dd_only() {
    // Views scaled about the corner by 3^-k show the same geometry, scaled, wherever the
    // sponge near the corner is its own image under p -> (p + 2) / 3: within the cube
    // [1 - 2 3^j, 1]^3 of a view j levels deep, in that view's units. Rays of the path's first
    // view (k = 0) that leave the sponge's cube [-1, 1]^3 see nothing, while at k >= 1 they
    // see its neighbouring copies; from k = 5 on the cube (side 2 3^5 = 486 starting
    // distances) is beyond the march's far limit (100 starting distances), so views at
    // k >= 5 are exactly self-similar: the reference is k0 = 5. Each view gets the same number
    // of levels below it (`10 + k - k0`), so the identity holds to the last level.
    let (n0, k0) = (10u32, 5i32);
    let reference = {
        let v = corner_view(k0);
        deep_depths(&menger_tape(n0), v.eye, &v.camera, W, H, &v.opts)
    };
    assert!(hits(&reference) > (W * H) as usize / 2);
    for k in [20, 31] {
        let v = corner_view(k);
        let tape = menger_tape(n0 + (k - k0) as u32);
        let zoomed = deep_depths(&tape, v.eye, &v.camera, W, H, &v.opts);
        let iou = silhouette_iou(&zoomed, &reference);
        let s = 3f64.powi(k - k0);
        let (within, worst, both) = depth_agreement(&zoomed, s, &reference, 1e-6);
        eprintln!(
            "dd 3^{k}: IoU {iou:.4}, depths x 3^{} within 1e-6 on {within:.4} of {both} (worst {worst:.1e})",
            k - k0
        );
        assert!(iou >= 0.99, "3^{k}: IoU {iou}");
        assert_eq!(
            within, 1.0,
            "3^{k}: depths agree on {within} only (worst {worst})"
        );
        // The same march in f64 from the rounded eye, and the ordinary tracer (its f64 path).
        let march64 = f64_depths(&tape, v.eye64, &v.camera64, W, H, &v.opts);
        let iou64 = silhouette_iou(&march64, &reference);
        let (within64, worst64, both64) = depth_agreement(&march64, s, &reference, 1e-6);
        let traced = tracer_depths(&scenes::menger(n0 + (k - k0) as u32), &v.camera64);
        let iou_t = silhouette_iou(&traced, &reference);
        let (within_t, _, both_t) = depth_agreement(&traced, s, &reference, 1e-2);
        eprintln!(
            "f64 3^{k}: march IoU {iou64:.4}, depths within 1e-6 on {within64:.4} of {both64} (worst {worst64:.1e}); \
             tracer IoU {iou_t:.4}, depths within 1e-2 on {within_t:.4} of {both_t}"
        );
        if k == 31 {
            assert!(
                within64 < 0.5,
                "f64 march at 3^31 agrees on {within64} of its depths"
            );
            assert!(
                iou_t < 0.99 || within_t < 0.5,
                "the ordinary tracer at 3^31 agrees (IoU {iou_t}, depths {within_t})"
            );
        }
    }
    // The path's own first view (k = 0) is not self-similar to the deep ones where its rays
    // leave the sponge's cube (see above); reported, not asserted.
    let v = corner_view(0);
    let top = deep_depths(
        &menger_tape(n0 - k0 as u32),
        v.eye,
        &v.camera,
        W,
        H,
        &v.opts,
    );
    eprintln!(
        "k = 0 against k = {k0}: IoU {:.4}",
        silhouette_iou(&top, &reference)
    );
}

#[test]
fn mandelbulb_zoom_frames_find_the_target_at_any_depth() {
    // The mandelbulb path (target refined in double-double) at 1e12, where f64 still resolves
    // the view, and at 1e15 and 1e18, where it cannot. An odd image has a pixel on the centre
    // ray, which runs through the target: its depth must be the eye's distance from the target
    // (to within the hit rule's half footprint, a few per cent of it). With the f64 target
    // alone (no tail) the surface is ~1e-16 away, a hundred eye distances at 1e18.
    let (w, h) = (49, 37);
    let centre = (h / 2 * w + w / 2) as usize;
    let pp = path_preset("mandelbulb").unwrap();
    let tape = Tape::compile(&pp.scene).unwrap();
    let CameraPath::Zoom {
        target, dir, start, ..
    } = pp.path
    else {
        panic!()
    };
    let tailless = CameraPath::zoom(target, dir, start);
    for depth in [1e12, 1e15, 1e18] {
        let dist = start / depth;
        let opts = DeepOptions::for_scale(dist);
        let (_, cam) = pp.path.deep_camera(1, 2, depth, pp.fov).unwrap();
        let deep = zoom_frame_depths(&tape, &pp.path, 1, 2, depth, pp.fov, w, h).unwrap();
        let t = deep[centre].expect("the centre ray misses");
        // The tail-less eye only where it is asserted on.
        let (eye0, _) = tailless.deep_camera(1, 2, depth, pp.fov).unwrap();
        let t0 = (depth == 1e18).then(|| deep_depths(&tape, eye0, &cam, w, h, &opts)[centre]);
        let cam64 = pp.camera(1, 2, depth);
        // The f64 march from the f64 camera: silhouette IoU, and the fraction of depths
        // within 1e-2 (the view is full of surface, so the IoU alone says little).
        let f64_view = (cam64.validate().is_ok()).then(|| {
            let m = f64_depths(&tape, cam64.eye, &cam64, w, h, &opts);
            (
                silhouette_iou(&deep, &m),
                depth_agreement(&m, 1.0, &deep, 1e-2).0,
            )
        });
        eprintln!(
            "mandelbulb zoom {depth:e}: {} of {} pixels hit; centre depth {:.4} eye distances \
             (without the tail: {:?}); f64 march (IoU, depths within 1e-2): {f64_view:?}",
            hits(&deep),
            w * h,
            t / dist,
            t0.flatten().map(|t0| t0 / dist)
        );
        let iou64 = f64_view.map(|v| v.0);
        assert!(
            (t / dist - 1.0).abs() < 0.05,
            "zoom {depth:e}: centre depth {}",
            t / dist
        );
        match depth {
            1e12 => assert!(
                f64_view.is_some_and(|(iou, within)| iou >= 0.99 && within >= 0.9),
                "f64 at 1e12: {f64_view:?}"
            ),
            // The f64 eye is off by 1.3 % of its distance and the surface is only resolved to
            // an ulp: most depths differ by more than 1 %.
            1e15 => assert!(
                f64_view.is_some_and(|(_, within)| within < 0.5),
                "f64 at 1e15: {f64_view:?}"
            ),
            1e18 => {
                assert!(iou64.is_none(), "the f64 camera still works at 1e18");
                assert!(
                    t0.unwrap().is_none_or(|t0| (t0 / dist - 1.0).abs() > 0.5),
                    "the f64 target alone finds the surface at 1e18"
                );
            }
            _ => {}
        }
    }
}

/// Display value (tonemapped, sRGB-encoded, 0..1) of a linear channel, as the comparisons see it.
fn display(x: f32) -> f64 {
    crate::post::srgb(crate::post::tonemap(x)) as f64
}

/// Silhouette IoU of two frames, and over the pixels both hit the mean display-colour
/// difference per channel and the largest.
fn frame_agreement(a: &Frame, b: &Frame) -> (f64, f64, f64) {
    let (mut inter, mut union, mut sum, mut worst) = (0usize, 0usize, 0.0, 0.0f64);
    for i in 0..a.len() {
        let (ha, hb) = (a.depth[i].is_finite(), b.depth[i].is_finite());
        union += (ha || hb) as usize;
        if ha && hb {
            inter += 1;
            let d: [f64; 3] =
                std::array::from_fn(|k| (display(a.colour[i][k]) - display(b.colour[i][k])).abs());
            sum += d.iter().sum::<f64>() / 3.0;
            worst = worst.max(d.iter().cloned().fold(0.0, f64::max));
        }
    }
    let iou = if union == 0 {
        1.0
    } else {
        inter as f64 / union as f64
    };
    (iou, sum / inter.max(1) as f64, worst)
}

/// Over all pixels (sky included), the mean display-colour difference per channel.
fn mean_colour_difference(a: &Frame, b: &Frame) -> f64 {
    let s: f64 = (0..a.len())
        .map(|i| {
            (0..3)
                .map(|k| (display(a.colour[i][k]) - display(b.colour[i][k])).abs())
                .sum::<f64>()
                / 3.0
        })
        .sum();
    s / a.len() as f64
}

#[test]
fn shallow_shaded_frames_match_the_ordinary_tracer() {
    // The shaded reference at the presets' own cameras against the ordinary tracer's frame
    // (f32 packets, its defaults: prepass, enhanced steps, soft shadows as the scene says).
    // The two marches stop at slightly different points of the same pixel (the tracer's
    // over-relaxed steps against half-footprint steps: depths differ by up to ~5 %), so
    // normals taken one footprint wide differ a little where the surface is rough.
    let mut results = Vec::new();
    for name in ["menger", "mandelbulb"] {
        let scene = presets::load(name).unwrap();
        let cam = scene.camera.clone();
        let tape = Tape::compile(&scene).unwrap();
        let scale = (cam.target - cam.eye).length();
        let opts = DeepOptions::for_scale(scale);
        let deep = deep_frame(&tape, &scene, eye_of(&cam), &cam, scale, W, H, &opts, 0.0);
        let tracer_opts = Options {
            width: W,
            height: H,
            ..Options::default()
        };
        let (ordinary, _) =
            render_tape(&tape, &scene, &cam, &tracer_opts, None, Hooks::NONE).unwrap();
        let (iou, hit_err, worst) = frame_agreement(&deep, &ordinary);
        let all_err = mean_colour_difference(&deep, &ordinary);
        eprintln!(
            "{name} shaded: IoU {iou:.4}; colour difference over common hits mean {hit_err:.4} (worst channel {worst:.3}), over all pixels {all_err:.4}"
        );
        results.push((name, iou, hit_err, all_err));
    }
    for (name, iou, hit_err, all_err) in results {
        assert!(iou >= 0.99, "{name}: IoU {iou}");
        assert!(
            hit_err < 0.02,
            "{name}: mean colour difference {hit_err} over hits"
        );
        assert!(all_err < 0.01, "{name}: mean colour difference {all_err}");
    }
}

#[test]
fn menger_corner_shaded_frames_are_self_similar() {
    // The corner views of `menger_corner_zooms_are_self_similar_in_dd_only` at 3^5 and 3^26,
    // shaded (soft shadows off, as the zoom's reference has them: a shadow ray's reach is the
    // scene's max distance, not a multiple of the view, so shadows are not self-similar).
    // Normals, AO, lights, orbit-trap palette and sky are. Before the shading's length floor
    // scaled with the view (`Shading::min_length`), the 3^26 view's normals were taken 1e-12
    // wide, a hundred pixels: mean colour difference 0.078.
    let (n0, k0, k) = (10u32, 5i32, 26i32);
    let shade = |k: i32| {
        let v = corner_view(k);
        let mut scene = scenes::menger(n0 + (k - k0) as u32);
        for l in &mut scene.lights {
            l.shadows = false;
        }
        let tape = Tape::compile(&scene).unwrap();
        let scale = v.opts.near * 100.0;
        deep_frame(&tape, &scene, v.eye, &v.camera, scale, W, H, &v.opts, 0.0)
    };
    let (reference, zoomed) = (shade(k0), shade(k));
    let (iou, hit_err, worst) = frame_agreement(&zoomed, &reference);
    let all_err = mean_colour_difference(&zoomed, &reference);
    eprintln!(
        "menger corner 3^{k} against 3^{k0} shaded: IoU {iou:.4}; colour difference over common hits mean {hit_err:.2e} (worst channel {worst:.2e}), over all pixels {all_err:.2e}"
    );
    let hit_px = reference.depth.iter().filter(|d| d.is_finite()).count();
    assert!(hit_px > (W * H) as usize / 2, "{hit_px} hits");
    assert!(iou >= 0.99, "IoU {iou}");
    assert!(hit_err < 0.01, "mean colour difference {hit_err}");
    assert!(worst < 0.05, "worst channel difference {worst}");
}

#[test]
fn sub_pixel_rays_are_the_centres_of_a_finer_image_s_pixels() {
    // Pixel (x, y)'s n x n rays at W x H are pixels (n x + i, n y + j) of an nW x nH image.
    let cam = presets::load("menger").unwrap().camera;
    let frame = cam.frame();
    for n in 1..=MAX_PIXEL_SAMPLES {
        for (x, y) in [(0, 0), (7, 3), (W - 1, H - 1)] {
            let rays: Vec<DVec3> = pixel_rays(&frame, x, y, W, H, n).collect();
            assert_eq!(rays.len(), (n * n) as usize);
            for (k, r) in rays.iter().enumerate() {
                let (i, j) = (k as u32 % n, k as u32 / n);
                let fine = frame.ray_dir(
                    (n * x + i) as f64 + 0.5,
                    (n * y + j) as f64 + 0.5,
                    n * W,
                    n * H,
                );
                assert!((*r - fine).length() < 1e-15, "n {n} pixel {x},{y} ray {k}");
            }
        }
    }
}

#[test]
fn a_pixel_of_two_by_two_rays_is_the_mean_of_the_four_pixels_they_sample() {
    // A unit sphere from the menger preset's camera: each pixel of a W/2 x H/2 frame with 2x2
    // rays, against the 2x2 block of a W x H frame of one ray a pixel marched with the same
    // absolute footprint (footprints doubled for the half-size pixels), so both cast the same
    // rays and stop them at the same points. Hits: at least two of the four, at the nearest
    // depth. Colours: the block's mean, up to the shading's normals, which are taken over a
    // pixel's footprint (twice as wide in the W/2 frame; the sphere is smooth, so this moves
    // them little), and well inside the difference one ray a pixel makes at the silhouette
    // (0.0014 against 0.0120 when written).
    let mut scene = scenes::sphere(1.0);
    scene.camera = presets::load("menger").unwrap().camera;
    let cam = scene.camera.clone();
    let tape = Tape::compile(&scene).unwrap();
    let scale = (cam.target - cam.eye).length();
    let base = DeepOptions::for_scale(scale);
    let (w, h) = (W / 2, H / 2);
    let eye = eye_of(&cam);
    let coarse = DeepOptions {
        pixel_samples: 2,
        ..base
    };
    let fine = DeepOptions {
        step_footprints: 2.0 * base.step_footprints,
        hit_footprints: 2.0 * base.hit_footprints,
        ..base
    };
    let a = deep_frame(&tape, &scene, eye, &cam, scale, w, h, &coarse, 0.0);
    let b = deep_frame(&tape, &scene, eye, &cam, scale, W, H, &fine, 0.0);
    let one = deep_frame(&tape, &scene, eye, &cam, scale, w, h, &base, 0.0);
    let (mut err, mut err_one, mut partial) = (0.0, 0.0, 0);
    for y in 0..h {
        for x in 0..w {
            let block: Vec<usize> = (0..4)
                .map(|k| b.index(2 * x + k % 2, 2 * y + k / 2))
                .collect();
            let hits: Vec<f32> = block
                .iter()
                .map(|&i| b.depth[i])
                .filter(|d| d.is_finite())
                .collect();
            partial += (1..4).contains(&hits.len()) as usize;
            let i = a.index(x, y);
            let near = hits.iter().cloned().fold(f32::INFINITY, f32::min);
            let want = if hits.len() >= 2 { near } else { f32::INFINITY };
            assert!(
                a.depth[i] == want || (a.depth[i] - want).abs() <= 1e-6 * want,
                "pixel {x},{y}: depth {} against the block's {want}",
                a.depth[i]
            );
            for c in 0..3 {
                let mean = block.iter().map(|&j| b.colour[j][c]).sum::<f32>() / 4.0;
                err += (a.colour[i][c] - mean).abs() as f64;
                err_one += (one.colour[i][c] - mean).abs() as f64;
            }
        }
    }
    let n = (w * h * 3) as f64;
    let (err, err_one) = (err / n, err_one / n);
    eprintln!(
        "2x2 rays against the block mean: mean colour difference {err:.5}; one ray {err_one:.5}; {partial} of {} pixels partly covered",
        w * h
    );
    assert!(
        partial > 0,
        "no pixel is partly covered: the test shows nothing"
    );
    assert!(
        err < 0.2 * err_one,
        "2x2 rays {err} against one ray {err_one}"
    );
}
