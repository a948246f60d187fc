//! Scale-adaptive generation: the conservative full test, the parallel evaluation of the 8
//! children of requested leaves, linking the results into the tree, and recombination of
//! all-empty children upward.
//!
//! Full test: a voxel is full when the distance bound at its centre is below half its diagonal
//! times `1 + margin`, plus a few ulps of the centre's coordinates. With a distance *bound*
//! (never larger than the true distance) a voxel the surface crosses always tests full: no
//! false negatives. The margin absorbs floating-point error in the estimator (the
//! dissertation's Menger holes came from testing without one).
//!
//! Estimates that are not bounds (the scene uses an operator of quality `Safety`: the
//! Mandelbulb, the Mandelbox, twists) get a second test: a voxel is also full when one of its
//! 8 corners is inside (distance <= 0). The Mandelbulb's estimate is 0 inside the set of points
//! that do not escape in its 12 iterations but about 7e-7 just outside it (it estimates the
//! distance to the limit set, not to that set), so below that size a voxel the set's boundary
//! crosses tested empty whenever its centre was outside: past zoom ~1e6 the surface at the
//! zoom target vanished and rays hit structure 100x further away. Where the boundary is
//! locally a plane, a voxel it crosses has a corner on each side, so the corner test catches
//! it. The corners of the 8 children are the parent's 3x3x3 lattice, evaluated lazily.

use crate::evict::free_children;
use crate::node::{EMPTY, NONE, REQUESTED, VISITED, pack_rgb};
use crate::octree::{BoxU, Octree};
use fathom_core::eval::Evaluator;
use fathom_core::registry::{Family, Quality};
use fathom_core::scene::Scene;
use fathom_core::tape::CompileError;
use fathom_core::{Tape, V3};
use glam::DVec3;

/// Default relative margin of the full test.
pub const DEFAULT_MARGIN: f64 = 0.01;

/// Everything needed to decide and colour voxels: the tape plus shading constants.
pub struct Shader {
    /// The compiled scene.
    pub tape: Tape,
    /// Relative margin of the full test.
    pub margin: f64,
    light: DVec3,
    ambient: f64,
    palette: [[f64; 3]; 4],
    /// Colour voxels by the DE gradient (lambert) on top of the orbit-trap colour.
    pub gradient_shading: bool,
    /// The distance is an estimate, not a bound: voxels with a corner inside are full too.
    pub corner_test: bool,
}

/// True when every shape, operator and combination of `scene` declares an exact distance or a
/// bound (no `Safety` estimates).
pub fn is_bound(scene: &Scene) -> bool {
    fn ok<K: Family>(c: &fathom_core::Call<K>) -> bool {
        c.kind.def().quality != Quality::Safety
    }
    fn node(n: &fathom_core::Node) -> bool {
        ok(&n.shape) && ok(&n.combine) && n.ops.iter().all(ok) && n.children.iter().all(node)
    }
    node(&scene.root) && scene.ifs.as_ref().is_none_or(|i| i.ops.iter().all(ok))
}

impl Shader {
    /// Compiles `scene` into a shader.
    pub fn new(scene: &Scene, margin: f64) -> Result<Shader, CompileError> {
        let tape = Tape::compile(scene)?;
        let light = scene
            .lights
            .first()
            .map(|l| l.direction)
            .unwrap_or(DVec3::new(0.6, 0.8, 0.4))
            .normalize_or(DVec3::Y);
        Ok(Shader {
            tape,
            margin,
            light,
            ambient: scene.render.ambient.clamp(0.0, 1.0).max(0.25),
            palette: scene.render.palette,
            gradient_shading: true,
            corner_test: !is_bound(scene),
        })
    }

    /// The full test at world centre `c` of a voxel with world half-diagonal `hd`; returns the
    /// evaluated value when full.
    #[inline]
    pub fn full(
        &self,
        ev: &mut Evaluator<f64>,
        c: DVec3,
        hd: f64,
    ) -> Option<fathom_core::Value<f64>> {
        let v = ev.eval(&self.tape, V3::new(c.x, c.y, c.z));
        if self.full_value(&v, c, hd) {
            Some(v)
        } else {
            None
        }
    }

    /// The corner test of estimate scenes: whether any corner of the cube `centre +
    /// [-half, half]^3` is inside (or NaN, never a false negative). Always false for scenes
    /// whose distance is a bound, where the centre test alone is conservative.
    pub fn corner_inside(&self, ev: &mut Evaluator<f64>, centre: DVec3, half: f64) -> bool {
        self.corner_test
            && (0..8).any(|k| {
                let sign = |bit: i32| if k & bit == 0 { -half } else { half };
                self.inside(ev, centre + DVec3::new(sign(1), sign(2), sign(4)))
            })
    }

