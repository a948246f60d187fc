//! fathom-micro: microgeometry. A triangle mesh gives an object its shape; any distance field
//! of the scene format (or a baked grid of one, or a chaos-game point cloud) is pasted over its
//! surface as a "distance-field texture", overhangs included, by raymarching inside a thin
//! shell of prisms over the mesh (Porumbescu et al. 2005's shell maps; the seed project
//! "Raymarched Microgeometry on Triangle Meshes"). `docs/micro.md` has the design and the
//! measurements.
//!
//! - [`mesh`]: OBJ and glTF loading, the built-in teapot and bush, cleaning, normals, UVs;
//! - [`shell`], [`tet`]: prisms split into tetrahedra without cracks, shell coordinates and the
//!   per-prism Lipschitz factor; [`bvh`]: the hierarchy the CPU rays start from;
//! - [`texture`], [`grid`], [`chaos`], [`anim`]: what can be pasted on, and how it tiles,
//!   bakes and moves;
//! - [`march`], [`shade`], [`render`]: the CPU renderer; [`alone`]: a texture on its own;
//! - [`gpu`]: the rasterising renderer on wgpu, marching in the fragment shader with
//!   fathom-gpu's WGSL tape interpreter;
//! - [`demo`]: the two shipped demos.
//!
//! A first use: the teapot demo (a sponge texture over the built-in teapot) prepared
//! from a [`request::Request`] and rendered small on the CPU.
//!
//! ```
//! use fathom_micro::request::{Prepared, Request};
//!
//! let request = Request {
//!     demo: Some("teapot".into()),
//!     width: 32,
//!     height: 24,
//!     ..Request::new()
//! };
//! let Prepared::Shell { scene, options, .. } = request.prepare()? else {
//!     unreachable!("a demo has a mesh")
//! };
//! let (frame, stats) = fathom_micro::render(&scene, &options, &|_, _| {})?;
//! assert_eq!((frame.width, frame.height), (32, 24));
//! assert!(stats.hits > 0);
//! # Ok::<(), fathom_micro::MicroError>(())
//! ```

#![warn(missing_docs)]

pub mod alone;
pub mod anim;
pub mod bvh;
pub mod cell;
pub mod chaos;
pub mod demo;
pub mod error;
pub mod gpu;
pub mod grid;
pub mod limits;
pub mod march;
pub mod mesh;
pub mod render;
pub mod request;
pub mod shade;
pub mod shell;
pub mod tet;
pub mod texture;

pub use error::{MeshLoadError, MicroError};
pub use mesh::{MeshReport, TriangleMesh, UvProjection};
pub use render::{MicroScene, MicroStats, RenderOptions, render};
pub use shell::Shell;
pub use texture::{Cell, Texture, Tiling};
