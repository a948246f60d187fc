//! The image buffers every renderer produces: linear colour plus the per-pixel geometry (depth,
//! normal, material id, step count) that shared post effects (fog, SSAO, tonemapping) and the
//! diagnostic outputs (masks, depth maps, step heat maps) read.

/// Material id of a pixel whose ray hit nothing.
pub const NO_ID: u32 = u32::MAX;

/// A rendered image with its G-buffer, row-major, pixel (0, 0) at the top left.
#[derive(Clone, Debug, PartialEq)]
pub struct Frame {
    pub width: u32,
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
}
