//! Multi-resolution cone-marching depth prepass.
//!
//! Level by level (blocks of 8, 4, then 2 pixels), one cone per block is marched from the eye.
//! A cone's radius at distance `t` is `t * slope`, with the slope covering the half-diagonal of
//! its block (`0.75 * block * pixel_angle`, where `pixel_angle` is the angular size of the
//! largest pixel, the one at the image centre). The cone steps by `d - t * slope`: by the
//! triangle inequality every ray inside the cone is then outside the surface up to where the
//! cone stops, so that distance is a safe start for every ray in the block. Each finer level
//! (and finally each pixel) starts at the minimum over the 2x2 nearest coarser cells, which also
//! absorbs small errors of distance estimates that are not strict bounds.
//!
//! When the rays of a block leave from different points (omni-directional stereo moves the
//! origin along the viewing circle with the longitude), the cone starts with the radius
//! [`Projection::cone_base`] covering that spread.

use crate::tracer::{MarchParams, march};
use fathom_core::frame::Rect;
use fathom_core::real::Real;
use fathom_core::{CameraFrame, Evaluator, Projection, Tape, V3};
use rayon::prelude::*;

/// Block sizes of the prepass levels, coarsest first (shared with the WGSL prepass).
pub use fathom_core::shared::PREPASS_LEVELS as LEVELS;

/// Safe start distances for one level: one per `block` x `block` cell of the image, for the
/// cells `x0 .. x0 + w` by `y0 .. y0 + h` of a level `full_w` x `full_h` cells large (all of
/// them for a whole image; a region's prepass computes only the cells its pixels read).
#[derive(Clone, Debug)]
pub struct StartGrid {
    /// Cell size in pixels.
    pub block: u32,
    /// Cells of the whole level per row.
    pub full_w: u32,
    /// Cells of the whole level per column.
    pub full_h: u32,
    /// The first column of cells held.
    pub x0: u32,
    /// The first row of cells held.
    pub y0: u32,
    /// Columns of cells held.
    pub w: u32,
    /// Rows of cells held.
    pub h: u32,
    /// Safe start distance per cell, row-major.
    pub t: Vec<f32>,
}

impl StartGrid {
    /// A grid of one cell whose start is `t` everywhere (no prepass).
    pub fn uniform(t: f32) -> Self {
        StartGrid {
            block: u32::MAX,
            full_w: 1,
            full_h: 1,
            x0: 0,
            y0: 0,
            w: 1,
            h: 1,
            t: vec![t],
        }
    }

    /// The cells (first x, first y, last x, last y; inclusive, in whole-level coordinates)
    /// whose centres surround some point at pixel coordinates in `[px0, px1] x [py0, py1]`:
    /// what [`StartGrid::start_at`] reads for points there.
    fn cells_read(&self, px: (f64, f64), py: (f64, f64)) -> (u32, u32, u32, u32) {
        let b = self.block as f64;
        let c = |p: f64, n: u32| ((p / b - 0.5).floor() as i64).clamp(0, n as i64 - 1) as u32;
        let c1 = |p: f64, n: u32| ((p / b - 0.5).floor() as i64 + 1).clamp(0, n as i64 - 1) as u32;
        (
            c(px.0, self.full_w),
            c(py.0, self.full_h),
            c1(px.1, self.full_w),
            c1(py.1, self.full_h),
        )
    }

    /// Safe start for the point at pixel coordinates (`px`, `py`) (pixel centres at +0.5): the
    /// minimum over the 2x2 cells whose centres surround it.
    pub fn start_at(&self, px: f64, py: f64) -> f32 {
        if self.block == u32::MAX {
            return self.t[0];
        }
        let b = self.block as f64;
        let fx = (px / b - 0.5).floor() as i64;
        let fy = (py / b - 0.5).floor() as i64;
        let mut m = f32::INFINITY;
        for dy in 0..2 {
            for dx in 0..2 {
                let x = (fx + dx).clamp(0, self.full_w as i64 - 1) as u32 - self.x0;
                let y = (fy + dy).clamp(0, self.full_h as i64 - 1) as u32 - self.y0;
                m = m.min(self.t[(y * self.w + x) as usize]);
            }
        }
        m
    }
}

/// What the prepass needs to know about the view.
pub struct View<'a> {
    /// The scene's compiled program.
    pub tape: &'a Tape,
    /// The camera's frame.
    pub cam: &'a CameraFrame,
    /// How rays leave the camera.
    pub projection: Projection,
    /// Which eye this view is: 0 left (or the only one), 1 right.
    pub eye: u32,
    /// One eye's image width, pixels.
    pub width: u32,
    /// One eye's image height, pixels.
    pub height: u32,
    /// Angular size of one pixel at the image centre, radians.
    pub pixel_angle: f64,
    /// Parameters of the primary rays (t_max, steps, pixel epsilon).
    pub base: MarchParams,
    /// Where every ray may start (the distance bound at the eye).
    pub t_start: f32,
}

