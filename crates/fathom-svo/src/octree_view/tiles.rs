//! A render's tiles of pixels: drawing a tile (each pixel cast, or filled from the lattice rays
//! around it), and finding where a tile's rays can start by walks of the nodes its frustum
//! meets, refined quadrant by quadrant.

use super::pixels::{PixelBand, PixelRow};
use crate::fill;
use crate::frustum::{Seed, TileStack, TileStart, tile_start};
use crate::geometry::{BoxU, Ray};
use crate::octree::Octree;
use crate::ray_grid::{RayGrid, RaySpan, SPAN};
use crate::traverse::Hit;
use glam::DVec3;

/// How a render draws a tile of pixels: its rays' directions and origin, and the rule that
/// fills pixels between lattice rays ([`crate::fill`]; `wide` infinite: every pixel cast).
pub(super) struct TileDrawing<'a> {
    pub(super) grid: &'a RayGrid,
    pub(super) o: [f64; 3],
    pub(super) lod: f64,
    pub(super) rule: fill::Rule,
    pub(super) wide: f64,
}

/// A thread's scratch for [`TileDrawing::draw`], kept across its tiles.
#[derive(Default)]
pub(super) struct TileScratch {
    pub(super) span: RaySpan,
    /// The hits of a tile's lattice rays.
    pub(super) lattice: Vec<Hit>,
}

impl TileDrawing<'_> {
    /// Whether pixels between lattice rays may be filled.
    pub(super) fn fills(&self) -> bool {
        self.wide.is_finite()
    }

    /// Draws columns `x0..x0 + n` (fewer at the right edge) of every row of `band`, which
    /// holds the frame's rows from `y0`: each pixel's hit is its ray's, `cast(x, y, ray)`,
    /// or, when the tile fills and is at most [`SPAN`] wide, filled from the lattice rays
    /// around it; `put(x, d, hit, row, filled)` writes it.
    #[inline(always)]
    pub(super) fn draw(
        &self,
        band: &mut PixelBand,
        (x0, y0, n): (usize, usize, usize),
        s: &mut TileScratch,
        mut cast: impl FnMut(usize, usize, &Ray) -> Hit,
        mut put: impl FnMut(usize, DVec3, Hit, &mut PixelRow, bool),
    ) {
        let n = n.min(band.width - x0);
        let rows = band.rows();
        if self.fills() && n <= SPAN {
            let mut at = usize::MAX;
            fill::tile(
                &mut s.lattice,
                n,
                rows,
                self.rule,
                self.wide,
                |j, i, filled| {
                    let y = y0 + j;
                    if j != at {
                        self.grid.span(y, x0, n, &mut s.span);
                        at = j;
                    }
                    let x = x0 + i;
                    let hit =
                        filled.unwrap_or_else(|| cast(x, y, &s.span.ray(i, self.o, self.lod)));
                    put(x, s.span.dir(i), hit, &mut band.row(j), filled.is_some());
                    hit
                },
            );
            return;
        }
        for j in 0..rows {
            let y = y0 + j;
            let mut row = band.row(j);
            self.grid
                .segment(y, x0, n, self.o, self.lod, &mut s.span, |x, d, r| {
                    let hit = cast(x, y, r);
                    put(x, d, hit, &mut row, false);
                });
        }
    }
}

/// The starts of one band's finest tiles (side `side` pixels, row-major, `cols` a row; the
/// band's first pixel row is `y0`); `None` where a tile has no start (its rays start at the
/// skip node).
pub(super) struct FineStarts {
    y0: usize,
    pub(super) cols: usize,
    pub(super) side: usize,
    pub(super) starts: Vec<Option<TileStart>>,
}

impl FineStarts {
    /// Tiles of side `side` over a band `width` pixels wide, rows `y0..=y1`, without starts.
    pub(super) fn new(width: usize, y0: usize, y1: usize, side: usize) -> FineStarts {
        let cols = width.div_ceil(side);
        FineStarts {
            y0,
            cols,
            side,
            starts: vec![None; cols * (y1 + 1 - y0).div_ceil(side)],
        }
    }

    /// The start of the finest tile holding pixel `(x, y)`.
    pub(super) fn at(&mut self, x: usize, y: usize) -> &mut Option<TileStart> {
        &mut self.starts[(y - self.y0) / self.side * self.cols + x / self.side]
    }
}

/// Finds the start of the tile `(x0, y0, side)` (clipped to the last pixel `last`) by a walk
/// of the nodes its frustum meets, seeded by its parent's start `parent` (without one, by the
/// node `from` holding the eye),
/// and recursively its quadrants' from it down to the finest side, whose starts go into `out`.
/// A tile without a start of its own keeps its parent's (valid for all the parent's rays).
/// Returns the nodes the walks visited.
#[allow(clippy::too_many_arguments)]
pub(super) fn refine_tile(
    tree: &Octree,
    ray: &impl Fn(usize, usize) -> Ray,
    (x0, y0, side): (usize, usize, usize),
    last: (usize, usize),
    from: (u32, BoxU),
    parent: Option<TileStart>,
    out: &mut FineStarts,
    stack: &mut TileStack,
) -> u64 {
    let (x1, y1) = ((x0 + side - 1).min(last.0), (y0 + side - 1).min(last.1));
    let corners = [ray(x0, y0), ray(x1, y0), ray(x0, y1), ray(x1, y1)];
    let seed = match parent {
        None => Some(Seed::at_eye(&corners, from)),
        Some(p) => Seed::within(tree, &corners, &p),
    };
    let (s, n) = match seed {
        Some(sd) => tile_start(tree, &corners, &sd, stack),
        None => (None, 0),
    };
    let s = s.or(parent);
    let mut n = n as u64;
    if side <= out.side {
        *out.at(x0, y0) = s;
        return n;
    }
    let half = side / 2;
    for (dx, dy) in [(0, 0), (half, 0), (0, half), (half, half)] {
        let (qx, qy) = (x0 + dx, y0 + dy);
        if qx <= last.0 && qy <= last.1 {
            n += refine_tile(tree, ray, (qx, qy, half), last, from, s, out, stack);
        }
    }
    n
}
