//! The pixel rays of one frame: directions per pixel, bit for bit the camera's, with the work
//! shared between pixels done once per frame and the per-pixel square root and divisions done a
//! run of pixels at a time.
//!
//! A ray's setup is a chain of dependent slow operations (a square root, a division to
//! normalise, three more for the reciprocal direction the slab tests use). Done pixel by pixel
//! inside the traversal loop, perf showed that chain as 16 % of a Menger zoom's samples. Done
//! for a [`SPAN`] of pixels in a loop with no dependency between pixels, the compiler issues
//! them two (or more) at a time and the traversal loop only loads the results. The tiled
//! render sets up a tile's row at a time ([`RayGrid::segment`], 16 pixels by default).

use crate::geometry::Ray;
use fathom_core::CameraFrame;
use glam::DVec3;

/// Pixels whose rays are set up together.
pub const SPAN: usize = 64;

/// The pixel rays' directions of one frame, [`CameraFrame::ray_dir`] bit for bit with its
/// divisions and per-row and per-column products done once: `forward + right sx` per column
/// and `up sy` per row, added in the order `ray_dir` adds them, then normalised.
pub struct RayGrid {
    cols: Vec<DVec3>,
    rows: Vec<DVec3>,
}

impl RayGrid {
    /// The grid of a `w` x `h` image seen through `frame`.
    pub fn new(frame: &CameraFrame, w: u32, h: u32) -> RayGrid {
        let hf = h as f64;
        let cols = (0..w)
            .map(|x| {
                let sx = (2.0 * (x as f64 + 0.5) - w as f64) / hf * frame.tan_half_fov;
                frame.forward + frame.right * sx
            })
            .collect();
        let rows = (0..h)
            .map(|y| {
                let sy = (hf - 2.0 * (y as f64 + 0.5)) / hf * frame.tan_half_fov;
                frame.up * sy
            })
            .collect();
        RayGrid { cols, rows }
    }

    /// Unit direction through the centre of pixel (`x`, `y`).
    #[inline(always)]
    pub fn dir(&self, x: usize, y: usize) -> DVec3 {
        (self.cols[x] + self.rows[y]).normalize()
    }

    /// Calls `f(x, d, ray)` for every pixel of row `y`, left to right: `d` its unit direction
    /// and `ray` from `o` with LOD factor `lod`, set up [`SPAN`] pixels at a time in `span`
    /// (scratch the caller keeps across rows).
    #[inline(always)]
    pub fn row(
        &self,
        y: usize,
        o: [f64; 3],
        lod: f64,
        span: &mut RaySpan,
        mut f: impl FnMut(usize, DVec3, &Ray),
    ) {
        self.segment(y, 0, self.cols.len(), o, lod, span, &mut f);
    }

    /// [`RayGrid::row`] for the pixels `x0..x0 + n` of row `y` only.
    #[inline(always)]
    #[allow(clippy::too_many_arguments)]
    pub fn segment(
        &self,
        y: usize,
        x0: usize,
        n: usize,
        o: [f64; 3],
        lod: f64,
        span: &mut RaySpan,
        mut f: impl FnMut(usize, DVec3, &Ray),
    ) {
        for a in (x0..x0 + n).step_by(SPAN) {
            let k = SPAN.min(x0 + n - a);
            self.span(y, a, k, span);
            for i in 0..k {
                f(a + i, span.dir(i), &span.ray(i, o, lod));
            }
        }
    }

    /// Sets `span` up for the pixels `x0..x0 + n` of row `y` (`n` at most [`SPAN`]), each
    /// direction and reciprocal bit for bit what [`RayGrid::dir`] and [`Ray::new`] give.
    pub fn span(&self, y: usize, x0: usize, n: usize, span: &mut RaySpan) {
        let r = self.rows[y];
        let cols = &self.cols[x0..x0 + n];
        // Structure of arrays, and no early exit: each step is one operation over the span.
        let mut len = [0f64; SPAN];
        for i in 0..n {
            let v = cols[i] + r;
            span.d[0][i] = v.x;
            span.d[1][i] = v.y;
            span.d[2][i] = v.z;
        }
        for i in 0..n {
            let (x, y, z) = (span.d[0][i], span.d[1][i], span.d[2][i]);
            len[i] = 1.0 / ((x * x) + (y * y) + (z * z)).sqrt();
        }
        for a in 0..3 {
            for i in 0..n {
                let d = span.d[a][i] * len[i];
                span.d[a][i] = d;
                span.inv[a][i] = 1.0 / d;
            }
        }
        span.n = n;
    }
}

