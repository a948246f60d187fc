//! What a settling loop at a fixed camera keeps between its probes ([`Settling`]): the pixels
//! whose voxel could still change, the only ones its next probe casts.

/// Which pixels the next probe of a settling loop casts
/// ([`OctreeView::probe_settling`](crate::OctreeView::probe_settling)). Keep one per loop at one
/// camera; a fresh one casts every pixel.
#[derive(Clone, Debug, Default)]
pub struct Settling {
    /// The pixels (`y * width + x`) whose voxel was wider than their footprint at the last
    /// probe; `None` before the first.
    pub(super) pixels: Option<Vec<u32>>,
}

impl Settling {
    /// Pixels still on voxels wider than their footprint at the last probe (`None` before
    /// the first): they only ever leave, so `width * height` minus this is a settling loop's
    /// progress.
    pub fn pending(&self) -> Option<usize> {
        self.pixels.as_ref().map(Vec::len)
    }
}

/// The LOD factor past which a settling probe counts a pixel's voxel as one that may still
/// change: its side over its distance reaches `lod / (1 + 2 lod)`, not `lod`. A voxel no
/// wider than this pixel's footprint can still be asked for by a ray that meets it nearer, up
/// to its diagonal (`sqrt 3` sides) nearer; split, it may turn out empty, and this pixel's ray
/// would then go on past it.
pub(super) fn settling_wide(lod: f64) -> f64 {
    lod / (1.0 + 2.0 * lod)
}

/// Pixels a worker casts at a time in a settling probe (a unit of rayon's work sharing).
pub(super) const SETTLING_CHUNK: usize = 256;

/// Pixels a settling probe casts between its checks of a stop
/// ([`OctreeView::probe_settling_until`](crate::OctreeView::probe_settling_until)): a tenth of a
/// 640x480 frame's rays.
pub const PROBE_SLICE: usize = 1 << 15;
