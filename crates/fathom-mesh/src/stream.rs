//! The streaming driver: one z-layer of bricks at a time, culled by the octree, sampled in
//! parallel, numbered in a fixed order (so the bytes do not depend on the thread count), and
//! stitched to the layer below, whose top slice of cells is all that is kept of it.

use crate::block::{Block, CellLookup, Field};
use crate::cull::Culler;
use crate::grid::{BRICK, BYTES_PER_BRICK, Grid, MemoryEstimate, human_bytes};
use crate::{IsoMeshError, MeshSink, Method, Vertex, Window};
use fathom_core::scene::Scene;
use fathom_core::{Evaluator, F32x8, Tape};
use glam::DVec3;
use rayon::prelude::*;
use std::collections::HashMap;
use std::time::Instant;

/// What to mesh and how.
#[derive(Clone, Debug, PartialEq)]
pub struct MeshOptions {
    /// Box to mesh; `None` fits it to the scene ([`crate::fit`]).
    pub bounds: Option<(DVec3, DVec3)>,
    /// Cells along the longest side.
    pub resolution: u32,
    pub method: Method,
    /// Evaluate vertex colours from materials and orbit traps.
    pub colours: bool,
    /// Refuse runs whose memory estimate exceeds this many bytes.
    pub max_memory: u64,
    /// Factor on the node radius in the culling test (larger culls less; 1 is exact for
    /// distance bounds).
    pub cull_margin: f64,
    /// Mesh the whole grid as one block without culling (the in-memory reference).
    pub in_memory: bool,
}

impl Default for MeshOptions {
    fn default() -> Self {
        MeshOptions {
            bounds: None,
            resolution: 256,
            method: Method::DualContouring,
            colours: true,
            max_memory: 4 << 30,
            cull_margin: 1.0,
            in_memory: false,
        }
    }
}

/// What a run did.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct MeshStats {
    pub cells: [u32; 3],
    pub voxel: f64,
    pub vertices: u64,
    pub triangles: u64,
    pub bricks_total: u64,
    pub bricks_meshed: u64,
    pub octree_nodes_tested: u64,
    pub evaluations: u64,
    /// Faces dropped because a cell they need was culled (0 when culling was sound).
    pub missing_faces: u64,
    pub seconds: f64,
}

/// A checked run: the grid and the memory estimate, made before anything large is allocated.
#[derive(Clone, Debug)]
pub struct Plan {
    pub grid: Grid,
    pub estimate: MemoryEstimate,
}

/// Validates the options, fits or checks the bounds, and estimates memory from a coarse
/// culling pass (at most 128 nodes per side); refuses the run if it exceeds `max_memory`.
pub fn plan(scene: &Scene, tape: &Tape, o: &MeshOptions) -> Result<Plan, IsoMeshError> {
    if !(o.cull_margin.is_finite() && (1.0..=16.0).contains(&o.cull_margin)) {
        return Err(IsoMeshError::Bounds(format!(
            "cull margin {} is out of range [1, 16]",
            o.cull_margin
        )));
    }
    let (lo, hi) = match o.bounds {
        Some(b) => b,
        None => crate::fit::fit_bounds(scene, tape)?,
    };
    let grid = Grid::new(lo, hi, o.resolution)?;
    let b = grid.bricks();
    let layer_index = (b[0] as u64 * b[1] as u64) * 16;
    let corners: u64 = grid.cells.iter().map(|&n| n as u64 + 1).product();
    let dense = corners * 4;
    let bricks_per_layer = if o.in_memory {
        b[0] as u64 * b[1] as u64
    } else {
        let mut c = Culler::new(tape, grid, o.cull_margin, false);
        // At most 128 coarse nodes per side, so the estimate costs little at any resolution;
        // each coarse node stands for up to 4^levels bricks of one layer (an upper estimate:
        // a flat face across a layer fills them all).
        let levels = c.top().saturating_sub(7).max(1).min(c.top());
        let mut most = 0u64;
        for z in (0..b[2]).step_by(1 << levels) {
            most = most.max(c.descend(z, levels).len() as u64);
        }
        (most << (2 * levels)).min(b[0] as u64 * b[1] as u64)
    };
    let estimate = if o.in_memory {
        MemoryEstimate {
            bricks_per_layer,
            fixed: 0,
            surface: dense * 8,
            dense,
        }
    } else {
        MemoryEstimate {
            bricks_per_layer,
            fixed: layer_index,
            surface: 2 * bricks_per_layer * BYTES_PER_BRICK,
            dense,
        }
    };
    if estimate.total() > o.max_memory {
        return Err(IsoMeshError::Memory {
            estimate: estimate.to_string(),
            limit: human_bytes(o.max_memory),
        });
    }
    Ok(Plan { grid, estimate })
}

/// What is kept of a meshed brick once its layer is done: its top slice of cells.
struct Top {
    cases: Vec<u8>,
    first: Vec<u64>,
}

/// Finds cells in the current layer's blocks and the previous layer's top slices.
struct Lookup<'a> {
    z: i64,
    blocks: &'a [Block],
    here: HashMap<[i64; 2], usize>,
    below: &'a HashMap<[i64; 2], Top>,
}

