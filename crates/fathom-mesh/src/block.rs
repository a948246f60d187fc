//! One block of cells: sampling its corners (eight points per tape run), the sign-changing
//! edges with their crossing points and normals, each cell's case and vertices, and the faces
//! a cell owns.
//!
//! Vertex ownership, shared by every method, makes blocks stitch without seams: a cell owns the
//! vertices of its own loops (dual methods) or of the three cube edges through its corner
//! `(0, 1, 1)`, `(1, 0, 1)`, `(1, 1, 0)` (marching cubes), and the faces it emits reference only
//! itself and its neighbours at offsets in `{-1, 0}^3`. So a block needs the vertex numbering of
//! the blocks below it in x, y and z and nothing above, which is what streaming by layers needs.

use crate::grid::Grid;
use crate::table::{CASES, EDGES, corner};
use crate::{Method, Vertex};
use fathom_core::real::Real;
use fathom_core::scene::RenderSettings;
use fathom_core::{Evaluator, F32x8, Tape, V3};
use glam::{DMat3, DVec3};

/// Cube edges a cell owns under marching cubes (one per axis, through the corner `(0,1,1)`,
/// `(1,0,1)`, `(1,1,0)`).
pub const OWNED_EDGES: [usize; 3] = [3, 7, 11];

/// What evaluation needs, shared by every block of a run.
pub struct Field<'a> {
    pub tape: &'a Tape,
    pub render: &'a RenderSettings,
    pub grid: Grid,
    pub method: Method,
    pub colours: bool,
}

/// A block's cells after sampling: cases, vertex numbering and vertices.
#[derive(Debug, Default)]
pub struct Block {
    /// Global index of the block's first cell.
    pub cell0: [i64; 3],
    /// Cells per axis.
    pub dims: [usize; 3],
    /// Inside mask of each cell's corners, x fastest.
    pub cases: Vec<u8>,
    /// Index (within the block) of each cell's first vertex.
    pub first: Vec<u32>,
    pub verts: Vec<Vertex>,
    /// Global id of the block's first vertex, once numbered.
    pub base: u64,
    /// Distance evaluations spent.
    pub evals: u64,
}

/// How many vertices a cell of this case owns.
#[inline]
pub fn slots(method: Method, case: u8) -> u32 {
    let c = &CASES[case as usize];
    match method {
        Method::MarchingCubes => OWNED_EDGES
            .iter()
            .filter(|&&e| c.loop_of_edge[e] != u8::MAX)
            .count() as u32,
        Method::SurfaceNets | Method::DualContouring => c.loops.len() as u32,
    }
}

/// Bisection steps for crossings next to an escape-time "inside" (1/64 of an edge).
const BISECTIONS: usize = 6;

/// Inside the surface: a negative estimate, or zero, which escape-time estimators (the
/// Mandelbulb) return for points that never escape.
#[inline]
pub fn inside(d: f32) -> bool {
    d <= 0.0
}

/// Evaluates distances at `pts` in packets of eight.
fn distances(ev: &mut Evaluator<F32x8>, tape: &Tape, pts: &[DVec3], out: &mut Vec<f32>) {
    for chunk in pts.chunks(8) {
        let p = packet(chunk);
        let d = ev.distance(tape, p);
        out.extend((0..chunk.len()).map(|l| d.lane(l) as f32));
    }
}

/// Eight points as one packet (a short chunk repeats its last point).
fn packet(chunk: &[DVec3]) -> V3<F32x8> {
    let lane = |f: fn(&DVec3) -> f64| {
        let v: Vec<f64> = (0..8).map(|l| f(&chunk[l.min(chunk.len() - 1)])).collect();
        F32x8::from_lanes(&v)
    };
    V3::new(lane(|p| p.x), lane(|p| p.y), lane(|p| p.z))
}

/// A crossing of the surface on a grid edge.
#[derive(Clone, Copy, Debug)]
struct Crossing {
    p: DVec3,
    n: DVec3,
}

