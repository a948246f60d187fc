//! Deep octree frames against the double-double reference tracer (`fathom_trace::deep`): zoom
//! frames at 1e12, 1e15 and far past f64, settled at a still camera, must show the silhouette
//! and the depths the careful tracer finds from the same double-double eye.

use crate::zoom::ZoomPath;
use fathom_core::Tape;
use fathom_core::camera_path::path_preset;
use fathom_image::compare::silhouette_iou;
use fathom_svo::{DeepEye, OctreeView, OctreeViewConfig, RootSpec};
use fathom_trace::deep::zoom_frame_depths;

/// The octree's depths (None: sky) of the zoom's frame at `zoom`, settled.
fn octree_depths(p: &ZoomPath, zoom: f64, w: u32, h: u32) -> (Vec<Option<f64>>, u8, DeepEye) {
    let (cam, deep) = p.deep_camera(1, 2, zoom);
    let root = match (p.cube, p.path.target()) {
        (Some(_), _) => RootSpec::from_cube(p.cube),
        (None, Some(t)) => RootSpec::Fit {
            half: (1.5 * t.abs().max_element()).max(4.0),
        },
        _ => RootSpec::default(),
    };
    let mut ex = OctreeView::new(
        &p.scene,
        OctreeViewConfig {
            width: w,
            height: h,
            threads: 2,
            root,
            ..OctreeViewConfig::default()
        },
    )
    .unwrap();
    for _ in 0..400 {
        let (_, reqs, _) = ex.render_deep(&cam, &deep);
        if reqs.is_empty() {
            break;
        }
        ex.subdivide(reqs, f64::INFINITY);
    }
    let (img, reqs, _) = ex.render_deep(&cam, &deep);
    ex.release_requests(&reqs);
    assert!(img.largest_voxel_px <= 1.0, "zoom {zoom:e} did not settle");
    fathom_svo::check::check(&ex.tree).unwrap();
    let depths = img
        .depth
        .iter()
        .map(|&d| d.is_finite().then_some(d as f64))
        .collect();
    (depths, ex.tree.anchor.depth, deep)
}

/// Silhouette IoU and the median and 90th percentile of `|octree - tracer| / tracer` over the
/// pixels both hit, of the zoom's frame at `zoom`; also the anchor depth.
fn agreement(p: &ZoomPath, tape: &Tape, zoom: f64, (w, h): (u32, u32)) -> (f64, f64, f64, u8) {
    let (svo, anchor, _) = octree_depths(p, zoom, w, h);
    let traced = zoom_frame_depths(tape, &p.path, 1, 2, zoom, p.fov, w, h).unwrap();
    let mut rel: Vec<f64> = svo
        .iter()
        .zip(&traced)
        .filter_map(|(a, b)| Some(((a.as_ref()? - b.as_ref()?) / b.as_ref()?).abs()))
        .collect();
    assert!(
        rel.len() > (w * h / 4) as usize,
        "zoom {zoom:e}: the surface is in view"
    );
    rel.sort_by(f64::total_cmp);
    let q = |f: f64| rel[(f * (rel.len() - 1) as f64) as usize];
    (silhouette_iou(&svo, &traced), q(0.5), q(0.9), anchor)
}

#[test]
fn deep_octree_frames_match_the_double_double_tracer() {
    // At 48x36 a voxel of one pixel is 2.4 % of its distance, and the tracer stops within
    // half a footprint of the surface: depths differ by a few per cent even in root units
    // (zoom 1e3). Deep frames must agree with the reference as well as that: silhouette IoU
    // >= 0.99, and depth errors no larger than at 1e3 plus 1 % (median) and 3 % (90th
    // percentile). Before the zoom's deep camera took its orientation from the
    // target-relative camera, frames past 1e16 came out rotated: Menger IoU 0.8155.
    let size = (48u32, 36u32);
    for name in ["menger", "mandelbulb"] {
        let p: ZoomPath = path_preset(name).unwrap().into();
        let tape = Tape::compile(&p.scene).unwrap();
        let (iou0, med0, p90_0, a0) = agreement(&p, &tape, 1e3, size);
        eprintln!(
            "{name} at zoom 1e3 (anchor {a0}): IoU {iou0:.4}, depth error median {med0:.4}, 90th percentile {p90_0:.4}"
        );
        assert_eq!(a0, 0);
        for zoom in [1e12, 1e15, 1e20, 1e27] {
            let (iou, med, p90, anchor) = agreement(&p, &tape, zoom, size);
            eprintln!(
                "{name} at zoom {zoom:.0e} (anchor {anchor}): IoU {iou:.4}, depth error median {med:.4}, 90th percentile {p90:.4}"
            );
            assert!(anchor > 0, "{name} {zoom:e}: rendered in root units");
            assert!(iou >= 0.99, "{name} {zoom:e}: silhouette IoU {iou}");
            assert!(
                med <= med0 + 0.01,
                "{name} {zoom:e}: median depth error {med}"
            );
            assert!(
                p90 <= p90_0 + 0.03,
                "{name} {zoom:e}: 90th percentile {p90}"
            );
        }
    }
}

#[test]
fn zoom_comparisons_use_the_double_double_reference_when_deep() {
    // A 30-frame zoom of the menger preset to 1e15 at 48x36, compared every 3 frames (and the
    // last): frames whose camera is in the deep form must be compared with the double-double
    // reference (full size at 48x36), shallow ones with the f64 tracer, and the deep ones must
    // agree with it in silhouette.
    use crate::request::{Backend, RenderRequest};
    use crate::zoom::Zoom;
    let p: ZoomPath = path_preset("menger").unwrap().into();
    let z = Zoom {
        depth: 1e15,
        frames: 30,
        request: RenderRequest {
            width: 48,
            height: 36,
            threads: Some(2),
            backend: Backend::Octree,
            ..RenderRequest::default()
        },
        compare_every: 3,
        reference_samples: 1,
        warmup_ms: 0.0,
    };
    let r = z.run(&p, false, |_| Ok(())).unwrap();
    assert!(r.stopped.is_none(), "{:?}", r.stopped);
    let mut deep = 0;
    for c in &r.compare {
        let (_, d) = p.deep_camera(c.frame, z.frames, z.depth);
        eprintln!(
            "frame {:2} zoom {:.1e}: {} reference (reduced {}), IoU {:.4}, SSIM {:.3}, colour error {:.4}, within {:.3}, largest voxel {:.2} px, {:.0} ms",
            c.frame,
            c.zoom,
            c.reference,
            c.reduced,
            c.agreement.iou,
            c.agreement.ssim,
            c.agreement.colour_error,
            c.agreement.colour_within,
            c.largest_voxel_px,
            c.trace_ms
        );
        let want = if p.is_deep(&d) {
            "double-double"
        } else {
            "f64"
        };
        assert_eq!(c.reference, want, "frame {}", c.frame);
        assert_eq!(c.reduced, 1);
        assert_eq!(c.reference_samples, 1);
        if p.is_deep(&d) {
            deep += 1;
            assert!(
                c.agreement.iou >= 0.98,
                "frame {} (zoom {:e}): IoU {}",
                c.frame,
                c.zoom,
                c.agreement.iou
            );
        }
    }
    assert!(deep >= 4, "only {deep} deep comparisons");
}
