//! Tests of zooms past f64 root units: boxes relative to the anchor, the double-double eye and
//! evaluation. The references are the sponge's own self-similarity (a Menger frame at zoom
//! `z * 3^k` into the corner (1, 1, 1) shows what the frame at `z` shows) and the checker.

use crate::check::check;
use crate::octree_view::{DeepEye, OctreeView, OctreeViewConfig, SvoImage, Traversal};
use crate::root::MENGER_CUBE;
use fathom_core::Camera;
use fathom_core::camera_path::path_preset;
use fathom_core::dd::to_dvec3;
use glam::DVec3;

fn cfg(w: u32, h: u32) -> OctreeViewConfig {
    OctreeViewConfig {
        width: w,
        height: h,
        threads: 2,
        root: MENGER_CUBE,
        ..OctreeViewConfig::default()
    }
}

/// The Menger zoom preset's camera at zoom `z` (any depth): the path's double-double eye
/// `(1,1,1) + dir * 1.5 / z` (`CameraPath::eye_dd`), looking along `-dir` with the
/// target-relative camera's exact orientation.
fn menger_camera(z: f64) -> (Camera, DeepEye) {
    let p = path_preset("menger").unwrap();
    let (eye, rel) = p.path.deep_camera(1, 2, z, p.fov).unwrap();
    let hi = to_dvec3(eye);
    let cam = Camera {
        eye: hi,
        target: hi - rel.eye.normalize(),
        up: rel.up,
        fov: rel.fov,
    };
    let deep = DeepEye {
        eye_lo: DVec3::new(eye.x.lo, eye.y.lo, eye.z.lo),
        scale: rel.eye.length(),
    };
    (cam, deep)
}

/// Settles the octree at a fixed deep camera; returns the frames taken.
fn settle(ex: &mut OctreeView, cam: &Camera, deep: &DeepEye, max: usize) -> usize {
    for i in 0..max {
        let (_, reqs, _) = ex.render_deep(cam, deep);
        if reqs.is_empty() {
            return i;
        }
        ex.subdivide(reqs, f64::INFINITY);
    }
    max
}

fn render(ex: &mut OctreeView, cam: &Camera, deep: &DeepEye, t: Traversal) -> SvoImage {
    ex.cfg.traversal = t;
    let (img, reqs, _) = ex.render_deep(cam, deep);
    ex.release_requests(&reqs);
    img
}

/// Silhouette intersection over union of two hit masks.
fn mask_iou(a: &[bool], b: &[bool]) -> f64 {
    let inter = a.iter().zip(b).filter(|(x, y)| **x && **y).count();
    let union = a.iter().zip(b).filter(|(x, y)| **x || **y).count();
    inter as f64 / union.max(1) as f64
}

fn iou(a: &SvoImage, b: &SvoImage) -> f64 {
    mask_iou(&a.mask(), &b.mask())
}

/// Mean absolute difference of the colour channels over pixels both images hit, in [0, 1].
fn colour_error(a: &SvoImage, b: &SvoImage) -> f64 {
    let (mut sum, mut n) = (0.0, 0usize);
    for i in 0..a.colour.len() {
        if a.depth[i].is_finite() && b.depth[i].is_finite() {
            for k in 0..3 {
                let ca = (a.colour[i] >> (8 * k) & 255) as f64;
                let cb = (b.colour[i] >> (8 * k) & 255) as f64;
                sum += (ca - cb).abs() / 255.0;
            }
            n += 3;
        }
    }
    sum / n.max(1) as f64
}

#[test]
fn past_f64_the_traversals_agree_and_the_links_hold() {
    // Zoom 1e15 at 64x48: voxels of a pixel are 2^-57 of the root, nine levels past what f64
    // root units could tell apart.
    let mut ex = OctreeView::new(&path_preset("menger").unwrap().scene, cfg(64, 48)).unwrap();
    let (cam, deep) = menger_camera(1e15);
    let frames = settle(&mut ex, &cam, &deep, 400);
    assert!(frames < 400, "the octree did not settle");
    assert!(
        ex.tree.anchor.depth > 0,
        "a deep frame needs an anchor off the root"
    );
    let kd = render(&mut ex, &cam, &deep, Traversal::KdRestart);
    let nb = render(&mut ex, &cam, &deep, Traversal::Neighbour);
    assert!(
        kd.mask().iter().filter(|&&m| m).count() > 500,
        "the corner is in view"
    );
    assert_eq!(
        nb, kd,
        "neighbour traversal differs from kd-restart at zoom 1e15"
    );
    check(&ex.tree).unwrap();
    let deepest = (0..ex.tree.nodes.len())
        .filter(|&i| !ex.tree.nodes[i].is_free())
        .map(|i| ex.tree.nodes[i].depth)
        .max()
        .unwrap();
    assert!(deepest > 55, "voxels reach depth {deepest} only");
    assert!(
        nb.largest_voxel_px <= 1.0,
        "settled frame shows {} px voxels",
        nb.largest_voxel_px
    );
}

