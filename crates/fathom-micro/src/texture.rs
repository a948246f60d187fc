//! Distance-field textures and how shell space maps onto them.
//!
//! A texture is any distance field evaluated in its own "texture-scene" coordinates: a scene
//! file or preset compiled to a tape (exact), a baked grid of such a tape's distances
//! ([`crate::grid`]), or a chaos-game point cloud ([`crate::chaos`]). The [`Tiling`] says which
//! box of texture-scene space one tile fills: shell coordinates (u, h, v), with u and v already
//! multiplied by the tiles per UV unit, map to `cell.min + (fract(u), h, fract(v)) * cell.size`.
//! Rays are split where u or v cross a whole number, so each piece samples one tile and the
//! texture shows as clipped to its cell and repeated, with no seam in the distance bound.

use crate::chaos::Cloud;
use crate::error::{MicroError, check_range};
use crate::grid::Grid;
use fathom_core::scene::{Material, Scene};
use fathom_core::{Evaluator, Tape, V3};
use glam::DVec3;

pub use crate::cell::Cell;

/// How shell coordinates map to texture-scene space.
#[derive(Clone, Debug, PartialEq)]
pub struct Tiling {
    /// Tiles per unit of UV.
    pub tiles: f64,
    /// The box one tile fills (x along u, y along the shell height, z along v).
    pub cell: Cell,
}

impl Default for Tiling {
    fn default() -> Self {
        Tiling {
            tiles: 1.0,
            cell: Cell::UNIT,
        }
    }
}

impl Tiling {
    /// Checks the tile count and the cell's size.
    pub fn validate(&self) -> Result<(), MicroError> {
        check_range("tiles", self.tiles, 1e-6, 1e6, "[1e-6, 1e6] per UV unit")?;
        let s = self.cell.size();
        for v in [s.x, s.y, s.z] {
            check_range(
                "cell size",
                v,
                1e-9,
                1e9,
                "[1e-9, 1e9] along each axis (max > min)",
            )?;
        }
        if !(self.cell.min.is_finite() && self.cell.max.is_finite()) {
            return Err(MicroError::Range {
                name: "cell",
                value: format!("{:?}", self.cell),
                range: "finite corners",
            });
        }
        Ok(())
    }

    /// The texture-scene point of shell point `s` (tile units) in tile (`cu`, `cv`).
    #[inline]
    pub fn scene_point(&self, s: DVec3, cu: f64, cv: f64) -> DVec3 {
        self.cell.min + DVec3::new(s.x - cu, s.y, s.z - cv) * self.cell.size()
    }
}

/// Where a texture's distances come from.
pub enum Field {
    /// A compiled scene, evaluated exactly.
    Tape(Tape),
    /// Trilinear samples of a distance field.
    Grid(Grid),
    /// Distance to a chaos-game point cloud.
    Cloud(Cloud),
}

/// A distance-field texture with its materials.
pub struct Texture {
    /// Where the distances come from.
    pub field: Field,
    /// Materials by id (the tape's; one for grids without ids and clouds).
    pub materials: Vec<Material>,
    /// Where it came from, for reports.
    pub origin: String,
}

impl Texture {
    /// A scene (file or preset) as an exact texture.
    pub fn from_scene(scene: &Scene, origin: &str) -> Result<Texture, MicroError> {
        let tape = Tape::compile(scene).map_err(|e| MicroError::Texture {
            origin: origin.into(),
            msg: e.to_string(),
        })?;
        Ok(Texture {
            materials: tape.materials().to_vec(),
            field: Field::Tape(tape),
            origin: origin.into(),
        })
    }

    /// The field's own Lipschitz bound: 1 for tapes and clouds (distance bounds), sqrt(3) for
    /// trilinear grids (each partial derivative of the interpolant is a weighted mean of
    /// 1-Lipschitz differences).
    pub fn field_lipschitz(&self) -> f64 {
        match &self.field {
            Field::Grid(_) => 3f64.sqrt(),
            _ => 1.0,
        }
    }

    /// A distance bound at texture-scene point `q`, already divided by the field's own
    /// Lipschitz factor.
    #[inline]
    pub fn distance(&self, ev: &mut Evaluator<f64>, q: DVec3) -> f64 {
        match &self.field {
            Field::Tape(t) => ev.distance(t, V3::new(q.x, q.y, q.z)),
            Field::Grid(g) => g.sample(q) / 3f64.sqrt(),
            Field::Cloud(c) => c.distance(q),
        }
    }

    /// The material id at `q`.
    pub fn material_id(&self, ev: &mut Evaluator<f64>, q: DVec3) -> u32 {
        let id = match &self.field {
            Field::Tape(t) => ev.eval(t, V3::new(q.x, q.y, q.z)).id.max(0.0) as u32,
            Field::Grid(g) => g.material_at(q) as u32,
            Field::Cloud(_) => 0,
        };
        id.min(self.materials.len().saturating_sub(1) as u32)
    }

    /// The unit normal at `q` in texture-scene space (tetrahedron technique, offset `h`).
    pub fn normal(&self, ev: &mut Evaluator<f64>, q: DVec3, h: f64) -> DVec3 {
        let mut n = DVec3::ZERO;
        for e in TETRA {
            n += e * self.distance(ev, q + e * h);
        }
        n.normalize_or(DVec3::Y)
    }

    /// The tape, for the GPU path.
    pub fn tape(&self) -> Option<&Tape> {
        match &self.field {
            Field::Tape(t) => Some(t),
            _ => None,
        }
    }
}

/// The four offsets of the tetrahedron normal technique, in fathom-core's order (the WGSL
/// mirrors it).
pub const TETRA: [DVec3; 4] = [
    DVec3::new(1.0, -1.0, -1.0),
    DVec3::new(-1.0, -1.0, 1.0),
    DVec3::new(-1.0, 1.0, -1.0),
    DVec3::new(1.0, 1.0, 1.0),
];
