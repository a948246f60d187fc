//! The image buffers every renderer produces: linear colour plus the per-pixel geometry (depth,
//! normal, material id, step count) that shared post effects (fog, SSAO, tonemapping) and the
//! diagnostic outputs (masks, depth maps, step heat maps) read.

use serde::{Deserialize, Serialize};

/// A rectangle of pixels: columns `x .. x + width`, rows `y .. y + height`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Rect {
    /// The first column.
    pub x: u32,
    /// The first row.
    pub y: u32,
    /// Columns.
    pub width: u32,
    /// Rows.
    pub height: u32,
}

impl Rect {
    /// The whole of a `width` x `height` image.
    pub fn full(width: u32, height: u32) -> Rect {
        Rect {
            x: 0,
            y: 0,
            width,
            height,
        }
    }

    /// One past the last column.
    pub fn right(&self) -> u32 {
        self.x + self.width
    }

    /// One past the last row.
    pub fn bottom(&self) -> u32 {
        self.y + self.height
    }

    /// No pixels.
    pub fn is_empty(&self) -> bool {
        self.width == 0 || self.height == 0
    }

    /// Whether the rectangle lies inside a `width` x `height` image (overflow-safe).
    pub fn fits(&self, width: u32, height: u32) -> bool {
        (self.x as u64 + self.width as u64) <= width as u64
            && (self.y as u64 + self.height as u64) <= height as u64
    }

    /// The overlap of two rectangles (empty, at `self`'s origin, when they do not meet).
    pub fn intersect(&self, o: &Rect) -> Rect {
        let (x0, y0) = (self.x.max(o.x), self.y.max(o.y));
        let (x1, y1) = (self.right().min(o.right()), self.bottom().min(o.bottom()));
        if x1 <= x0 || y1 <= y0 {
            return Rect {
                x: self.x,
                y: self.y,
                width: 0,
                height: 0,
            };
        }
        Rect {
            x: x0,
            y: y0,
            width: x1 - x0,
            height: y1 - y0,
        }
    }

    /// Grown by `m` pixels on every side, then clipped to a `width` x `height` image.
    pub fn grown(&self, m: u32, width: u32, height: u32) -> Rect {
        let (x0, y0) = (self.x.saturating_sub(m), self.y.saturating_sub(m));
        let x1 = self.right().saturating_add(m).min(width);
        let y1 = self.bottom().saturating_add(m).min(height);
        Rect {
            x: x0,
            y: y0,
            width: x1.saturating_sub(x0),
            height: y1.saturating_sub(y0),
        }
    }

    /// Scaled by `k` (pixels to supersamples).
    pub fn scaled(&self, k: u32) -> Rect {
        Rect {
            x: self.x * k,
            y: self.y * k,
            width: self.width * k,
            height: self.height * k,
        }
    }

    /// Moved by (-dx, -dy): the same pixels in the coordinates of an image whose top-left
    /// corner is at (dx, dy).
    pub fn relative_to(&self, dx: u32, dy: u32) -> Rect {
        Rect {
            x: self.x - dx,
            y: self.y - dy,
            width: self.width,
            height: self.height,
        }
    }
}

/// Material id of a pixel whose ray hit nothing.
pub const NO_ID: u32 = u32::MAX;

/// A rendered image with its G-buffer, row-major, pixel (0, 0) at the top left.
#[derive(Clone, Debug, PartialEq)]
pub struct Frame {
    /// Columns, pixels.
    pub width: u32,
    /// Rows, pixels.
    pub height: u32,
    /// Linear RGB, not yet tonemapped.
    pub colour: Vec<[f32; 3]>,
    /// Distance along the (unit) ray from the eye to the hit; `f32::INFINITY` for a miss.
    pub depth: Vec<f32>,
    /// World-space unit normal at the hit; zero for a miss.
    pub normal: Vec<[f32; 3]>,
    /// Material id of the hit; [`NO_ID`] for a miss.
    pub id: Vec<u32>,
    /// Distance evaluations the primary ray took.
    pub steps: Vec<u32>,
}

