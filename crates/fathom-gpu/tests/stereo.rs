//! Stereo on the GPU: side-by-side views differ by the parallax a pinhole pair predicts, the
//! omni-directional stereo (ODS) frame wraps around without a seam, and an ODS frame of a
//! preset matches the CPU tracer's.

mod common;

use common::{COLOUR_TOL, compare, renderer};
use fathom_core::Scene;
use fathom_core::frame::Frame;
use fathom_core::primitives::Primitive;
use fathom_core::scene::{Call, Node, Shape};
use fathom_gpu::{Projection, RenderOptions};
use fathom_trace::post::to_rgb8;

/// Mean x of the hit pixels in columns [x0, x0 + w) of `f`.
fn hit_centroid_x(f: &Frame, x0: u32, w: u32) -> f64 {
    let (mut sum, mut n) = (0.0, 0.0);
    for y in 0..f.height {
        for x in x0..x0 + w {
            if f.is_hit(f.index(x, y)) {
                sum += (x - x0) as f64 + 0.5;
                n += 1.0;
            }
        }
    }
    assert!(n > 0.0, "no hits in the view");
    sum / n
}

#[test]
fn side_by_side_views_differ_by_the_expected_parallax() {
    let mut r = renderer();
    // A small sphere straight ahead at distance 4: its image is nearly a disc centred on the
    // projection of its centre.
    let mut scene = Scene::new(Node::new(Call {
        kind: Shape::Primitive(Primitive::Sphere),
        params: vec![0.3],
    }));
    scene.camera.eye = glam::DVec3::new(0.0, 0.0, 4.0);
    scene.camera.target = glam::DVec3::ZERO;
    let (w, h) = (160u32, 120u32);
    let sep = 0.2;
    let o = RenderOptions {
        width: w,
        height: h,
        projection: Projection::SideBySide {
            eye_separation: sep,
        },
        prepass: true,
        fog: true,
    };
    let (f, _) = r.render_scene(&scene, &o).unwrap();
    assert_eq!((f.width, f.height), (2 * w, h));
    let left = hit_centroid_x(&f, 0, w);
    let right = hit_centroid_x(&f, w, w);
    // Parallel cameras: disparity = focal length in pixels * separation / depth.
    let focal = h as f64 / (2.0 * (scene.camera.fov.to_radians() / 2.0).tan());
    let want = focal * sep / 4.0;
    let got = left - right;
    assert!(
        (got - want).abs() < 0.05 * want,
        "disparity {got:.2} px, expected {want:.2} px"
    );
    // And each view is centred on the sphere's shifted projection, not just offset.
    assert!((left - (w as f64 / 2.0 + want / 2.0)).abs() < 0.05 * want + 0.5);
}

#[test]
fn ods_frame_wraps_around_without_a_seam() {
    let mut r = renderer();
    let scene = fathom_core::scenes::ring_over_floor();
    let (w, h) = (256u32, 128u32);
    let o = RenderOptions {
        width: w,
        height: h,
        projection: Projection::Ods {
            eye_separation: 0.065,
        },
        prepass: true,
        fog: true,
    };
    let (f, _) = r.render_scene(&scene, &o).unwrap();
    assert_eq!((f.width, f.height), (w, 2 * h));
    let rgb = to_rgb8(&f);
    let diff = |a: usize, b: usize| -> f64 {
        (0..3)
            .map(|c| (rgb[3 * a + c] as f64 - rgb[3 * b + c] as f64).abs())
            .sum::<f64>()
    };
    for eye in 0..2 {
        let rows = (eye * h)..(eye * h + h);
        // Across the seam: the last column against the first.
        let seam: f64 = rows
            .clone()
            .map(|y| diff(f.index(w - 1, y), f.index(0, y)))
            .sum::<f64>()
            / h as f64;
        // Typical neighbouring columns elsewhere.
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
        // Hit/miss is continuous across the seam too, except where a silhouette runs along it.
        let flips = rows
            .clone()
            .filter(|&y| f.is_hit(f.index(w - 1, y)) != f.is_hit(f.index(0, y)))
            .count();
        assert!(
            flips <= 2,
            "eye {eye}: {flips} rows change hit/miss at the seam"
        );
    }
    // The two eyes see the ring from points 6.5 cm apart: the views differ, slightly.
    let differing = (0..(w * h) as usize)
        .filter(|&i| diff(i, i + (w * h) as usize) > 12.0)
        .count();
    assert!(
        differing > 0 && differing < (w * h) as usize / 4,
        "{differing} pixels differ between the eyes"
    );
}

#[test]
fn ods_frame_of_a_preset_matches_the_cpu_tracer() {
    let mut r = renderer();
    let mut scene = fathom_core::presets::load("menger").unwrap();
    // Close to the sponge, so that it fills a good part of the panorama.
    scene.camera.eye = glam::DVec3::new(0.6, 0.5, 1.7);
    let (w, h) = (128u32, 64u32);
    let projection = Projection::Ods {
        eye_separation: 0.2,
    };
    let o = RenderOptions {
        width: w,
        height: h,
        projection,
        prepass: true,
        fog: true,
    };
    let (g, _) = r.render_scene(&scene, &o).unwrap();
    let co = fathom_trace::Options {
        width: w,
        height: h,
        projection,
        ..Default::default()
    };
    let (c, _) = fathom_trace::render(&scene, &co, &|_, _| {}).unwrap();
    let hits = (0..c.len()).filter(|&i| c.is_hit(i)).count();
    let (same, hit_bad, hit_sil) = compare(&c, &g);
    let report = format!(
        "{:.2}% of pixels within {COLOUR_TOL}/255, {hit_bad} hit/miss disagreements off \
         silhouettes, {hit_sil} on them ({hits} CPU hits of {})",
        same * 100.0,
        c.len()
    );
    eprintln!("menger ODS {w}x{h} per eye: {report}");
    // The same threshold as the mono preset agreement test.
    assert!(hits > c.len() / 10, "the preset fills the view: {report}");
    assert!(same >= 0.99 && hit_bad == 0, "{report}");
}
