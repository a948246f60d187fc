//! The tracer's stereo renders: per-eye views from the shifted eyes, laid out by
//! [`fathom_image::stereo`]; the disparity and seams of omni-directional stereo; refusal of
//! bad stereo options.

use crate::{Options, render};
use fathom_core::frame::Frame;
use fathom_core::primitives::Primitive;
use fathom_core::scene::{Call, DomainOp, Node, Shape};
use fathom_core::transforms::Transform;
use fathom_core::{Projection, Scene};
use fathom_image::post::to_rgb8;

fn draw(scene: &Scene, w: u32, h: u32, projection: Projection) -> Frame {
    let o = Options {
        width: w,
        height: h,
        projection,
        ..Options::default()
    };
    render(scene, &o, &|_, _| {}).unwrap().0
}

/// A small sphere of radius `r` at distance `dist` straight ahead of a camera at the origin.
fn sphere_ahead(r: f64, dist: f64) -> Scene {
    let mut n = Node::new(Call {
        kind: Shape::Primitive(Primitive::Sphere),
        params: vec![r],
    });
    n.ops.push(Call {
        kind: DomainOp::Transform(Transform::Translate),
        params: vec![0.0, 0.0, -dist],
    });
    let mut s = Scene::new(n);
    s.camera.eye = glam::DVec3::ZERO;
    s.camera.target = glam::DVec3::new(0.0, 0.0, -1.0);
    s.camera.up = glam::DVec3::Y;
    s.render.max_distance = 50.0;
    s
}

/// Mean column (in pixels, centres at +0.5) of the hits in rows [y0, y0 + h).
fn hit_centroid_x(f: &Frame, y0: u32, h: u32) -> f64 {
    let (mut sum, mut n) = (0.0, 0.0);
    for y in y0..y0 + h {
        for x in 0..f.width {
            if f.is_hit(f.index(x, y)) {
                sum += x as f64 + 0.5;
                n += 1.0;
            }
        }
    }
    assert!(n > 0.0, "no hits in the view");
    sum / n
}

#[test]
fn ods_eyes_see_a_point_ahead_with_the_disparity_of_the_viewing_circle() {
    // A sphere 1.5 ahead seen by eyes 0.4 apart: disparity 2 asin(0.2 / 1.5) = 15.3
    // degrees, 43.6 columns of a 1024-wide panorama. The sphere is small and the disparity
    // is measured between hit centroids, which follow its centre to a fraction of a pixel.
    let (sep, dist) = (0.4, 1.5);
    let scene = sphere_ahead(0.1, dist);
    let (w, h) = (1024u32, 512u32);
    let f = draw(
        &scene,
        w,
        h,
        Projection::Ods {
            eye_separation: sep,
        },
    );
    assert_eq!((f.width, f.height), (w, 2 * h));
    let left = hit_centroid_x(&f, 0, h);
    let right = hit_centroid_x(&f, h, h);
    let got = (left - right) / w as f64 * std::f64::consts::TAU;
    let want = 2.0 * (sep / (2.0 * dist)).asin();
    eprintln!(
        "ODS disparity {:.4} deg, expected {:.4} deg",
        got.to_degrees(),
        want.to_degrees()
    );
    assert!(
        (got - want).abs() < 0.01 * want,
        "disparity {:.3} deg, expected {:.3} deg",
        got.to_degrees(),
        want.to_degrees()
    );
    // The left eye sees the point to the right of straight ahead, the right eye to the left.
    assert!(left > w as f64 / 2.0 && right < w as f64 / 2.0);
}

