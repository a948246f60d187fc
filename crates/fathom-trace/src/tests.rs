//! End-to-end checks of the tracer: golden masks and images, analytic depth, agreement of the
//! enhanced tracer and the prepass with basic tracing, determinism across thread counts.

use crate::render::{MAX_PIXELS, MAX_SIDE};
use crate::{Method, Options, post, render};
use fathom_core::frame::Frame;
use fathom_core::presets::{self, PRESETS};
use fathom_core::primitives::Primitive;
use fathom_core::transforms::Transform;
use fathom_core::{Node, Scene};

fn opts(w: u32, h: u32, method: Method, prepass: bool, geometry_only: bool) -> Options {
    Options {
        width: w,
        height: h,
        method,
        prepass,
        geometry_only,
        ..Options::default()
    }
}

fn draw(scene: &Scene, o: &Options) -> Frame {
    render(scene, o, &|_, _| {}).unwrap().0
}

/// '#' where a ray hit, '.' elsewhere, one line per row.
fn ascii(f: &Frame) -> String {
    let mut s = String::new();
    for y in 0..f.height {
        for x in 0..f.width {
            s.push(if f.is_hit(f.index(x, y)) { '#' } else { '.' });
        }
        s.push('\n');
    }
    s
}

/// Compares masks, allowing `slack` differing pixels, and prints both side by side otherwise.
fn check_mask(got: &str, want: &str, slack: usize) {
    let want: String = want
        .lines()
        .map(str::trim)
        .filter(|l| !l.is_empty())
        .map(|l| format!("{l}\n"))
        .collect();
    let diff = got
        .chars()
        .zip(want.chars())
        .filter(|(a, b)| a != b)
        .count();
    if got.len() != want.len() || diff > slack {
        let mut msg = String::from("got | want\n");
        let mut wl = want.lines();
        for a in got.lines() {
            let b = wl.next().unwrap_or("");
            msg += &format!("{a} | {b}{}\n", if a != b { "  <" } else { "" });
        }
        panic!("{diff} pixels differ (allowed {slack}):\n{msg}");
    }
}

fn sphere_and_box() -> Scene {
    let mut s = Scene::new(
        Node::new(Primitive::Sphere).child(Node::new(Primitive::Box).op(Transform::Translate)),
    );
    // Place the box to the right and slightly up.
    let b = &mut s.root.children[0];
    b.ops[0].set("offset", &[1.6, 0.4, 0.0]).unwrap();
    b.shape.set("size", &[0.45, 0.45, 0.45]).unwrap();
    s.camera.eye = glam::DVec3::new(0.5, 0.5, 5.0);
    s.camera.target = glam::DVec3::new(0.5, 0.0, 0.0);
    s
}

#[test]
fn golden_mask_sphere_and_box() {
    let f = draw(
        &sphere_and_box(),
        &opts(32, 20, Method::Enhanced, true, true),
    );
    check_mask(&ascii(&f), GOLDEN_SPHERE_BOX, 0);
}

#[test]
fn golden_mask_default_preset() {
    let s = presets::load(presets::DEFAULT_PRESET).unwrap();
    let f = draw(&s, &opts(32, 24, Method::Enhanced, true, true));
    check_mask(&ascii(&f), GOLDEN_BULB, 3);
}

#[test]
fn golden_mask_menger() {
    let s = presets::load("menger").unwrap();
    let f = draw(&s, &opts(32, 24, Method::Enhanced, true, true));
    check_mask(&ascii(&f), GOLDEN_MENGER, 3);
}

