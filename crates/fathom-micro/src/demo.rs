//! The two demos that ship with the repository: the Utah teapot wearing a Menger-sponge
//! texture, and a bush whose leaves overhang its surface. Each is a built-in mesh, a texture
//! scene file in `crates/fathom-micro/demos/`, a shell height, a tiling and a camera.

use crate::error::MicroError;
use crate::mesh::{self, MeshReport, TriangleMesh};
use crate::texture::{Cell, Tiling};
use fathom_core::scene::{Material, Scene};
use fathom_core::scene_file;
use glam::DVec3;

/// A demo's ingredients.
pub struct Demo {
    /// The name `--demo` takes.
    pub name: &'static str,
    /// The base mesh.
    pub mesh: TriangleMesh,
    /// What cleaning the mesh found.
    pub mesh_report: MeshReport,
    /// The texture scene.
    pub texture: Scene,
    /// Where the texture came from, for messages.
    pub texture_origin: String,
    /// Height of the shell over the mesh, mesh units.
    pub shell_height: f64,
    /// How the texture tiles the mesh's UVs.
    pub tiling: Tiling,
    /// Direction from the object's centre to the camera.
    pub view_from: DVec3,
    /// The base mesh's material.
    pub base: Material,
}

/// (name, mesh, texture file text, shell height, tiles per UV unit, view direction, base colour)
type Spec = (
    &'static str,
    &'static str,
    &'static str,
    f64,
    f64,
    [f64; 3],
    [f64; 3],
);

/// Every demo.
pub const DEMOS: &[Spec] = &[
    (
        "teapot",
        "teapot",
        include_str!("../demos/teapot-sponge.ron"),
        0.06,
        1.0,
        [1.0, 0.75, 1.7],
        [0.45, 0.38, 0.32],
    ),
    (
        "bush",
        "bush",
        include_str!("../demos/bush-leaves.ron"),
        0.12,
        1.0,
        [0.9, 0.55, 1.5],
        [0.18, 0.14, 0.08],
    ),
];

/// The demo called `name`; unknown names list the valid ones.
pub fn load(name: &str) -> Result<Demo, MicroError> {
    let spec = DEMOS
        .iter()
        .find(|d| d.0 == name)
        .ok_or_else(|| MicroError::Texture {
            origin: name.into(),
            msg: format!(
                "no such demo; expected one of: {}",
                DEMOS.iter().map(|d| d.0).collect::<Vec<_>>().join(", ")
            ),
        })?;
    let (mesh, mesh_report) = mesh::load(spec.1, None)?;
    let origin = format!("<demo:{}>", spec.0);
    let texture = scene_file::parse(spec.2, &origin).map_err(|e| MicroError::Texture {
        origin: origin.clone(),
        msg: e.to_string(),
    })?;
    Ok(Demo {
        name: spec.0,
        mesh,
        mesh_report,
        texture,
        texture_origin: origin,
        shell_height: spec.3,
        tiling: Tiling {
            tiles: spec.4,
            cell: Cell::UNIT,
        },
        view_from: DVec3::from_array(spec.5),
        base: Material {
            albedo: spec.6,
            specular: 0.1,
            shininess: 16.0,
            trap_colour: 0.0,
            ..Material::default()
        },
    })
}
