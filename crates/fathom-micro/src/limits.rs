//! Documented limits on meshes and grids, checked before anything is allocated for them.

/// Largest mesh file read, in bytes (256 MiB).
pub const MAX_MESH_FILE_BYTES: u64 = 256 << 20;
/// Most triangles in one mesh (each becomes a prism of three tetrahedra).
pub const MAX_TRIANGLES: u64 = 1 << 20;
/// Most vertices in one mesh.
pub const MAX_VERTICES: u64 = 3 << 20;
/// Largest baked or point-cloud grid resolution per axis (512^3 f32 = 512 MiB).
pub const MAX_GRID: u32 = 512;
/// Most points of a chaos-game cloud.
pub const MAX_CLOUD_POINTS: u64 = 1 << 24;
/// Largest shell height relative to the mesh's bounding-box diagonal.
pub const MAX_SHELL_RELATIVE: f64 = 0.5;
/// Widest or tallest image, in pixels.
pub const MAX_SIDE: u32 = 16384;
/// Most pixels in one image.
pub const MAX_PIXELS: u64 = 64 << 20;