#[test]
fn sphere_depth_matches_the_analytic_depth_within_the_hit_epsilon() {
    let mut s = Scene::new(Node::new(Primitive::Sphere));
    s.camera.eye = glam::DVec3::new(0.3, 0.8, 3.5);
    s.camera.target = glam::DVec3::ZERO;
    for (method, prepass) in [(Method::Basic, false), (Method::Enhanced, true)] {
        let (w, h) = (48u32, 36u32);
        let f = draw(&s, &opts(w, h, method, prepass, true));
        let cam = s.camera.frame();
        let pixel_angle = cam.pixel_angle(h);
        let mut hits = 0;
        for y in 0..h {
            for x in 0..w {
                let d = cam.ray_dir(x as f64 + 0.5, y as f64 + 0.5, w, h);
                let o = cam.eye;
                let b = o.dot(d);
                let disc = b * b - (o.length_squared() - 1.0);
                let got = f.depth[f.index(x, y)] as f64;
                // The tracer stops once d < eps(t) = 0.5 * pixel_angle * t (pixel_epsilon 1), so
                // wherever it stops the point lies within eps(t) outside the sphere: rays that
                // graze the silhouette within that distance count as hits.
                if got.is_finite() {
                    let r = (o + d * got).length() - 1.0;
                    let eps = 0.5 * pixel_angle * got;
                    assert!(
                        r >= -1e-5 && r <= eps * 1.01 + 1e-6,
                        "({x},{y}) {method:?}: stopped {r} from the sphere, eps {eps}"
                    );
                }
                if disc < 0.0 {
                    let closest = (o.length_squared() - b * b).max(0.0).sqrt() - 1.0;
                    assert!(
                        got.is_infinite() || closest <= 0.5 * pixel_angle * got * 1.01,
                        "({x},{y}) should miss, depth {got}, passes {closest} from the sphere"
                    );
                    continue;
                }
                let t = -b - disc.sqrt();
                // Away from the silhouette, the depth is the analytic one within eps / cos(i).
                let cos_i = -(o + d * t).normalize().dot(d);
                let eps = 0.5 * pixel_angle * t / cos_i.max(0.05) + 1e-5 * t;
                assert!(
                    got.is_finite() && got <= t + 1e-5 * t && (cos_i < 0.2 || t - got <= eps),
                    "({x},{y}) {method:?}: depth {got}, analytic {t}, eps {eps}"
                );
                hits += 1;
            }
        }
        assert!(hits > 200, "{hits}");
    }
}

#[test]
fn enhanced_and_prepass_change_few_hit_decisions_on_every_preset() {
    for p in PRESETS {
        let s = presets::load(p.name).unwrap();
        let (w, h) = (80, 60);
        let base = draw(&s, &opts(w, h, Method::Basic, false, true));
        for (m, pre) in [
            (Method::Enhanced, false),
            (Method::Basic, true),
            (Method::Enhanced, true),
        ] {
            let f = draw(&s, &opts(w, h, m, pre, true));
            let diff = (0..f.len())
                .filter(|&i| f.is_hit(i) != base.is_hit(i))
                .count();
            let pct = 100.0 * diff as f64 / f.len() as f64;
            assert!(
                pct <= 0.5,
                "{}: {m:?} prepass={pre} changes {diff} pixels ({pct:.2}%)",
                p.name
            );
        }
    }
}

#[test]
fn one_and_two_threads_give_identical_pngs() {
    let s = presets::load(presets::DEFAULT_PRESET).unwrap();
    let o = opts(40, 30, Method::Enhanced, true, false);
    let png = |threads| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        let f = pool.install(|| draw(&s, &o));
        post::to_rgb8(&f)
    };
    let a = png(1);
    assert!(a.iter().any(|&v| v > 0));
    assert_eq!(a, png(2));
}

#[test]
fn small_png_matches_the_golden_image_within_tolerance() {
    let s = presets::load(presets::DEFAULT_PRESET).unwrap();
    let f = draw(&s, &opts(48, 36, Method::Enhanced, true, false));
    let got = post::to_rgb8(&f);
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/tests/golden/mandelbulb_48x36.png"
    );
    if std::env::var_os("FATHOM_BLESS").is_some() {
        image::save_buffer(path, &got, 48, 36, image::ColorType::Rgb8).unwrap();
    }
    let want = image::open(path).unwrap().to_rgb8().into_raw();
    assert_eq!(want.len(), got.len());
    let diffs: Vec<i32> = got
        .iter()
        .zip(&want)
        .map(|(&a, &b)| (a as i32 - b as i32).abs())
        .collect();
    let mean = diffs.iter().sum::<i32>() as f64 / diffs.len() as f64;
    let big = diffs.iter().filter(|&&d| d > 24).count();
    // Tolerance: mean channel error under 1 level of 255, and at most 1% of channels off by
    // more than 24 levels (silhouette pixels that flip).
    assert!(
        mean < 1.0 && big * 100 <= diffs.len(),
        "mean {mean:.3}, {big} channels off by > 24"
    );
}

