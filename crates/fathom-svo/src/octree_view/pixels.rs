//! A render's per-pixel buffers (colour, depth, smoothing widths, settling marks): kept from
//! one frame to the next, and cut into bands of rows for the threads.

use rayon::prelude::*;

/// Per-pixel buffers a render fills, kept between frames. Allocated afresh, a 640x480
/// frame's 3 MB came as new zeroed pages from the kernel every frame, about 650 page faults
/// a frame (2.4 s of system time in a 1000-frame zoom's 36 s).
#[derive(Default)]
pub(super) struct FrameBuffers {
    /// Colour and depth of a returned image handed back by [`OctreeView::recycle`].
    pub(super) image: Option<(Vec<u32>, Vec<f32>)>,
    /// Each pixel's smoothing half-width.
    pub(super) half: Vec<u8>,
    /// Pixels marked not yet settled.
    pub(super) marks: Vec<u8>,
}

/// `v` holding `n` zeros, reusing its allocation.
pub(super) fn zeroed<T: Copy + Default>(mut v: Vec<T>, n: usize) -> Vec<T> {
    v.clear();
    v.resize(n, T::default());
    v
}

/// One row of a frame's per-pixel buffers, as a render fills it.
pub(super) struct PixelRow<'a> {
    pub(super) colour: &'a mut [u32],
    pub(super) depth: &'a mut [f32],
    /// Box half-widths for [`Smoother::smooth`] (0: keep the pixel).
    pub(super) half: &'a mut [u8],
    /// 1: not yet settled (the next settling probe casts the pixel).
    pub(super) marks: &'a mut [u8],
}

/// A band of whole rows of a frame's per-pixel buffers, `width` pixels a row.
pub(super) struct PixelBand<'a> {
    pub(super) colour: &'a mut [u32],
    pub(super) depth: &'a mut [f32],
    pub(super) half: &'a mut [u8],
    pub(super) marks: &'a mut [u8],
    pub(super) width: usize,
}

impl PixelBand<'_> {
    pub(super) fn rows(&self) -> usize {
        self.colour.len() / self.width
    }

    /// The band's `j`th row.
    pub(super) fn row(&mut self, j: usize) -> PixelRow<'_> {
        let r = j * self.width..(j + 1) * self.width;
        PixelRow {
            colour: &mut self.colour[r.clone()],
            depth: &mut self.depth[r.clone()],
            half: &mut self.half[r.clone()],
            marks: &mut self.marks[r],
        }
    }
}

/// `rows`-row bands of a frame's per-pixel buffers (colour, depth, smoothing half-widths and
/// marks), `width` pixels a row, for the threads.
pub(super) fn bands<'a>(
    (colour, depth, half, marks): (&'a mut [u32], &'a mut [f32], &'a mut [u8], &'a mut [u8]),
    width: usize,
    rows: usize,
) -> impl IndexedParallelIterator<Item = PixelBand<'a>> {
    let n = rows * width;
    colour
        .par_chunks_mut(n)
        .zip(depth.par_chunks_mut(n))
        .zip(half.par_chunks_mut(n))
        .zip(marks.par_chunks_mut(n))
        .map(move |(((colour, depth), half), marks)| PixelBand {
            colour,
            depth,
            half,
            marks,
            width,
        })
}