impl Field<'_> {
    /// Samples and meshes the cells `cell0 .. cell0 + dims` (vertices only; faces come from
    /// [`Block::faces`] once every neighbour is numbered).
    pub fn block(&self, ev: &mut Evaluator<F32x8>, cell0: [i64; 3], dims: [usize; 3]) -> Block {
        let g = &self.grid;
        let cd = dims.map(|d| d + 1);
        let ci = |x: usize, y: usize, z: usize| (z * cd[1] + y) * cd[0] + x;
        let mut pts = Vec::with_capacity(cd[0] * cd[1] * cd[2]);
        for z in 0..cd[2] {
            for y in 0..cd[1] {
                for x in 0..cd[0] {
                    let c = [
                        cell0[0] + x as i64,
                        cell0[1] + y as i64,
                        cell0[2] + z as i64,
                    ];
                    pts.push(g.corner(c));
                }
            }
        }
        let mut vals = Vec::with_capacity(pts.len());
        distances(ev, self.tape, &pts, &mut vals);
        let mut evals = pts.len() as u64;
        for z in 0..cd[2] {
            for y in 0..cd[1] {
                for x in 0..cd[0] {
                    let c = [
                        cell0[0] + x as i64,
                        cell0[1] + y as i64,
                        cell0[2] + z as i64,
                    ];
                    let v = &mut vals[ci(x, y, z)];
                    if v.is_nan() {
                        *v = 1.0;
                    }
                    if g.is_boundary(c) {
                        *v = v.max(f32::MIN_POSITIVE);
                    }
                }
            }
        }

        // Crossings on sign-changing edges, indexed by corner * 3 + axis.
        let mut edge_of = vec![u32::MAX; vals.len() * 3];
        let mut crossings: Vec<Crossing> = Vec::new();
        let mut bisect: Vec<(usize, DVec3, DVec3)> = Vec::new();
        for z in 0..cd[2] {
            for y in 0..cd[1] {
                for x in 0..cd[0] {
                    let i = ci(x, y, z);
                    for (axis, step) in [(0, [1, 0, 0]), (1, [0, 1, 0]), (2, [0, 0, 1])] {
                        let (x1, y1, z1) = (x + step[0], y + step[1], z + step[2]);
                        if x1 >= cd[0] || y1 >= cd[1] || z1 >= cd[2] {
                            continue;
                        }
                        let j = ci(x1, y1, z1);
                        let (a, b) = (vals[i], vals[j]);
                        if inside(a) == inside(b) {
                            continue;
                        }
                        edge_of[i * 3 + axis] = crossings.len() as u32;
                        if a == 0.0 || b == 0.0 {
                            // An escape-time estimate says "inside" without a distance:
                            // locate the crossing by bisection below.
                            let (pin, pout) = if inside(a) { (i, j) } else { (j, i) };
                            bisect.push((crossings.len(), pts[pin], pts[pout]));
                        }
                        let t = (a as f64 / (a as f64 - b as f64)).clamp(0.0, 1.0);
                        crossings.push(Crossing {
                            p: pts[i] + (pts[j] - pts[i]) * t,
                            n: DVec3::ZERO,
                        });
                    }
                }
            }
        }
        evals += self.bisect(ev, &mut bisect, &mut crossings);
        if self.method == Method::DualContouring {
            let eps = <F32x8 as Real>::splat(0.25 * g.h);
            for chunk in crossings.chunks_mut(8) {
                let pts: Vec<DVec3> = chunk.iter().map(|c| c.p).collect();
                let n = ev.normal(self.tape, packet(&pts), eps);
                for (l, c) in chunk.iter_mut().enumerate() {
                    c.n = DVec3::new(n.x.lane(l), n.y.lane(l), n.z.lane(l));
                }
                evals += 4 * pts.len() as u64;
            }
        }

        let ncells = dims[0] * dims[1] * dims[2];
        let mut cases = vec![0u8; ncells];
        let mut first = vec![0u32; ncells];
        let mut positions: Vec<DVec3> = Vec::new();
        let mut cell = 0;
        for z in 0..dims[2] {
            for y in 0..dims[1] {
                for x in 0..dims[0] {
                    let mut case = 0u8;
                    for c in 0..8 {
                        let [dx, dy, dz] = corner(c);
                        if inside(vals[ci(x + dx, y + dy, z + dz)]) {
                            case |= 1 << c;
                        }
                    }
                    cases[cell] = case;
                    first[cell] = positions.len() as u32;
                    let crossing = |e: usize| {
                        let (axis, c) = EDGES[e];
                        let [dx, dy, dz] = corner(c);
                        crossings[edge_of[ci(x + dx, y + dy, z + dz) * 3 + axis] as usize]
                    };
                    let k = &CASES[case as usize];
                    match self.method {
                        Method::MarchingCubes => {
                            for e in OWNED_EDGES {
                                if k.loop_of_edge[e] != u8::MAX {
                                    positions.push(crossing(e).p);
                                }
                            }
                        }
                        Method::SurfaceNets | Method::DualContouring => {
                            let lo = g.corner([
                                cell0[0] + x as i64,
                                cell0[1] + y as i64,
                                cell0[2] + z as i64,
                            ]);
                            for lp in &k.loops {
                                let cs: Vec<Crossing> =
                                    lp.iter().map(|&e| crossing(e as usize)).collect();
                                positions.push(self.place(&cs, lo));
                            }
                        }
                    }
                    cell += 1;
                }
            }
        }
        let colours = if self.colours {
            evals += positions.len() as u64;
            self.colours(ev, &positions)
        } else {
            vec![[200; 3]; positions.len()]
        };
        let verts = positions
            .iter()
            .zip(colours)
            .map(|(p, colour)| Vertex {
                p: p.as_vec3().to_array(),
                colour,
            })
            .collect();
        Block {
            cell0,
            dims,
            cases,
            first,
            verts,
            base: 0,
            evals,
        }
    }

    /// Moves the crossings of edges with an "inside, distance unknown" end (estimate exactly
    /// 0) to the boundary found by bisection, eight edges per packet. Returns evaluations.
    fn bisect(
        &self,
        ev: &mut Evaluator<F32x8>,
        todo: &mut [(usize, DVec3, DVec3)],
        crossings: &mut [Crossing],
    ) -> u64 {
        let mut evals = 0;
        for chunk in todo.chunks_mut(8) {
            for _ in 0..BISECTIONS {
                let mids: Vec<DVec3> = chunk.iter().map(|(_, a, b)| (*a + *b) * 0.5).collect();
                let mut d = Vec::with_capacity(8);
                distances(ev, self.tape, &mids, &mut d);
                evals += mids.len() as u64;
                for ((_, a, b), (m, d)) in chunk.iter_mut().zip(mids.iter().zip(d)) {
                    if inside(d) {
                        *a = *m;
                    } else {
                        *b = *m;
                    }
                }
            }
            for (k, a, b) in chunk.iter() {
                crossings[*k].p = (*a + *b) * 0.5;
            }
        }
        evals
    }

    /// A dual vertex for one loop: its crossings' mean (surface nets), or the minimiser of the
    /// quadratic error of the crossings' tangent planes (dual contouring, Ju et al. 2002),
    /// regularised towards the mean so flat patches stay put and corners are found where the
    /// normals span them, then clamped to the cell.
    fn place(&self, cs: &[Crossing], cell_lo: DVec3) -> DVec3 {
        let mean = cs.iter().map(|c| c.p).sum::<DVec3>() / cs.len() as f64;
        if self.method == Method::SurfaceNets {
            return mean;
        }
        let mut ata = DMat3::ZERO;
        let mut atb = DVec3::ZERO;
        for c in cs {
            let n = c.n;
            ata += DMat3::from_cols(n * n.x, n * n.y, n * n.z);
            atb += n * n.dot(c.p - mean);
        }
        // Tikhonov weight: small against the unit normals' contribution.
        let lambda = 0.05;
        let m = ata + DMat3::from_diagonal(DVec3::splat(lambda));
        let x = mean + m.inverse() * atb;
        let h = self.grid.h;
        if x.is_finite() {
            x.clamp(cell_lo, cell_lo + DVec3::splat(h))
        } else {
            mean
        }
    }

    /// sRGB vertex colours: the material's albedo mixed with the orbit-trap palette by its
    /// `trap_colour`, as the renderer's shading does.
    fn colours(&self, ev: &mut Evaluator<F32x8>, pts: &[DVec3]) -> Vec<[u8; 3]> {
        let mats = self.tape.materials();
        let pal = self.render.palette;
        let mut out = Vec::with_capacity(pts.len());
        for chunk in pts.chunks(8) {
            let v = ev.eval(self.tape, packet(chunk));
            for l in 0..chunk.len() {
                let id = (v.id.lane(l).max(0.0) as usize).min(mats.len() - 1);
                let id2 = (v.id2.lane(l).max(0.0) as usize).min(mats.len() - 1);
                let w = v.blend.lane(l).clamp(0.0, 1.0);
                let trap = v.trap.lane(l).min(4.0);
                let (a, b) = (&mats[id], &mats[id2]);
                let tw = a.trap_colour * (1.0 - w) + b.trap_colour * w;
                out.push([0, 1, 2].map(|c| {
                    let albedo = a.albedo[c] * (1.0 - w) + b.albedo[c] * w;
                    let x = std::f64::consts::TAU * (pal[2][c] * trap + pal[3][c]);
                    let p = (pal[0][c] + pal[1][c] * x.cos()).clamp(0.0, 1.0);
                    srgb8(albedo * (1.0 - tw) + p * tw)
                }));
            }
        }
        out
    }
}

