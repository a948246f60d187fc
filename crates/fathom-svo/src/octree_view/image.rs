//! A rendered frame of the octree ([`SvoImage`]) and its conversions to the shared frame type
//! and to sRGB bytes.

/// A rendered frame: colours (RGBA8, linear) and world depth (`f32::INFINITY` for sky).
#[derive(Clone, Debug, PartialEq)]
pub struct SvoImage {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// RGBA8 linear colours, row-major from the top-left.
    pub colour: Vec<u32>,
    /// Distance along the ray in world units.
    pub depth: Vec<f32>,
    /// The largest voxel any pixel shows, in pixels: its side over the pixel footprint at the
    /// distance where the ray met it (0 when nothing was hit; at most [`MAX_VOXEL_PX`]).
    pub largest_voxel_px: f64,
}

impl SvoImage {
    /// Silhouette mask: true where a voxel was hit.
    pub fn mask(&self) -> Vec<bool> {
        self.depth.iter().map(|d| d.is_finite()).collect()
    }

    /// The shared frame type, so the post effects of the sphere tracer (fog, SSAO, tonemap)
    /// and its output writers apply to octree renders too. Voxels carry no normal or id: the
    /// normal is zero, the id 0 for hits.
    pub fn to_frame(&self) -> fathom_core::frame::Frame {
        let mut f = fathom_core::frame::Frame::new(self.width, self.height);
        for (i, (&c, &d)) in self.colour.iter().zip(&self.depth).enumerate() {
            f.colour[i] = std::array::from_fn(|k| ((c >> (8 * k)) & 255) as f32 / 255.0);
            f.depth[i] = d;
            if d.is_finite() {
                f.id[i] = 0;
            }
        }
        f
    }

    /// 8-bit sRGB bytes (RGB), for PNG output.
    pub fn to_srgb8(&self) -> Vec<u8> {
        let mut out = Vec::with_capacity(self.colour.len() * 3);
        for &c in &self.colour {
            for i in 0..3 {
                let v = ((c >> (8 * i)) & 255) as f64 / 255.0;
                out.push((v.powf(1.0 / 2.2) * 255.0 + 0.5) as u8);
            }
        }
        out
    }
}

/// Voxels seen from closer than this many pixel footprints' worth (the eye inside a full
/// voxel, `t` = 0) count as this many pixels: keeps the figure finite for JSON.
pub const MAX_VOXEL_PX: f64 = 1e6;