#[test]
fn ods_seams_match_the_left_and_right_edges_continue_each_other() {
    let scene = fathom_core::scenes::ring_over_floor();
    let (w, h) = (256u32, 128u32);
    let f = draw(
        &scene,
        w,
        h,
        Projection::Ods {
            eye_separation: 0.065,
        },
    );
    let rgb = to_rgb8(&f);
    let diff = |a: usize, b: usize| -> f64 {
        (0..3)
            .map(|c| (rgb[3 * a + c] as f64 - rgb[3 * b + c] as f64).abs())
            .sum::<f64>()
    };
    for eye in 0..2 {
        let rows = (eye * h)..(eye * h + h);
        let seam = rows
            .clone()
            .map(|y| diff(f.index(w - 1, y), f.index(0, y)))
            .sum::<f64>()
            / h as f64;
        let mut inner = 0.0;
        for x in 0..w - 1 {
            inner += rows
                .clone()
                .map(|y| diff(f.index(x, y), f.index(x + 1, y)))
                .sum::<f64>();
        }
        inner /= ((w - 1) * h) as f64;
        assert!(
            seam <= 2.0 * inner + 1.0,
            "eye {eye}: mean difference across the seam {seam:.2}, between columns {inner:.2}"
        );
        // Depth continues too: the last and first columns see the same surfaces.
        let mut flips = 0;
        let mut depth_jumps = 0;
        for y in rows {
            let (a, b) = (f.index(w - 1, y), f.index(0, y));
            if f.is_hit(a) != f.is_hit(b) {
                flips += 1;
            } else if f.is_hit(a) {
                let (da, db) = (f.depth[a] as f64, f.depth[b] as f64);
                // Neighbouring columns 1.4 degrees apart: depth may change by the
                // surface's slope, not jump.
                if (da - db).abs() > 0.1 * da.max(db) {
                    depth_jumps += 1;
                }
            }
        }
        assert!(
            flips <= 2,
            "eye {eye}: {flips} rows change hit/miss at the seam"
        );
        assert!(
            depth_jumps <= 2,
            "eye {eye}: {depth_jumps} rows jump in depth"
        );
    }
}

#[test]
fn side_by_side_equals_mono_renders_from_the_shifted_eyes() {
    let mut scene = fathom_core::presets::load("menger").unwrap();
    scene.camera.eye = glam::DVec3::new(0.4, 0.5, 2.6);
    let sep = 0.3;
    let (w, h) = (64u32, 48u32);
    let pair = draw(
        &scene,
        w,
        h,
        Projection::SideBySide {
            eye_separation: sep,
        },
    );
    let right = scene.camera.frame().right;
    for (eye, side) in [(0u32, -0.5), (1, 0.5)] {
        let mut s = scene.clone();
        s.camera.eye += right * (side * sep);
        s.camera.target += right * (side * sep);
        let mono = draw(&s, w, h, Projection::Mono);
        let mut differ = 0;
        for y in 0..h {
            for x in 0..w {
                let (a, b) = (mono.index(x, y), pair.index(eye * w + x, y));
                if mono.colour[a] != pair.colour[b] || mono.depth[a] != pair.depth[b] {
                    differ += 1;
                }
            }
        }
        assert_eq!(
            differ, 0,
            "eye {eye}: {differ} pixels differ from the mono render"
        );
    }
    // And the eyes do see different images.
    let hits = (0..pair.len()).filter(|&i| pair.is_hit(i)).count();
    let apart = (0..h)
        .flat_map(|y| (0..w).map(move |x| (x, y)))
        .filter(|&(x, y)| pair.depth[pair.index(x, y)] != pair.depth[pair.index(w + x, y)])
        .count();
    assert!(
        hits > 100 && apart > 100,
        "{hits} hits, {apart} pixels differ between the eyes"
    );
}

#[test]
fn bad_stereo_options_are_refused_before_rendering() {
    let scene = fathom_core::scenes::ring_over_floor();
    for sep in [-1.0, f64::NAN, f64::INFINITY] {
        let o = Options {
            width: 8,
            height: 4,
            projection: Projection::Ods {
                eye_separation: sep,
            },
            ..Options::default()
        };
        let e = render(&scene, &o, &|_, _| {}).unwrap_err().to_string();
        assert!(e.contains("eye separation"), "{e}");
    }
    // A size whose doubled output would overflow u32 is refused, not wrapped.
    for projection in [
        Projection::SideBySide {
            eye_separation: 0.1,
        },
        Projection::Ods {
            eye_separation: 0.1,
        },
    ] {
        let o = Options {
            width: 1 << 31,
            height: 1 << 31,
            projection,
            ..Options::default()
        };
        let e = render(&scene, &o, &|_, _| {}).unwrap_err().to_string();
        assert!(e.contains("limit"), "{e}");
    }
    // The output size counts: two 16384-wide views side by side exceed the limit.
    let o = Options {
        width: 16384,
        height: 4,
        projection: Projection::SideBySide {
            eye_separation: 0.1,
        },
        ..Options::default()
    };
    let e = render(&scene, &o, &|_, _| {}).unwrap_err();
    assert!(
        matches!(
            e,
            crate::TraceError::Options(crate::OptionsError::StereoTooLarge { .. })
        ),
        "{e}"
    );
    let e = e.to_string();
    assert!(e.contains("32768x4") && e.contains("limit"), "{e}");
}