impl CellLookup for Lookup<'_> {
    fn cell(&self, g: [i64; 3]) -> Option<(u8, u64)> {
        let b = BRICK as i64;
        let key = [g[0].div_euclid(b), g[1].div_euclid(b)];
        let bz = g[2].div_euclid(b);
        if bz == self.z {
            let i = *self.here.get(&key)?;
            self.blocks[i].local(g)
        } else if bz == self.z - 1 && g[2].rem_euclid(b) == b - 1 {
            let t = self.below.get(&key)?;
            let i = (g[1].rem_euclid(b) * b + g[0].rem_euclid(b)) as usize;
            Some((t.cases[i], t.first[i]))
        } else {
            None
        }
    }
}

/// Meshes `scene` into `sink`, layer by layer. `progress(done, total)` is called per layer.
pub fn mesh(
    scene: &Scene,
    tape: &Tape,
    plan: &Plan,
    o: &MeshOptions,
    sink: &mut dyn MeshSink,
    progress: &(dyn Fn(u64, u64) + Sync),
) -> Result<MeshStats, IsoMeshError> {
    let start = Instant::now();
    let grid = plan.grid;
    let field = Field {
        tape,
        render: &scene.render,
        grid,
        method: o.method,
        colours: o.colours,
    };
    let b = grid.bricks();
    let mut stats = MeshStats {
        cells: grid.cells,
        voxel: grid.h,
        bricks_total: b.iter().map(|&v| v as u64).product(),
        ..MeshStats::default()
    };
    let mut next_id = 0u64;
    if o.in_memory {
        let mut ev = Evaluator::<F32x8>::new();
        let dims = grid.cells.map(|n| n as usize);
        let block = field.block(&mut ev, [0; 3], dims);
        if block.verts.len() as u64 > u32::MAX as u64 {
            return Err(IsoMeshError::TooManyVertices);
        }
        stats.evaluations = block.evals;
        stats.vertices = block.verts.len() as u64;
        sink.vertices(&block.verts)?;
        let (tris, missing) = block.faces(o.method, &NoNeighbours);
        stats.triangles = tris.len() as u64;
        stats.missing_faces = missing;
        let window = Window {
            first: 0,
            parts: [&block.verts, &[]],
        };
        sink.triangles(&tris, &window)?;
        stats.bricks_meshed = 1;
        stats.seconds = start.elapsed().as_secs_f64();
        progress(1, 1);
        sink.finish()?;
        return Ok(stats);
    }

    let mut culler = Culler::new(tape, grid, o.cull_margin, false);
    let mut below: HashMap<[i64; 2], Top> = HashMap::new();
    let mut below_verts: Vec<Vertex> = Vec::new();
    let mut below_first = 0u64;
    let b3 = BRICK * BRICK * BRICK;
    for z in 0..b[2] {
        let active = culler.layer(z);
        stats.bricks_meshed += active.len() as u64;
        let mut blocks: Vec<Block> = active
            .par_iter()
            .map_init(Evaluator::<F32x8>::new, |ev, n| {
                let cell0 = n.map(|v| v as i64 * BRICK as i64);
                field.block(ev, cell0, [BRICK; 3])
            })
            .collect();
        let layer_first = next_id;
        for blk in &mut blocks {
            blk.base = next_id;
            next_id += blk.verts.len() as u64;
            stats.evaluations += blk.evals;
        }
        if next_id > u32::MAX as u64 {
            return Err(IsoMeshError::TooManyVertices);
        }
        let layer_verts: Vec<Vertex> = blocks
            .iter()
            .flat_map(|b| b.verts.iter().copied())
            .collect();
        sink.vertices(&layer_verts)?;
        let here: HashMap<[i64; 2], usize> = blocks
            .iter()
            .enumerate()
            .map(|(i, blk)| {
                (
                    [blk.cell0[0] / BRICK as i64, blk.cell0[1] / BRICK as i64],
                    i,
                )
            })
            .collect();
        let look = Lookup {
            z: z as i64,
            blocks: &blocks,
            here,
            below: &below,
        };
        let faces: Vec<(Vec<[u32; 3]>, u64)> = blocks
            .par_iter()
            .map(|blk| blk.faces(o.method, &look))
            .collect();
        let window = Window {
            first: below_first,
            parts: [&below_verts, &layer_verts],
        };
        for (tris, missing) in &faces {
            stats.missing_faces += missing;
            stats.triangles += tris.len() as u64;
            sink.triangles(tris, &window)?;
        }
        drop(look);
        below = blocks
            .iter()
            .map(|blk| {
                let key = [blk.cell0[0] / BRICK as i64, blk.cell0[1] / BRICK as i64];
                let top = b3 - BRICK * BRICK..b3;
                let cases = blk.cases[top.clone()].to_vec();
                let first = blk.first[top]
                    .iter()
                    .map(|&f| blk.base + f as u64)
                    .collect();
                (key, Top { cases, first })
            })
            .collect();
        below_verts = layer_verts;
        below_first = layer_first;
        progress(z as u64 + 1, b[2] as u64);
    }
    stats.vertices = next_id;
    stats.octree_nodes_tested = culler.tested;
    stats.seconds = start.elapsed().as_secs_f64();
    sink.finish()?;
    Ok(stats)
}

/// The in-memory block has no neighbours.
struct NoNeighbours;

impl CellLookup for NoNeighbours {
    fn cell(&self, _: [i64; 3]) -> Option<(u8, u64)> {
        None
    }
}