/// The rays of up to [`SPAN`] pixels of one row (see [`RayGrid::span`]).
pub struct RaySpan {
    d: [[f64; SPAN]; 3],
    inv: [[f64; SPAN]; 3],
    n: usize,
}

impl Default for RaySpan {
    fn default() -> Self {
        RaySpan {
            d: [[0.0; SPAN]; 3],
            inv: [[0.0; SPAN]; 3],
            n: 0,
        }
    }
}

impl RaySpan {
    /// Unit direction of the span's `i`th pixel.
    #[inline(always)]
    pub fn dir(&self, i: usize) -> DVec3 {
        debug_assert!(i < self.n);
        DVec3::new(self.d[0][i], self.d[1][i], self.d[2][i])
    }

    /// The span's `i`th pixel's ray from `o` with LOD factor `lod` ([`Ray::new`] bit for bit).
    #[inline(always)]
    pub fn ray(&self, i: usize, o: [f64; 3], lod: f64) -> Ray {
        debug_assert!(i < self.n);
        Ray {
            o,
            d: [self.d[0][i], self.d[1][i], self.d[2][i]],
            lod,
            inv: [self.inv[0][i], self.inv[1][i], self.inv[2][i]],
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use fathom_core::Camera;

    #[test]
    fn the_ray_grid_gives_the_cameras_directions_bit_for_bit() {
        let cam = Camera {
            eye: DVec3::new(0.3, -1.7, 2.9),
            target: DVec3::new(-0.2, 0.1, 0.05),
            ..Camera::default()
        };
        let frame = cam.frame();
        for (w, h) in [(640, 480), (33, 17), (1, 1)] {
            let grid = RayGrid::new(&frame, w, h);
            for y in 0..h as usize {
                for x in 0..w as usize {
                    let d = frame.ray_dir(x as f64 + 0.5, y as f64 + 0.5, w, h);
                    assert_eq!(grid.dir(x, y).to_array(), d.to_array(), "pixel {x},{y}");
                }
            }
        }
    }

    #[test]
    fn a_segment_visits_its_pixels_in_order_with_the_grids_rays() {
        let cam = Camera::default();
        let frame = cam.frame();
        let (w, h) = (3 * SPAN as u32 + 5, 4);
        let grid = RayGrid::new(&frame, w, h);
        let mut span = RaySpan::default();
        // Segments inside one span, across span boundaries, the whole row and an empty one.
        for (x0, n) in [(3, 9), (SPAN - 2, SPAN + 7), (0, w as usize), (17, 0)] {
            let mut seen = Vec::new();
            grid.segment(2, x0, n, [0.5; 3], 0.25, &mut span, |x, d, r| {
                let want = Ray::new([0.5; 3], grid.dir(x, 2).to_array(), 0.25);
                assert_eq!(d.to_array(), want.d, "pixel {x}");
                assert_eq!((r.d, r.inv), (want.d, want.inv), "pixel {x}");
                seen.push(x);
            });
            assert_eq!(seen, (x0..x0 + n).collect::<Vec<_>>());
        }
    }

    #[test]
    fn a_span_gives_the_grids_rays_bit_for_bit() {
        let cam = Camera {
            eye: DVec3::new(-2.1, 0.4, 1.3),
            target: DVec3::new(0.2, -0.3, 0.1),
            ..Camera::default()
        };
        let frame = cam.frame();
        let mut span = RaySpan::default();
        // Spans that fill the row exactly, one that ends short, and a one-pixel image.
        for (w, h) in [(2 * SPAN as u32, 3), (SPAN as u32 + 7, 5), (1, 1)] {
            let grid = RayGrid::new(&frame, w, h);
            for y in 0..h as usize {
                for x0 in (0..w as usize).step_by(SPAN) {
                    let n = SPAN.min(w as usize - x0);
                    grid.span(y, x0, n, &mut span);
                    for i in 0..n {
                        let d = grid.dir(x0 + i, y);
                        let want = Ray::new([1.0, 2.0, 3.0], d.to_array(), 0.5);
                        let got = span.ray(i, [1.0, 2.0, 3.0], 0.5);
                        assert_eq!(span.dir(i).to_array(), d.to_array(), "pixel {},{y}", x0 + i);
                        assert_eq!(
                            (got.d, got.inv, got.o, got.lod),
                            (want.d, want.inv, want.o, want.lod),
                            "pixel {},{y}",
                            x0 + i
                        );
                    }
                }
            }
        }
    }
}