    /// Whether world point `p` is inside the surface, or its distance is NaN (never a false
    /// negative): the corner test's question.
    #[inline]
    pub fn inside(&self, ev: &mut Evaluator<f64>, p: DVec3) -> bool {
        let d = ev.distance(&self.tape, V3::new(p.x, p.y, p.z));
        d <= 0.0 || d.is_nan()
    }

    /// The full test on an evaluated value `v` at world centre `c` (half-diagonal `hd`).
    #[inline]
    pub fn full_value(&self, v: &fathom_core::Value<f64>, c: DVec3, hd: f64) -> bool {
        let slack = 8.0 * f64::EPSILON * c.abs().max_element().max(1.0);
        // NaN counts as full: never a false negative.
        v.d.is_nan() || v.d < hd * (1.0 + self.margin) + slack
    }

    /// Colour of a full voxel at world centre `c` (half side `h`) with value `v`.
    pub fn colour(
        &self,
        ev: &mut Evaluator<f64>,
        c: DVec3,
        h: f64,
        v: &fathom_core::Value<f64>,
    ) -> u32 {
        let mats = self.tape.materials();
        let m = mats.get(v.id as usize).or(mats.first());
        let (albedo, mix) = m
            .map(|m| (m.albedo, m.trap_colour))
            .unwrap_or(([0.75; 3], 0.0));
        let t = v.trap.clamp(0.0, 4.0);
        let p = &self.palette;
        let mut base = [0.0; 3];
        for i in 0..3 {
            let pal = p[0][i] + p[1][i] * (std::f64::consts::TAU * (p[2][i] * t + p[3][i])).cos();
            base[i] = albedo[i] * (1.0 - mix) + pal.clamp(0.0, 1.0) * mix;
        }
        let lum = if self.gradient_shading {
            let n = ev.normal(&self.tape, V3::new(c.x, c.y, c.z), h.max(1e-300));
            let n = DVec3::new(n.x, n.y, n.z);
            self.ambient + (1.0 - self.ambient) * n.dot(self.light).max(0.0)
        } else {
            1.0
        };
        pack_rgb(base.map(|b| b * lum))
    }
}

/// The evaluated children of one node: bit `o` of `full` set when child `o` is full.
#[derive(Clone, Copy, Debug)]
pub struct Children {
    /// Node that was evaluated.
    pub id: u32,
    /// Its box.
    pub b: BoxU,
    /// Full-child mask.
    pub full: u8,
    /// Colours of the full children.
    pub colours: [u32; 8],
}

/// Evaluates the 8 children of the leaf with box `b` (read-only; runs in parallel).
pub fn eval_children(
    sh: &Shader,
    tree: &Octree,
    ev: &mut Evaluator<f64>,
    id: u32,
    b: BoxU,
) -> Children {
    let mut out = Children {
        id,
        b,
        full: 0,
        colours: [0; 8],
    };
    let side = b.dim() * 0.5 * tree.root_size;
    let hd = side * 0.5 * 3f64.sqrt();
    // Inside flags of the parent's 3x3x3 lattice (the children's corners), filled on demand.
    let mut lattice = [None::<bool>; 27];
    let h = b.dim() * 0.5;
    for o in 0..8 {
        let cb = b.child(o);
        let c = tree.centre_world(&cb);
        let v = ev.eval(&sh.tape, V3::new(c.x, c.y, c.z));
        let mut full = sh.full_value(&v, c, hd);
        if !full && sh.corner_test {
            full = (0..8).any(|k| {
                let ijk = [0, 1, 2].map(|a| (o >> a & 1) + (k >> a & 1));
                *lattice[ijk[0] + 3 * ijk[1] + 9 * ijk[2]].get_or_insert_with(|| {
                    let u = DVec3::new(
                        b.min[0] + h * ijk[0] as f64,
                        b.min[1] + h * ijk[1] as f64,
                        b.min[2] + h * ijk[2] as f64,
                    );
                    sh.inside(ev, tree.root_min + u * tree.root_size)
                })
            });
        }
        if full {
            out.full |= 1 << o;
            out.colours[o] = sh.colour(ev, c, side * 0.5, &v);
        }
    }
    out
}

/// What linking one evaluated node did.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Outcome {
    /// 8 children were linked in.
    Split,
    /// Every child was empty: the node became an empty leaf (and maybe recombined upward).
    Emptied,
    /// The node was freed, split or emptied since it was requested: nothing done.
    Stale,
    /// The memory budget had no room for 8 children.
    NoMemory,
}

