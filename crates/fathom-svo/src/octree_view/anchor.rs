//! Where the eye is, to more than f64 precision ([`DeepEye`]), and the anchor that box
//! coordinates are measured from, moved with the eye so boxes near it stay exact.

use super::OctreeView;
use crate::geometry::dim_at;
use crate::octree::Anchor;
use fathom_core::Camera;
use fathom_core::dd::Dd;
use glam::DVec3;

/// What a frame past f64 needs beyond its [`Camera`]: the eye is `cam.eye + eye_lo` (a
/// double-double position), and `scale` is the distance to what the view looks at (world
/// units; it places the anchor and sets the reach of ambient occlusion). Past zoom ~1e16 the
/// eye and its target are the same f64 point, so a deep camera looks along the zoom's
/// direction at a target one unit away and carries the true distance here.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DeepEye {
    /// Trailing part of the eye position (below an ulp of `cam.eye`).
    pub eye_lo: DVec3,
    /// Distance from the eye to what it looks at, world units.
    pub scale: f64,
}

impl DeepEye {
    /// An ordinary camera: no trailing part, the distance to its target.
    pub fn of(cam: &Camera) -> DeepEye {
        DeepEye {
            eye_lo: DVec3::ZERO,
            scale: (cam.target - cam.eye).length(),
        }
    }
}

/// How many levels above the eye's scale the anchor sits (see `OctreeView::place_anchor`): the
/// voxels the eye needs lie about 10 levels below that scale at 640x480, so boxes near the eye
/// reach about 46 levels below the anchor, within its exact span of 48
/// ([`crate::octree::ANCHOR_SPAN`]). Until the eye's scale is 37 levels below the root the
/// anchor is the root's corner and frames are evaluated in f64 exactly as before.
pub const ANCHOR_LEVELS_ABOVE: u8 = 36;

impl OctreeView {
    /// The eye in root units as double-double, from its world position `eye + eye_lo`.
    pub(super) fn eye_root_units(&self, eye: DVec3, eye_lo: DVec3) -> [Dd; 3] {
        let (m, s) = (self.tree.root_min, Dd::from(self.tree.root_size));
        [0, 1, 2].map(|a| (Dd::new(eye[a], eye_lo[a]) - Dd::from(m[a])) / s)
    }

    /// Moves the anchor (the lattice point box coordinates are measured from) with the eye:
    /// [`ANCHOR_LEVELS_ABOVE`] levels above the depth whose cells are the size of the eye's
    /// distance to its target, so every box a ray meets near the eye is a small exact dyadic
    /// (see [`crate::octree`]). It stays where it is while that depth changes by less than 4
    /// levels and the eye stays within its cell's neighbours; at depth 0 it is the root's
    /// corner (root units, the f64 path of shallow frames). Returns true when it moved.
    pub(super) fn place_anchor(&mut self, eye_u: &[Dd; 3], scale: f64) -> bool {
        let depth_e = (self.tree.root_size / scale).log2().floor();
        let want = (depth_e - ANCHOR_LEVELS_ABOVE as f64)
            .clamp(0.0, crate::octree::MAX_ANCHOR_DEPTH as f64) as u8;
        let cur = &self.tree.anchor;
        let near = {
            let o = cur.origin();
            let unit = dim_at(cur.depth);
            (0..3).all(|a| {
                let local = ((eye_u[a] - Dd::new(o[a].0, o[a].1)).hi) / unit;
                (-1.0..2.0).contains(&local)
            })
        };
        if (want == 0 && cur.depth == 0) || (want.abs_diff(cur.depth) < 4 && near && cur.depth > 0)
        {
            return false;
        }
        self.tree.anchor = if want == 0 {
            Anchor::default()
        } else {
            Anchor::at(want, eye_u.map(|x| x.hi), eye_u.map(|x| x.lo))
        };
        self.skip = None;
        true
    }
}