/// Runs every level for the pixels of `rect` (the view's sample coordinates); returns the
/// finest grid (holding every cell those pixels read) and the distance evaluations spent.
/// `cancelled` is checked between levels (a cancelled prepass returns what it has).
pub fn run<S: Real>(view: &View, rect: Rect, cancelled: &dyn Fn() -> bool) -> (StartGrid, u64) {
    // From the finest level out: the cells each level must hold so that the next finer level
    // (or, for the finest, the pixels of `rect`) reads only cells that were computed.
    let mut need = Vec::with_capacity(LEVELS.len());
    let mut px = (rect.x as f64 + 0.5, (rect.right() - 1) as f64 + 0.5);
    let mut py = (rect.y as f64 + 0.5, (rect.bottom() - 1) as f64 + 0.5);
    for &block in LEVELS.iter().rev() {
        let g = StartGrid {
            block,
            full_w: view.width.div_ceil(block),
            full_h: view.height.div_ceil(block),
            ..StartGrid::uniform(0.0)
        };
        let cells = g.cells_read(px, py);
        need.push((block, cells));
        // The finer level is marched from the centres of these cells.
        let centre = |c: u32, size: u32| ((c * block) as f64 + 0.5 * block as f64).min(size as f64);
        px = (centre(cells.0, view.width), centre(cells.2, view.width));
        py = (centre(cells.1, view.height), centre(cells.3, view.height));
    }
    need.reverse();
    let mut grid = StartGrid::uniform(view.t_start);
    let mut evals = 0u64;
    for (block, cells) in need {
        if cancelled() {
            break;
        }
        let (g, e) = level::<S>(view, block, cells, &grid);
        grid = g;
        evals += e;
    }
    (grid, evals)
}

fn level<S: Real>(
    view: &View,
    block: u32,
    (cx0, cy0, cx1, cy1): (u32, u32, u32, u32),
    coarser: &StartGrid,
) -> (StartGrid, u64) {
    let w = cx1 - cx0 + 1;
    let h = cy1 - cy0 + 1;
    let n = w as usize * h as usize;
    let slope = 0.75 * block as f64 * view.pixel_angle;
    let params = MarchParams {
        cone_slope: slope,
        cone_base: view.projection.cone_base(block, view.width),
        // Stop once the cone has closed in to within a quarter of its radius: creeping further
        // costs many steps for little.
        eps_slope: 0.25 * slope + view.base.eps_slope,
        omega: 1.0,
        ..view.base
    };
    let mut t = vec![0f32; n];
    let chunk = S::LANES * 16;
    let evals: u64 = t
        .par_chunks_mut(chunk)
        .enumerate()
        .map_init(Evaluator::<S>::new, |ev, (ci, out)| {
            let mut evals = 0u64;
            for (pi, lanes) in out.chunks_mut(S::LANES).enumerate() {
                let first = ci * chunk + pi * S::LANES;
                let mut dx = [0f64; 8];
                let mut dy = [0f64; 8];
                let mut dz = [0f64; 8];
                let mut o = [[0f64; 8]; 3];
                let mut t0 = [0f64; 8];
                let mut live = [0f64; 8];
                for l in 0..S::LANES {
                    let k = (first + l.min(lanes.len() - 1)) as u32;
                    let (cx, cy) = (cx0 + k % w, cy0 + k / w);
                    let px = ((cx * block) as f64 + 0.5 * block as f64).min(view.width as f64);
                    let py = ((cy * block) as f64 + 0.5 * block as f64).min(view.height as f64);
                    let (off, d) =
                        view.projection
                            .ray(view.cam, view.eye, px, py, view.width, view.height);
                    (dx[l], dy[l], dz[l]) = (d.x, d.y, d.z);
                    let e = view.cam.eye + off;
                    (o[0][l], o[1][l], o[2][l]) = (e.x, e.y, e.z);
                    t0[l] = coarser.start_at(px, py) as f64;
                    live[l] = if l < lanes.len() { 0.0 } else { 1.0 };
                }
                let dir = V3::new(
                    S::from_lanes(&dx[..S::LANES]),
                    S::from_lanes(&dy[..S::LANES]),
                    S::from_lanes(&dz[..S::LANES]),
                );
                let origin = V3::new(
                    S::from_lanes(&o[0][..S::LANES]),
                    S::from_lanes(&o[1][..S::LANES]),
                    S::from_lanes(&o[2][..S::LANES]),
                );
                let live = S::from_lanes(&live[..S::LANES]).lt(S::splat(0.5));
                let t0 = S::from_lanes(&t0[..S::LANES]);
                let m = march(ev, view.tape, origin, dir, t0, live, &params);
                for (l, o) in lanes.iter_mut().enumerate() {
                    // A small pull-back keeps the next level clear of the surface the cone
                    // touched.
                    *o = (m.t.lane(l) * (1.0 - 1e-3)) as f32;
                    evals += m.steps.lane(l) as u64;
                }
            }
            evals
        })
        .sum();
    let grid = StartGrid {
        block,
        full_w: view.width.div_ceil(block),
        full_h: view.height.div_ceil(block),
        x0: cx0,
        y0: cy0,
        w,
        h,
        t,
    };
    (grid, evals)
}