/// Links the result of [`eval_children`] into the tree (single-threaded, between frames).
pub fn apply(tree: &mut Octree, r: &Children) -> Outcome {
    let id = r.id;
    {
        let n = &tree.nodes[id as usize];
        n.clear_flags(REQUESTED);
        if n.is_free() || !n.is_leaf() || n.is_empty() || n.depth != r.b.depth {
            return Outcome::Stale;
        }
    }
    if r.full == 0 {
        tree.nodes[id as usize].set_flags(EMPTY);
        recombine_up(tree, id);
        return Outcome::Emptied;
    }
    let Some(first) = tree.alloc_block() else {
        return Outcome::NoMemory;
    };
    let depth = r.b.depth + 1;
    let brick_here = tree.is_brick_depth(depth);
    let (parent_links, parent_brick) = {
        let n = &tree.nodes[id as usize];
        (std::array::from_fn::<u32, 6, _>(|f| n.link(f)), n.brick)
    };
    let mut sum = [0u32; 3];
    let mut count = 0;
    for o in 0..8u32 {
        let cid = first + o;
        let c = &mut tree.nodes[cid as usize];
        c.children = NONE;
        c.parent = id;
        c.depth = depth;
        c.brick = if brick_here { cid } else { parent_brick };
        let full = r.full >> o & 1 == 1;
        c.colour = if full { r.colours[o as usize] } else { 0 };
        // New nodes count as visited so the next unification does not unload them unseen.
        *c.flags.get_mut() = if full { 0 } else { EMPTY } | VISITED;
        for a in 0..3 {
            let hi = o >> a & 1 == 1;
            // Face towards the sibling: exact link; face outwards: the parent's link (same
            // or coarser depth, made finer by rays on the fly).
            let (inner, outer) = if hi {
                (2 * a, 2 * a + 1)
            } else {
                (2 * a + 1, 2 * a)
            };
            *c.nb[inner].get_mut() = first + (o ^ (1 << a));
            *c.nb[outer].get_mut() = parent_links[outer];
        }
        if full {
            let rgb = r.colours[o as usize];
            for (i, s) in sum.iter_mut().enumerate() {
                *s += rgb >> (8 * i) & 255;
            }
            count += 1;
        }
    }
    // Refine the copied outer links: descend from the parent's neighbour towards each child's
    // adjacent box, as deep as the child (safe here: nothing else runs during link-in).
    // Without this, chains of full leaves subdivided level after level hand their children
    // links many levels too coarse, and every first crossing pays a long descent.
    for o in 0..8u32 {
        let cb = r.b.child(o as usize);
        for a in 0..3 {
            let outer = if o >> a & 1 == 1 { 2 * a + 1 } else { 2 * a };
            let l = parent_links[outer];
            if l == NONE {
                continue;
            }
            let target = cb.across(outer);
            let mut m = l;
            let mut mb = target.snapped(tree.nodes[m as usize].depth);
            while mb.depth < cb.depth {
                let mn = &tree.nodes[m as usize];
                if mn.is_leaf() {
                    break;
                }
                let oc = mb.octant_of(target.min);
                m = mn.children + oc as u32;
                mb = mb.child(oc);
            }
            if m != l {
                tree.nodes[(first + o) as usize].set_link(outer, m);
            }
        }
    }
    let n = &mut tree.nodes[id as usize];
    n.children = first;
    n.colour = sum
        .iter()
        .enumerate()
        .fold(255 << 24, |acc, (i, s)| acc | (s / count) << (8 * i));
    tree.note_inner(id, true);
    Outcome::Split
}

/// After `id` became an empty leaf: while every child of the parent is an empty leaf, free
/// them and make the parent an empty leaf.
pub fn recombine_up(tree: &mut Octree, mut id: u32) {
    loop {
        let p = tree.nodes[id as usize].parent;
        if p == NONE {
            return;
        }
        let first = tree.nodes[p as usize].children;
        if !(first..first + 8).all(|c| tree.is_empty_leaf(c)) {
            return;
        }
        let pb = tree.box_of(p);
        free_children(tree, p, pb);
        tree.nodes[p as usize].set_flags(EMPTY);
        id = p;
    }
}

/// Evaluates the root and sets it full (with a colour) or empty.
pub fn init_root(tree: &mut Octree, sh: &Shader) {
    let mut ev = Evaluator::new();
    let b = BoxU::ROOT;
    let c = tree.centre_world(&b);
    let hd = tree.root_size * 0.5 * 3f64.sqrt();
    let n = &mut tree.nodes[0];
    match sh.full(&mut ev, c, hd) {
        Some(v) => n.colour = sh.colour(&mut ev, c, tree.root_size * 0.5, &v),
        None => *n.flags.get_mut() |= EMPTY,
    }
}
