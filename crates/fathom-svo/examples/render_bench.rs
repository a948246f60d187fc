//! Render-phase micro benchmark: builds a tree deterministically along a zoom (fixed number of
//! subdivisions per frame, no time budget), then times the render phase alone at chosen frames
//! (min and median of repeated renders of the same frozen tree) and prints an image checksum.
//!
//! `cargo run --release -p fathom-svo --example render_bench -- mandelbulb 300 1e11 [threads]
//! [neighbour|kdrestart] [beam tile side, 0 for none] [finest beam tile side] [fovea]
//! [smooth: 1 or 0] [fill_px, or several comma-separated] [subdivisions a frame]`
//!
//! The fovea (default `request_order::DEFAULT_FOVEA`) decides which leaves the fixed number of
//! subdivisions splits: 0 builds the trees of the builds without a fovea, whose checksums
//! `docs/log/svo.md` records. Smoothing (default on, as in every front end; `crate::smooth`)
//! changes the checksummed colours wherever a frame shows voxels two or more pixels wide: 0
//! gives the checksums of the builds before smoothing.
//!
//! Pixel filling (`crate::fill`, default `fill::DEFAULT_FILL_PX`): with several values (e.g.
//! `0,4`) each checkpoint's repeated renders take them in turn on the same frozen tree, and
//! each value's times are reported; the tree is built with the first. The tree is built with
//! 1700 subdivisions a frame by default, far finer than a zoom's frames (a few hundred a
//! frame at the default 3 ms): pass a smaller count to time the coarse trees zooms show.

use fathom_core::camera_path::path_preset;
use fathom_svo::RootSpec;
use fathom_svo::octree_view::{OctreeView, OctreeViewConfig, Traversal};
use std::time::Instant;

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let name = args.get(1).map(String::as_str).unwrap_or("mandelbulb");
    let frames: usize = args.get(2).and_then(|s| s.parse().ok()).unwrap_or(300);
    let depth: f64 = args.get(3).and_then(|s| s.parse().ok()).unwrap_or(1e11);
    let threads: usize = args.get(4).and_then(|s| s.parse().ok()).unwrap_or(2);
    let trav = match args.get(5).map(String::as_str) {
        Some("kdrestart") => Traversal::KdRestart,
        _ => Traversal::Neighbour,
    };
    let reps = 15;
    let fills: Vec<f64> = args
        .get(10)
        .map(|s| s.split(',').filter_map(|v| v.parse().ok()).collect())
        .filter(|v: &Vec<f64>| !v.is_empty())
        .unwrap_or_else(|| vec![fathom_svo::fill::DEFAULT_FILL_PX]);
    let subdivisions: usize = args.get(11).and_then(|s| s.parse().ok()).unwrap_or(1700);
    let p = path_preset(name).unwrap_or_else(|e| {
        eprintln!("render_bench: {e}");
        std::process::exit(2)
    });
    let cfg = OctreeViewConfig {
        threads,
        subdivide_ms: 0.0,
        min_subdivisions: subdivisions,
        root: RootSpec::from_cube(p.cube),
        traversal: trav,
        beam: args
            .get(6)
            .and_then(|s| s.parse().ok())
            .unwrap_or(fathom_svo::octree_view::DEFAULT_BEAM),
        beam_min: args
            .get(7)
            .and_then(|s| s.parse().ok())
            .unwrap_or(fathom_svo::octree_view::DEFAULT_BEAM_MIN),
        fovea: args
            .get(8)
            .and_then(|s| s.parse().ok())
            .unwrap_or(fathom_svo::request_order::DEFAULT_FOVEA),
        smooth: args.get(9).is_none_or(|s| s != "0"),
        fill_px: fills[0],
        ..OctreeViewConfig::default()
    };
    let mut ex = OctreeView::new(&p.scene, cfg).unwrap();
    let checkpoints = [frames / 3, 2 * frames / 3, frames - 1];
    let mut total_min = vec![0.0; fills.len()];
    for i in 0..frames {
        let cam = p.camera(i, frames, depth);
        if checkpoints.contains(&i) {
            let mut times = vec![Vec::new(); fills.len()];
            let mut sums = vec![0u64; fills.len()];
            let mut npr = vec![0.0; fills.len()];
            let mut rays = vec![1u64; fills.len()];
            let mut walks = vec![0u64; fills.len()];
            for _ in 0..reps {
                for (k, &fill) in fills.iter().enumerate() {
                    ex.cfg.fill_px = fill;
                    let t0 = Instant::now();
                    let (img, reqs, c) = ex.render(&cam);
                    times[k].push(t0.elapsed().as_secs_f64() * 1e3);
                    ex.release_requests(&reqs);
                    npr[k] = c[2] as f64 / c[0] as f64;
                    rays[k] = c[0].max(1);
                    walks[k] = ex.beam_steps();
                    sums[k] = img.colour.iter().zip(&img.depth).fold(0u64, |h, (&c, &d)| {
                        (h ^ (c as u64) ^ ((d.to_bits() as u64) << 32)).wrapping_mul(0x100000001b3)
                    });
                }
            }
            ex.cfg.fill_px = fills[0];
            for (k, &fill) in fills.iter().enumerate() {
                let t = &mut times[k];
                t.sort_by(|a, b| a.partial_cmp(b).unwrap());
                total_min[k] += t[0];
                println!(
                    "{name} frame {i} fill {fill}: render min {:.2} ms median {:.2} ms, {:.2} \
                     nodes/ray ({:.2} in tile walks), {} rays, {} nodes, checksum {:016x}",
                    t[0],
                    t[reps / 2],
                    npr[k],
                    walks[k] as f64 / rays[k] as f64,
                    rays[k],
                    ex.tree.counts().nodes,
                    sums[k]
                );
            }
        }
        ex.step(&cam);
    }
    for (fill, total) in fills.iter().zip(&total_min) {
        println!("{name} fill {fill}: sum of min render ms {total:.2}");
    }
}
