//! Summaries of a zoom's per-frame stats: the figures the issue asks for (median fps once
//! settled, last-decade / first-decade fps ratio, peak memory, node-count growth over the
//! brick cycle).

use crate::octree_view::FrameStats;
use serde::Serialize;

/// The headline numbers of one zoom run.
#[derive(Clone, Debug, Default, Serialize)]
pub struct Summary {
    /// Frames rendered.
    pub frames: usize,
    /// Zoom factor reached.
    pub zoom_reached: f64,
    /// Median fps over all frames.
    pub median_fps: f64,
    /// Median fps after the first decade of zoom (detail has settled by then).
    pub median_fps_settled: f64,
    /// Median fps over the first decade of zoom after settling (zoom 10..100).
    pub median_fps_first_decade: f64,
    /// Median fps over the last decade of zoom.
    pub median_fps_last_decade: f64,
    /// `median_fps_last_decade / median_fps_first_decade`.
    pub last_over_first: f64,
    /// Mean nodes per ray over the last decade.
    pub nodes_per_ray_last_decade: f64,
    /// Peak resident memory in bytes.
    pub peak_resident_bytes: u64,
    /// Peak node-arena bytes.
    pub peak_arena_bytes: u64,
    /// Largest node count over the run.
    pub max_nodes: u64,
    /// Largest node count during the first brick cycle after settling (zoom 10 .. 10 * 2^k).
    pub first_cycle_nodes: u64,
    /// `max_nodes / first_cycle_nodes`.
    pub max_over_first_cycle: f64,
    /// Median frame time in ms.
    pub median_frame_ms: f64,
}

/// Median of a slice (0 when empty).
pub fn median(v: &[f64]) -> f64 {
    if v.is_empty() {
        return 0.0;
    }
    let mut s = v.to_vec();
    s.sort_by(|a, b| a.total_cmp(b));
    let n = s.len();
    if n % 2 == 1 {
        s[n / 2]
    } else {
        0.5 * (s[n / 2 - 1] + s[n / 2])
    }
}

impl Summary {
    /// Summarises frames with the zoom factor each was rendered at; `brick_period` sets the
    /// node-count cycle (`2^k` of zoom).
    pub fn new(frames: &[FrameStats], zooms: &[f64], brick_period: u8) -> Summary {
        let fps = |f: &FrameStats| 1e3 / f.frame_ms.max(1e-6);
        let pick = |lo: f64, hi: f64| -> Vec<&FrameStats> {
            frames
                .iter()
                .zip(zooms)
                .filter(|(_, z)| **z >= lo && **z <= hi)
                .map(|(f, _)| f)
                .collect()
        };
        let zmax = zooms.iter().copied().fold(1.0, f64::max);
        let all: Vec<f64> = frames.iter().map(fps).collect();
        let settled: Vec<f64> = pick(10.0, f64::INFINITY).into_iter().map(fps).collect();
        let first: Vec<f64> = pick(10.0, 100.0).into_iter().map(fps).collect();
        let last_f = pick(zmax / 10.0, zmax);
        let last: Vec<f64> = last_f.iter().map(|f| fps(f)).collect();
        let cycle = pick(10.0, 10.0 * 2f64.powi(brick_period as i32));
        let first_cycle_nodes = cycle.iter().map(|f| f.node_count).max().unwrap_or(0);
        let max_nodes = frames.iter().map(|f| f.node_count).max().unwrap_or(0);
        let mf = median(&first);
        let ml = median(&last);
        Summary {
            frames: frames.len(),
            zoom_reached: zmax,
            median_fps: median(&all),
            median_fps_settled: median(&settled),
            median_fps_first_decade: mf,
            median_fps_last_decade: ml,
            last_over_first: if mf > 0.0 { ml / mf } else { 0.0 },
            nodes_per_ray_last_decade: last_f.iter().map(|f| f.nodes_per_ray).sum::<f64>()
                / last_f.len().max(1) as f64,
            peak_resident_bytes: frames.iter().map(|f| f.resident_bytes).max().unwrap_or(0),
            peak_arena_bytes: frames.iter().map(|f| f.arena_bytes).max().unwrap_or(0),
            max_nodes,
            first_cycle_nodes,
            max_over_first_cycle: if first_cycle_nodes > 0 {
                max_nodes as f64 / first_cycle_nodes as f64
            } else {
                0.0
            },
            median_frame_ms: median(&frames.iter().map(|f| f.frame_ms).collect::<Vec<_>>()),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn summary_picks_decades() {
        assert_eq!(median(&[3.0, 1.0, 2.0]), 2.0);
        assert_eq!(median(&[4.0, 1.0, 2.0, 3.0]), 2.5);
        let frames: Vec<FrameStats> = (0..100)
            .map(|i| FrameStats {
                frame: i,
                frame_ms: if i < 50 { 10.0 } else { 20.0 },
                node_count: 100 + i,
                ..FrameStats::default()
            })
            .collect();
        let zooms: Vec<f64> = (0..100).map(|i| 1e4f64.powf(i as f64 / 99.0)).collect();
        let s = Summary::new(&frames, &zooms, 3);
        assert_eq!(s.median_fps_first_decade, 100.0);
        assert_eq!(s.median_fps_last_decade, 50.0);
        assert!((s.last_over_first - 0.5).abs() < 1e-12);
        assert_eq!(s.max_nodes, 199);
    }
}
