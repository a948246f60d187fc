//! What one frame did ([`FrameStats`]): its phases' times, rays, splits, unloads and memory.

use serde::Serialize;

/// Per-frame statistics (written as JSON by `fathom zoom --stats`).
#[derive(Clone, Debug, Default, Serialize)]
pub struct FrameStats {
    /// Frame number from 0.
    pub frame: u64,
    /// Wall time of the whole frame in ms.
    pub frame_ms: f64,
    /// Render phase in ms.
    pub render_ms: f64,
    /// Subdivision phase in ms (on a window's still step, its settling probes too).
    pub subdivide_ms: f64,
    /// Unification phase in ms.
    pub unify_ms: f64,
    /// Rays cast.
    pub rays: u64,
    /// Rays that hit a voxel.
    pub hits: u64,
    /// Mean nodes stepped through per ray.
    pub nodes_per_ray: f64,
    /// Distinct leaves rays asked to subdivide (`rays`, `hits`, `nodes_per_ray` and this
    /// count the render's rays only, not a still step's settling probes).
    pub requests: u64,
    /// Leaves split into children (on a still step, more than `requests` when its settling
    /// probes asked for more).
    pub subdivisions: u64,
    /// Leaves whose children were all empty.
    pub emptied: u64,
    /// Requests refused by the memory budget (on a still step, its settling probes' too:
    /// the step settles no further once the budget is spent, so none is counted twice).
    pub no_memory: u64,
    /// Bricks unloaded.
    pub unified: u64,
    /// Allocated node slots.
    pub node_count: u64,
    /// Bricks (inner nodes at brick depths).
    pub brick_count: u64,
    /// Bytes of the node arena.
    pub arena_bytes: u64,
    /// Resident memory of the process (bytes, from /proc; 0 where unavailable).
    pub resident_bytes: u64,
    /// Depth of the skip node (-1 when the eye is outside the root).
    pub skip_depth: i32,
    /// Depth of the anchor box coordinates are measured from (0: root units, f64 evaluation;
    /// deeper: double-double evaluation).
    pub anchor_depth: u8,
    /// The largest voxel visible in this frame, in pixels
    /// ([`SvoImage::largest_voxel_px`](crate::SvoImage::largest_voxel_px)).
    pub largest_voxel_px: f64,
    /// The part of `nodes_per_ray` the tiles' start walks took (the nodes their frusta met,
    /// per ray of the image).
    pub beam_nodes_per_ray: f64,
    /// Rays of the tiled path that started at the skip node: their tile found no start (a
    /// walk cut short, or a degenerate frustum), or their start point was within a rounding
    /// margin of a leaf's face at the start distance and at both earlier tries.
    pub rays_from_skip: u64,
    /// Pixels that took the hit of the lattice rays around them instead of casting a ray
    /// ([`crate::fill`]; not counted in `rays`).
    pub filled: u64,
}

/// Resident set size of this process in bytes (Linux), or 0.
pub fn resident_bytes() -> u64 {
    std::fs::read_to_string("/proc/self/statm")
        .ok()
        .and_then(|s| s.split_whitespace().nth(1)?.parse::<u64>().ok())
        .map(|pages| pages * 4096)
        .unwrap_or(0)
}