/// Linear [0, 1] to an 8-bit sRGB value.
pub fn srgb8(v: f64) -> u8 {
    let v = v.clamp(0.0, 1.0);
    let s = if v <= 0.003_130_8 {
        12.92 * v
    } else {
        1.055 * v.powf(1.0 / 2.4) - 0.055
    };
    (s * 255.0 + 0.5) as u8
}

/// Looks up a cell anywhere in the grid: its case and the global id of its first vertex, or
/// `None` where no block was meshed (culled space).
pub trait CellLookup {
    fn cell(&self, g: [i64; 3]) -> Option<(u8, u64)>;
}

impl Block {
    /// Index of local cell `l`.
    #[inline]
    pub fn index(&self, l: [usize; 3]) -> usize {
        (l[2] * self.dims[1] + l[1]) * self.dims[0] + l[0]
    }

    /// Case and first global vertex id of global cell `g` if it is in this block.
    #[inline]
    pub fn local(&self, g: [i64; 3]) -> Option<(u8, u64)> {
        let l = [0, 1, 2].map(|a| g[a] - self.cell0[a]);
        if (0..3).any(|a| l[a] < 0 || l[a] >= self.dims[a] as i64) {
            return None;
        }
        let i = self.index(l.map(|v| v as usize));
        Some((self.cases[i], self.base + self.first[i] as u64))
    }