#[test]
fn menger_frames_whole_powers_of_three_apart_show_the_same_corner() {
    // The corner (1, 1, 1) is a fixed point of the sponge's scaling by 1/3: the frame at zoom
    // `z * 3^k` shows what the frame at `z` shows. z = 9 * 3^5 renders in root units (f64);
    // the deep frames are 19 to 31 powers of 3 further (zoom 2.5e12 to 1.4e18), all past f64
    // root units, relative to an anchor and evaluated in double-double. The reference is the
    // f64 sphere tracer's silhouette at z, and the octree's own frame at z.
    let scene = path_preset("menger").unwrap().scene;
    let (w, h) = (64, 48);
    let settled = |z: f64| {
        let mut ex = OctreeView::new(&scene, cfg(w, h)).unwrap();
        let (cam, deep) = menger_camera(z);
        let n = settle(&mut ex, &cam, &deep, 400);
        assert!(n < 400, "zoom {z:e} did not settle");
        let img = render(&mut ex, &cam, &deep, Traversal::Neighbour);
        check(&ex.tree).unwrap();
        (img, ex.tree.anchor.depth)
    };
    let z0 = 9.0 * 3f64.powi(5);
    let (base, a0) = settled(z0);
    assert_eq!(a0, 0, "zoom {z0} renders in root units");
    let traced = crate::outline::trace_mask(&scene, &menger_camera(z0).0, w, h, 0.3).unwrap();
    let tracer_iou = |img: &SvoImage| mask_iou(&img.mask(), &traced);
    // How far two root-unit frames a power of 3 apart differ in colour: the dyadic voxel grid
    // does not scale with the sponge's 1/3, so voxels straddle hole edges differently.
    let (shallow, _) = settled(z0 * 3.0);
    let shallow_err = colour_error(&base, &shallow);
    eprintln!(
        "root units, 3^1 deeper: IoU {:.4}, colour error {shallow_err:.4}; tracer IoU at z0 {:.4}",
        iou(&base, &shallow),
        tracer_iou(&base)
    );
    for k in [19, 26, 31] {
        let z = z0 * 3f64.powi(k);
        let (img, a) = settled(z);
        assert!(a > 0, "zoom {z:e} renders relative to an anchor");
        let (i, e, t) = (
            iou(&base, &img),
            colour_error(&base, &img),
            tracer_iou(&img),
        );
        eprintln!(
            "3^{k} deeper (zoom {z:.2e}, anchor depth {a}): IoU {i:.4} (tracer {t:.4}), colour error {e:.4}"
        );
        assert!(i >= 0.99, "zoom {z:e}: IoU with the frame at {z0} {i}");
        assert!(t >= 0.99, "zoom {z:e}: IoU with the tracer at {z0} {t}");
        assert!(
            e <= shallow_err + 0.02,
            "zoom {z:e}: colour error {e}, root-unit frames differ by {shallow_err}"
        );
    }
}

#[test]
fn node_count_stays_flat_on_a_zoom_to_1e15() {
    // 300 frames to zoom 1e15, exactly 256 subdivisions a frame (the same tree on any machine).
    let p = path_preset("menger").unwrap();
    let mut c = cfg(80, 60);
    c.subdivide_ms = 0.0;
    let mut ex = OctreeView::new(&p.scene, c).unwrap();
    let frames = 300;
    let (mut nodes, mut anchors) = (Vec::new(), Vec::new());
    for i in 0..frames {
        let z = 1e15f64.powf(i as f64 / (frames - 1) as f64);
        let (cam, deep) = menger_camera(z);
        let (img, st) = ex.step_deep(&cam, &deep);
        assert!(
            img.mask().iter().any(|&m| m),
            "frame {i} (zoom {z:.2e}) shows nothing"
        );
        nodes.push(st.node_count);
        anchors.push(st.anchor_depth);
    }
    check(&ex.tree).unwrap();
    let first_cycle = *nodes[..40].iter().max().unwrap();
    let later = *nodes[40..].iter().max().unwrap();
    let last_third = *nodes[200..].iter().max().unwrap();
    eprintln!(
        "nodes: first 40 frames max {first_cycle}, later max {later}, last third max {last_third}; anchor depth at the end {}",
        anchors.last().unwrap()
    );
    assert!(
        *anchors.last().unwrap() >= 10,
        "the anchor followed the eye down"
    );
    assert!(
        later as f64 <= 1.5 * first_cycle as f64,
        "node count grew from {first_cycle} to {later}"
    );
}
