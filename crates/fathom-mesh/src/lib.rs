//! fathom-mesh: triangle meshes (and voxel grids) of any fathom scene, fractals included, at
//! any resolution in memory that follows the surface, not the N^3 volume.
//!
//! - [`grid`]: bounds, resolution, limits and the memory estimate checked before allocation;
//! - [`cull`]: the octree over bricks that skips space the distance bound proves empty;
//! - [`table`]: the marching-cubes cases and their loops, derived from one rule per face;
//! - [`block`]: sampling a brick, its cells' cases and vertices (marching cubes, surface nets,
//!   dual contouring), and the faces each cell owns;
//! - [`stream`]: the layer-by-layer driver that numbers vertices, stitches bricks and hands
//!   vertices and triangles to a [`MeshSink`] as soon as they are final;
//! - [`write`]: PLY, STL, OBJ and GLB sinks;
//! - [`check`]: closed-manifold checks and Hausdorff distances, for tests and benchmarks;
//! - [`fit`]: bounds fitted to a scene;
//! - [`simplify`]: simplification to a triangle budget (meshoptimizer), the triangle-count
//!   and file-size estimates made before meshing, and mesh-to-mesh Hausdorff distances.
//!
//! What is guaranteed (and tested): the corner signs define the surface; each cube face's
//! contour depends on that face's corners only, so neighbouring cells agree and every mesh is
//! closed where culling was sound. Marching cubes output is a closed, consistently oriented
//! 2-manifold by index (every edge in exactly two triangles, once in each direction).
//! Dual contouring and surface nets put one vertex per loop of a cell (not per cell), which
//! keeps separate sheets apart; their output is closed and oriented, and 2-manifold except where
//! one loop crosses an ambiguous face twice on both sides (a tunnel through two cells), which
//! the checks count. Culling is sound for scenes whose estimate is a distance bound; for
//! estimators with a safety factor (Mandelbulb, Mandelbox) a face that would need a culled cell
//! is dropped and counted in [`MeshStats::missing_faces`].

pub mod block;
pub mod check;
pub mod cull;
pub mod fit;
pub mod grid;
pub mod simplify;
pub mod stream;
pub mod table;
pub mod write;

pub use grid::{Grid, MemoryEstimate};
pub use stream::{MeshOptions, MeshStats, Plan, mesh, plan};
use thiserror::Error;

/// How vertices are placed.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Method {
    /// Lorensen and Cline: vertices on the grid edges, triangles per cell. The watertight
    /// manifold baseline.
    MarchingCubes,
    /// One vertex per loop at the mean of its crossings; quads across sign-changing edges.
    SurfaceNets,
    /// As surface nets, with each vertex at the minimiser of its crossings' tangent-plane error
    /// (normals from the tape's gradient), which keeps sharp edges and corners.
    DualContouring,
}

impl Method {
    pub const ALL: [Method; 3] = [
        Method::MarchingCubes,
        Method::SurfaceNets,
        Method::DualContouring,
    ];
    pub fn name(self) -> &'static str {
        match self {
            Method::MarchingCubes => "marching-cubes",
            Method::SurfaceNets => "surface-nets",
            Method::DualContouring => "dual-contouring",
        }
    }
}

/// A mesh vertex: position and sRGB colour.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Vertex {
    pub p: [f32; 3],
    pub colour: [u8; 3],
}

/// Why a mesh could not be made or written.
#[derive(Debug, Error)]
pub enum IsoMeshError {
    #[error(
        "--resolution {0} is out of range [{min}, {max}]",
        min = grid::MIN_RESOLUTION,
        max = grid::MAX_RESOLUTION
    )]
    Resolution(u32),
    #[error("{0}")]
    Bounds(String),
    #[error(
        "the mesh would need {estimate}; that is more than --max-memory {limit} (lower \
         --resolution, shrink --bounds or raise --max-memory)"
    )]
    Memory { estimate: String, limit: String },
    #[error("the mesh has more than {max} vertices, more than the output formats can index", max = u32::MAX)]
    TooManyVertices,
    #[error("{path}: {source}")]
    Io {
        path: String,
        #[source]
        source: std::io::Error,
    },
    #[error("{path}: {msg}")]
    Format { path: String, msg: String },
    #[error("{0}")]
    Simplify(String),
    #[error("invalid scene: {0}")]
    Scene(String),
    /// The output could not be created or put in place (an existing file is unchanged).
    #[error(transparent)]
    Write(#[from] fathom_core::atomic_file::WriteError),
}

/// Receives a mesh as it is made: vertices in id order, then triangles that use them.
pub trait MeshSink: Send {
    /// New vertices; the first has id = number of vertices sent before.
    fn vertices(&mut self, v: &[Vertex]) -> Result<(), IsoMeshError>;
    /// Triangles (counter-clockwise seen from outside) over ids sent so far; `window` holds
    /// every vertex they use.
    fn triangles(&mut self, t: &[[u32; 3]], window: &Window) -> Result<(), IsoMeshError>;
    /// Called once after the last triangle.
    fn finish(&mut self) -> Result<(), IsoMeshError>;
}

/// The vertices recent triangles may use: ids `first .. first + verts.len()`.
pub struct Window<'a> {
    pub first: u64,
    pub parts: [&'a [Vertex]; 2],
}

impl Window<'_> {
    /// The vertex with id `id` (which must be in the window).
    #[inline]
    pub fn get(&self, id: u32) -> &Vertex {
        let i = (id as u64 - self.first) as usize;
        let a = self.parts[0];
        if i < a.len() {
            &a[i]
        } else {
            &self.parts[1][i - a.len()]
        }
    }
}

/// A whole mesh in memory.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct IsoMesh {
    pub verts: Vec<Vertex>,
    pub tris: Vec<[u32; 3]>,
}

impl MeshSink for IsoMesh {
    fn vertices(&mut self, v: &[Vertex]) -> Result<(), IsoMeshError> {
        self.verts.extend_from_slice(v);
        Ok(())
    }
    fn triangles(&mut self, t: &[[u32; 3]], _: &Window) -> Result<(), IsoMeshError> {
        self.tris.extend_from_slice(t);
        Ok(())
    }
    fn finish(&mut self) -> Result<(), IsoMeshError> {
        Ok(())
    }
}

/// Counts without keeping anything (benchmarks of the mesher alone).
#[derive(Clone, Copy, Debug, Default)]
pub struct Counter {
    pub verts: u64,
    pub tris: u64,
}

impl MeshSink for Counter {
    fn vertices(&mut self, v: &[Vertex]) -> Result<(), IsoMeshError> {
        self.verts += v.len() as u64;
        Ok(())
    }
    fn triangles(&mut self, t: &[[u32; 3]], _: &Window) -> Result<(), IsoMeshError> {
        self.tris += t.len() as u64;
        Ok(())
    }
    fn finish(&mut self) -> Result<(), IsoMeshError> {
        Ok(())
    }
}

#[cfg(test)]
mod tests;