    /// The triangles this block's cells own, with global vertex ids; `others` finds cells in
    /// the neighbouring blocks. Returns the triangles and the number of faces dropped because
    /// a cell they need lies in culled space (zero whenever the culling was sound).
    pub fn faces(&self, method: Method, others: &dyn CellLookup) -> (Vec<[u32; 3]>, u64) {
        let mut tris = Vec::new();
        let mut missing = 0u64;
        let find = |g: [i64; 3]| self.local(g).or_else(|| others.cell(g));
        let mut cell = 0;
        for z in 0..self.dims[2] {
            for y in 0..self.dims[1] {
                for x in 0..self.dims[0] {
                    let case = self.cases[cell];
                    let me = [
                        self.cell0[0] + x as i64,
                        self.cell0[1] + y as i64,
                        self.cell0[2] + z as i64,
                    ];
                    cell += 1;
                    if case == 0 || case == 255 {
                        continue;
                    }
                    match method {
                        Method::MarchingCubes => {
                            for lp in &CASES[case as usize].loops {
                                let ids: Option<Vec<u32>> = lp
                                    .iter()
                                    .map(|&e| mc_vertex(me, e as usize, &find))
                                    .collect();
                                match ids {
                                    Some(ids) => {
                                        for i in 1..ids.len() - 1 {
                                            tris.push([ids[0], ids[i], ids[i + 1]]);
                                        }
                                    }
                                    None => missing += 1,
                                }
                            }
                        }
                        Method::SurfaceNets | Method::DualContouring => {
                            for axis in 0..3 {
                                let lo_in = case & 1 != 0;
                                if lo_in == (case >> (1 << axis) & 1 != 0) {
                                    continue;
                                }
                                match dual_quad(me, axis, lo_in, &find) {
                                    Some(q) => {
                                        tris.push([q[0], q[1], q[2]]);
                                        tris.push([q[0], q[2], q[3]]);
                                    }
                                    None => missing += 1,
                                }
                            }
                        }
                    }
                }
            }
        }
        (tris, missing)
    }
}

/// The global id of the marching-cubes vertex on cube edge `e` of cell `me`.
fn mc_vertex(me: [i64; 3], e: usize, find: &dyn Fn([i64; 3]) -> Option<(u8, u64)>) -> Option<u32> {
    let (axis, c) = EDGES[e];
    let bits = corner(c);
    let mut owner = me;
    for (b, &bit) in bits.iter().enumerate() {
        if b != axis {
            owner[b] += bit as i64 - 1;
        }
    }
    let (case, first) = find(owner)?;
    let k = &CASES[case as usize];
    let slot = OWNED_EDGES[..axis]
        .iter()
        .filter(|&&o| k.loop_of_edge[o] != u8::MAX)
        .count() as u64;
    debug_assert_ne!(k.loop_of_edge[OWNED_EDGES[axis]], u8::MAX);
    Some((first + slot) as u32)
}

/// The quad of the four cells around the grid edge along `axis` at cell `me`'s lowest corner,
/// counter-clockwise around the outward normal.
fn dual_quad(
    me: [i64; 3],
    axis: usize,
    lo_inside: bool,
    find: &dyn Fn([i64; 3]) -> Option<(u8, u64)>,
) -> Option<[u32; 4]> {
    let (b, c) = ((axis + 1) % 3, (axis + 2) % 3);
    let mut q = [0u32; 4];
    for (i, (ob, oc)) in [(-1i64, -1i64), (0, -1), (0, 0), (-1, 0)]
        .into_iter()
        .enumerate()
    {
        let mut g = me;
        g[b] += ob;
        g[c] += oc;
        let (case, first) = find(g)?;
        let k = ((-ob) as usize) | ((-oc) as usize) << 1;
        let lp = CASES[case as usize].loop_of_edge[axis * 4 + k];
        if lp == u8::MAX {
            return None;
        }
        q[i] = (first + lp as u64) as u32;
    }
    if !lo_inside {
        q.reverse();
    }
    Some(q)
}