#[test]
fn sizes_and_sample_counts_are_checked_before_allocating() {
    let ok = Options::default();
    assert!(ok.validate().is_ok());
    for (w, h, ss) in [
        (0, 10, 1),
        (MAX_SIDE + 1, 10, 1),
        (16384, 16384, 1),
        (640, 480, 0),
        (640, 480, 9),
    ] {
        let o = Options {
            width: w,
            height: h,
            supersample: ss,
            ..Options::default()
        };
        assert!(o.validate().is_err(), "{w}x{h} ss {ss}");
    }
    let o = Options {
        width: 8192,
        height: 8192,
        supersample: 1,
        ..Options::default()
    };
    assert!(8192u64 * 8192 <= MAX_PIXELS && o.validate().is_ok());
    let o = Options {
        ssao: f32::NAN,
        ..Options::default()
    };
    assert!(o.validate().is_err());
}

#[test]
fn supersampled_frames_have_the_requested_size_and_finite_pixels() {
    let s = sphere_and_box();
    let o = Options {
        supersample: 2,
        ssao: 1.0,
        ..opts(20, 12, Method::Enhanced, true, false)
    };
    let f = draw(&s, &o);
    assert_eq!((f.width, f.height, f.len()), (20, 12, 240));
    assert!(f.colour.iter().flatten().all(|v| v.is_finite()));
}

const GOLDEN_SPHERE_BOX: &str = "
    ................................
    ................................
    ................................
    ................................
    ................................
    ..........#######..######.......
    .........################.......
    .........################.......
    ........#################.......
    ........#################.......
    ........#################.......
    ........###########.............
    .........#########..............
    .........#########..............
    ..........#######...............
    ................................
    ................................
    ................................
    ................................
    ................................
";

const GOLDEN_BULB: &str = "
    ............########............
    ..........############..........
    ..........#############.........
    .........##############.........
    .........###############........
    ......###################.......
    ......####################......
    ......####################......
    .....######################.....
    .....######################.....
    ....#######################.....
    .....######################.....
    .....#####################......
    ......#####################.....
    ......#####################.....
    ......#####################.....
    ......####################......
    .......#################........
    .......#################........
    ........###############.........
    ..........############..........
    ...........###########..........
    .............#####..............
    ................................
";

const GOLDEN_MENGER: &str = "
    ................................
    ................................
    ..........############..........
    .....#######################....
    ...#########################....
    ...#########################....
    ...########################.....
    ....#######################.....
    ....#######################.....
    ....#######################.....
    ....#######################.....
    ....#######################.....
    ....######################......
    .....#####################......
    .....#####################......
    .....#####################......
    .....#####################......
    .....#####################......
    .....####################.......
    ......##################........
    ........###############.........
    ..........############..........
    ...........##########...........
    .............#######............
";

/// The `k`-th of `n` nearly equal parts of `0..len` (the last takes the rest).
fn part(len: u32, n: u32, k: u32) -> (u32, u32) {
    let a = len * k / n;
    let b = len * (k + 1) / n;
    (a, b - a)
}

#[test]
fn regions_are_bit_identical_to_the_whole_image() {
    // A 3x3 grid of uneven regions (not tile- or block-aligned), with SSAO (whose reach crosses
    // region borders), supersampling and the prepass (whose cells straddle them), mono and
    // side by side (regions that straddle the two eyes), on a fractal and a tree scene.
    use crate::render_tape;
    use fathom_core::frame::Rect;
    use fathom_core::{Projection, Tape};
    for name in ["menger", "model-tree"] {
        let scene = presets::load(name).unwrap();
        let tape = Tape::compile(&scene).unwrap();
        for projection in [
            Projection::Mono,
            Projection::SideBySide {
                eye_separation: 0.1,
            },
        ] {
            let o = Options {
                width: 45,
                height: 29,
                supersample: 2,
                ssao: 1.5,
                projection,
                ..Options::default()
            };
            let hooks = crate::Hooks::NONE;
            let (whole, _) = render_tape(&tape, &scene, &scene.camera, &o, None, hooks).unwrap();
            assert!(
                whole.depth.iter().any(|d| d.is_finite()),
                "{name}: nothing in view"
            );
            let (ow, oh) = o.output_size();
            for j in 0..3 {
                for i in 0..3 {
                    let (x, width) = part(ow, 3, i);
                    let (y, height) = part(oh, 3, j);
                    let r = Rect {
                        x,
                        y,
                        width,
                        height,
                    };
                    let (got, s) =
                        render_tape(&tape, &scene, &scene.camera, &o, Some(r), hooks).unwrap();
                    assert_eq!((s.width, s.height), (width, height));
                    assert!(
                        got == whole.crop(r),
                        "{name} {projection:?}: region {r:?} differs from the whole image"
                    );
                }
            }
        }
    }
}
