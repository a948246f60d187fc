//! [`Cell`]: a box of texture-scene space, the box one tile of a texture fills and the box a
//! grid or point cloud covers.

use glam::DVec3;

/// A box of texture-scene space.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Cell {
    /// The lowest corner.
    pub min: DVec3,
    /// The highest corner.
    pub max: DVec3,
}

impl Cell {
    /// The cube [-1, 1]^3, which most presets fill.
    pub const UNIT: Cell = Cell {
        min: DVec3::splat(-1.0),
        max: DVec3::splat(1.0),
    };

    /// The box's extent along each axis.
    pub fn size(&self) -> DVec3 {
        self.max - self.min
    }
}