impl Frame {
    /// A frame of misses: black, infinitely deep. The caller checks the size is sane first.
    pub fn new(width: u32, height: u32) -> Self {
        let n = width as usize * height as usize;
        Frame {
            width,
            height,
            colour: vec![[0.0; 3]; n],
            depth: vec![f32::INFINITY; n],
            normal: vec![[0.0; 3]; n],
            id: vec![NO_ID; n],
            steps: vec![0; n],
        }
    }

    /// Number of pixels.
    pub fn len(&self) -> usize {
        self.depth.len()
    }

    /// True for a zero-sized frame.
    pub fn is_empty(&self) -> bool {
        self.depth.is_empty()
    }

    /// Index of pixel (x, y).
    #[inline]
    pub fn index(&self, x: u32, y: u32) -> usize {
        y as usize * self.width as usize + x as usize
    }

    /// Copies every buffer's pixel `j` of `src` into pixel `i` of this frame (how frames are
    /// laid out and taken apart, one place that knows every buffer).
    #[inline]
    pub fn copy_pixel(&mut self, i: usize, src: &Frame, j: usize) {
        self.colour[i] = src.colour[j];
        self.depth[i] = src.depth[j];
        self.normal[i] = src.normal[j];
        self.id[i] = src.id[j];
        self.steps[i] = src.steps[j];
    }

    /// The pixels of `r` (which must lie inside the frame) as a frame of their own.
    pub fn crop(&self, r: Rect) -> Frame {
        assert!(
            r.fits(self.width, self.height),
            "crop {r:?} outside the frame"
        );
        if r == Rect::full(self.width, self.height) {
            return self.clone();
        }
        let mut f = Frame::new(r.width, r.height);
        for y in 0..r.height {
            for x in 0..r.width {
                let (i, j) = (f.index(x, y), self.index(r.x + x, r.y + y));
                f.copy_pixel(i, self, j);
            }
        }
        f
    }

    /// Copies `src` into this frame with its top-left pixel at (`x`, `y`) (it must fit).
    pub fn paste(&mut self, src: &Frame, x: u32, y: u32) {
        let r = Rect {
            x,
            y,
            width: src.width,
            height: src.height,
        };
        assert!(
            r.fits(self.width, self.height),
            "paste {r:?} outside the frame"
        );
        for sy in 0..src.height {
            for sx in 0..src.width {
                let (i, j) = (self.index(x + sx, y + sy), src.index(sx, sy));
                self.copy_pixel(i, src, j);
            }
        }
    }

    /// Whether the ray through pixel `i` hit a surface.
    #[inline]
    pub fn is_hit(&self, i: usize) -> bool {
        self.depth[i].is_finite()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn new_frame_is_all_misses() {
        let f = Frame::new(3, 2);
        assert_eq!(f.len(), 6);
        assert!((0..6).all(|i| !f.is_hit(i) && f.id[i] == NO_ID));
        assert_eq!(f.index(2, 1), 5);
    }

    #[test]
    fn crops_and_pastes_are_inverse_and_rects_clip() {
        let mut f = Frame::new(5, 4);
        for (i, s) in f.steps.iter_mut().enumerate() {
            *s = i as u32;
        }
        let r = Rect {
            x: 1,
            y: 2,
            width: 3,
            height: 2,
        };
        let c = f.crop(r);
        assert_eq!(c.steps, vec![11, 12, 13, 16, 17, 18]);
        let mut g = Frame::new(5, 4);
        g.paste(&c, 1, 2);
        assert_eq!(g.crop(r), c);
        assert_eq!(r.grown(2, 5, 4), Rect::full(5, 4));
        assert!(r.intersect(&Rect::full(1, 1)).is_empty());
        assert!(
            !Rect {
                x: u32::MAX,
                y: 0,
                width: 2,
                height: 1
            }
            .fits(10, 10)
        );
    }
}
