//! Scale-adaptive generation: the conservative full test, the parallel evaluation of the 8
//! children of requested leaves, linking the results into the tree, and recombination of
//! all-empty children upward. Colouring the full children (lighting, occlusion, lines of
//! sight) is [`crate::shader`]'s.
//!
//! Full test: a voxel is full when the distance bound at its centre is below half its diagonal
//! times `1 + margin`, plus a few ulps of the centre's coordinates. With a distance *bound*
//! (never larger than the true distance) a voxel the surface crosses always tests full: no
//! false negatives. The margin absorbs floating-point error in the estimator (the
//! dissertation's Menger holes came from testing without one).
//!
//! Estimates that are not bounds (the scene uses an operator of quality `Safety`: the
//! Mandelbulb, the Mandelbox, twists) get a second test: a voxel is also full when one of its
//! 8 corners is inside (distance <= 0). The Mandelbulb's estimate used to be 0 inside the set
//! of points that do not escape in its 12 iterations but about 7e-7 just outside it, so below
//! that size a voxel the set's boundary crosses tested empty whenever its centre was outside;
//! it is now first-order at that boundary but can still overestimate it many times where the
//! running derivative underestimates the map's stretch (`fathom_core` fractals tests). Where
//! the boundary is locally a plane, a voxel it crosses has a corner on each side, so the
//! corner test catches it. The corners of the 8 children are the parent's 3x3x3 lattice.
//!
//! A conservative test keeps a shell of full voxels the surface does not cross in front of an
//! underestimated surface. A new child whose line of sight passes it without meeting the
//! surface, or whose surface point lies outside its cube (its plane is clear of it), and that
//! is still wider than the footprint of the ray that asked for the split is therefore tested
//! one level down at once, and dropped when none of its own children is
//! full ([`eval_children`]): the decision its split would have made a frame or more later,
//! after being drawn as a cube in front of the surface and walked through by rays.

use crate::evict::{free_children, mark_visited};
use crate::geometry::BoxU;
use crate::node::{EMPTY, NONE, REQUESTED, VISITED};
use crate::octree::Octree;
use crate::plane::SurfacePlane;
use crate::shader::{Probe, Shader, Sight, Surface};
use glam::DVec3;

/// Default relative margin of the full test.
pub const DEFAULT_MARGIN: f64 = 0.01;

/// The full test (see the module doc).
impl Shader {
    /// The full test at centre `c` (relative to the origin) of a voxel with world
    /// half-diagonal `hd`; returns the evaluated value when full.
    #[inline]
    pub fn full(&self, ev: &mut Probe, c: DVec3, hd: f64) -> Option<fathom_core::Value<f64>> {
        let v = self.eval(ev, c);
        if self.full_distance(v.d, c, hd) {
            Some(v)
        } else {
            None
        }
    }

    /// The corner test of estimate scenes: whether any corner of the cube `centre +
    /// [-half, half]^3` is inside (or NaN, never a false negative). Always false for scenes
    /// whose distance is a bound, where the centre test alone is conservative.
    pub fn corner_inside(&self, ev: &mut Probe, centre: DVec3, half: f64) -> bool {
        self.corner_test
            && (0..8).any(|k| {
                let sign = |bit: i32| if k & bit == 0 { -half } else { half };
                self.inside(ev, centre + DVec3::new(sign(1), sign(2), sign(4)))
            })
    }

    /// Whether point `p` (relative to the origin) is inside the surface, or its distance is
    /// NaN (never a false negative): the corner test's question.
    #[inline]
    pub fn inside(&self, ev: &mut Probe, p: DVec3) -> bool {
        let d = self.distance(ev, p);
        d <= 0.0 || d.is_nan()
    }

    /// The full test on the distance `d` at centre `c` (relative to the origin,
    /// half-diagonal `hd`). The slack is a few units of the last place of the centre's
    /// coordinates: f64 ones, or double-double ones (2^-104 of the origin) on deep frames.
    #[inline]
    pub fn full_distance(&self, d: f64, c: DVec3, hd: f64) -> bool {
        let o = &self.origin;
        let slack = if o.deep {
            8.0 * f64::EPSILON * c.abs().max_element()
                + 8.0 * 2f64.powi(-104) * o.hi.abs().max_element().max(1.0)
        } else {
            8.0 * f64::EPSILON * (o.hi + c).abs().max_element().max(1.0)
        };
        // NaN counts as full: never a false negative.
        d.is_nan() || d < hd * (1.0 + self.margin) + slack
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
    /// Surface planes of the full children.
    pub planes: [SurfacePlane; 8],
}

/// Evaluates the 8 children of the leaf `id` with box `b` (read-only; runs in parallel).
///
/// A full child wider than `final_side` (root units: the footprint of the ray that asked for
/// the split, below which the child is drawn as it is) whose line of sight passes its
/// bounding sphere without meeting the surface (on estimate scenes, before the line is traced
/// on past it), or whose surface plane lies clear of its cube (its surface point is outside
/// it, [`SurfacePlane::is_clear`]), has its own children tested at once, and is empty when
/// none of them is full: the test its subdivision would make, made before it is drawn. Such
/// a child is the conservative full test's shell in front of an underestimated surface (two
/// thirds of the Mandelbulb zoom's full leaves, three quarters of which emptied when split
/// later). Children at or below `final_side` keep the plain test, so settled trees are
/// unchanged, up to one approximation: the footprint is the asking ray's at the parent, so a
/// child within a few tenths of a percent of it can fall on either side (and with several
/// threads, which ray asks first is a race).
pub fn eval_children(
    sh: &Shader,
    tree: &Octree,
    ev: &mut Probe,
    (id, b): (u32, BoxU),
    final_side: f64,
) -> Children {
    let mut out = Children {
        id,
        b,
        full: 0,
        colours: [0; 8],
        planes: [SurfacePlane::NONE; 8],
    };
    let side = b.dim() * 0.5 * tree.root_size;
    let h = (side * 0.5).max(1e-300);
    let hd = h * 3f64.sqrt();
    let reach = sh.sight_limits().0;
    let t = full_children(sh, tree, ev, &b);
    out.full = t.full;
    let look_deeper = b.depth + 1 < tree.depth_limit() && b.dim() * 0.5 > final_side;
    let mut full = [0usize; 8];
    let mut n = 0;
    for o in (0..8).filter(|o| t.full >> o & 1 == 1) {
        full[n] = o;
        n += 1;
    }
    // The full children's lines of sight, four at a time, as far as each child's bounding
    // sphere; on estimate scenes a line that gets there is `Passed`, to be traced on.
    let mut sight: [Sight; 8] = std::array::from_fn(|o| {
        let traced = t.full >> o & 1 == 1 && sh.traces(t.d[o]);
        match traced.then(|| sh.sight_line(t.centres[o], h)).flatten() {
            Some(l) => Sight::Passed(l),
            None => Sight::Lost,
        }
    });
    trace_on(sh, ev, &mut sight, &full[..n], h, hd, reach > 1.0);
    // A wide child whose line passed it without meeting the surface is tested one level down
    // before its line is traced on: dropped, it needs neither the rest of the trace nor a
    // gradient (on the Mandelbulb zoom 70 % of the wide children with a clear plane were
    // dropped, and four fifths of the trace's steps were past the bounding sphere).
    let mut tested = 0u8;
    let mut passed = [0usize; 8];
    let mut np = 0;
    for &o in &full[..n] {
        if !matches!(sight[o], Sight::Passed(_)) {
            continue;
        }
        if look_deeper {
            tested |= 1 << o;
            if !any_child_full(sh, tree, ev, &b, o, &t) {
                out.full &= !(1 << o);
                continue;
            }
        }
        passed[np] = o;
        np += 1;
    }
    // The kept children's lines traced on, to the reach.
    trace_on(sh, ev, &mut sight, &passed[..np], h, hd * reach, false);
    // Each kept child's surface; a wide one whose plane is clear of it, not tested yet, is
    // tested one level down now.
    let mut surfaces = [Surface::NONE; 8];
    let mut kept = [0usize; 8];
    let mut m = 0;
    for &o in &full[..n] {
        if out.full >> o & 1 == 0 {
            continue;
        }
        let s = sh.surface_from(ev, t.centres[o], h, t.d[o], sight[o].hit());
        if look_deeper
            && tested >> o & 1 == 0
            && s.plane.is_clear()
            && !any_child_full(sh, tree, ev, &b, o, &t)
        {
            out.full &= !(1 << o);
            continue;
        }
        surfaces[o] = s;
        kept[m] = o;
        m += 1;
    }
    // The kept children shaded together, four at a time (`Shader::shade4`).
    for group in kept[..m].chunks(4) {
        let colours = sh.shade4(
            ev,
            std::array::from_fn(|j| &surfaces[group[j.min(group.len() - 1)]]),
            group.len(),
        );
        for (j, &o) in group.iter().enumerate() {
            (out.colours[o], out.planes[o]) = (colours[j], surfaces[o].plane);
        }
    }
    out
}

/// Traces on the lines of sight of children `which` that are [`Sight::Passed`] (the others
/// stay as they are), four at a time, with [`Shader::trace4`]'s `until` and `pass`.
fn trace_on(
    sh: &Shader,
    ev: &mut Probe,
    sight: &mut [Sight; 8],
    which: &[usize],
    h: f64,
    until: f64,
    pass: bool,
) {
    for group in which.chunks(4) {
        let lines = std::array::from_fn(|k| match group.get(k).map(|&o| sight[o]) {
            Some(Sight::Passed(l)) => Some(l),
            _ => None,
        });
        let s = sh.trace4(ev, lines, h, until, pass);
        for (k, &o) in group.iter().enumerate() {
            if matches!(sight[o], Sight::Passed(_)) {
                sight[o] = s[k];
            }
        }
    }
}

/// The full test of the children of `b`'s child `o` (`t` is `b`'s [`full_children`]): true
/// when one of them is full, as `full_children(&b.child(o)).full != 0` would say, without
/// evaluating again the points of the child's 3x3x3 lattice `t` already has: its centre and,
/// when `b`'s lattice was evaluated, its corners (26 new points instead of 35).
fn any_child_full(
    sh: &Shader,
    tree: &Octree,
    ev: &mut Probe,
    b: &BoxU,
    o: usize,
    t: &ChildTests,
) -> bool {
    let cb = b.child(o);
    if centre_test(sh, tree, ev, &cb).2 != 0 {
        return true;
    }
    if !sh.corner_test {
        return false;
    }
    // Every point of the child's lattice is a corner of one of its children: one inside
    // makes that child full. Its centre is `t.d[o]`; its corners are in `b`'s lattice.
    if inside(t.d[o]) {
        return true;
    }
    let corners = match &t.lattice {
        Some(l) => (0..8).any(|k| l[corner_index(o, k)]),
        None => {
            let pts: [DVec3; 8] = std::array::from_fn(|k| {
                lattice_point(tree, &cb, [0, 1, 2].map(|a| 2 * (k >> a & 1)))
            });
            sh.distances(ev, &pts).into_iter().any(inside)
        }
    };
    if corners {
        return true;
    }
    // The 18 others: a coordinate at the middle, not all three.
    let others: [DVec3; 18] = std::array::from_fn(|k| {
        let ijk = LATTICE_MIDDLES[k];
        lattice_point(tree, &cb, ijk)
    });
    sh.distances(ev, &others).into_iter().any(inside)
}

/// The points of a 3x3x3 lattice with one or two coordinates at the middle (neither a corner
/// nor the centre), in `lattice_ijk` order.
const LATTICE_MIDDLES: [[usize; 3]; 18] = {
    let mut out = [[0; 3]; 18];
    let (mut i, mut n) = (0, 0);
    while i < 27 {
        let ijk = lattice_ijk(i);
        let middles = (ijk[0] == 1) as u8 + (ijk[1] == 1) as u8 + (ijk[2] == 1) as u8;
        if middles == 1 || middles == 2 {
            out[n] = ijk;
            n += 1;
        }
        i += 1;
    }
    out
};

/// Point `i` of a 3x3x3 lattice as `ijk`, 0..=2 per axis (`i = i0 + 3 i1 + 9 i2`).
const fn lattice_ijk(i: usize) -> [usize; 3] {
    [i % 3, i / 3 % 3, i / 9]
}

/// The lattice index of corner `k` of child `o` in its parent's 3x3x3 lattice.
fn corner_index(o: usize, k: usize) -> usize {
    let ijk = [0, 1, 2].map(|a| (o >> a & 1) + (k >> a & 1));
    ijk[0] + 3 * ijk[1] + 9 * ijk[2]
}

/// Lattice point `ijk` of box `b` (world units relative to the origin).
fn lattice_point(tree: &Octree, b: &BoxU, ijk: [usize; 3]) -> DVec3 {
    let h = b.dim() * 0.5;
    tree.local_world([0, 1, 2].map(|a| b.min[a] + h * ijk[a] as f64))
}

/// The corner test's "inside": at or below zero, or NaN (never a false negative).
fn inside(d: f64) -> bool {
    d <= 0.0 || d.is_nan()
}

/// The centre test of the 8 children of box `b`: their centres (world units relative to the
/// origin), the distances there and the mask of those that pass.
fn centre_test(sh: &Shader, tree: &Octree, ev: &mut Probe, b: &BoxU) -> ([DVec3; 8], [f64; 8], u8) {
    let side = b.dim() * 0.5 * tree.root_size;
    let hd = side * 0.5 * 3f64.sqrt();
    let centres: [DVec3; 8] = std::array::from_fn(|o| tree.centre_local(&b.child(o)));
    let d = sh.distances(ev, &centres);
    let mut full = 0u8;
    for (o, (&c, &d)) in centres.iter().zip(&d).enumerate() {
        if sh.full_distance(d, c, hd) {
            full |= 1 << o;
        }
    }
    (centres, d, full)
}

/// The full test of the 8 children of a box ([`full_children`]).
struct ChildTests {
    /// Mask of the full children.
    full: u8,
    /// Their centres (world units relative to the origin) and the distances there.
    centres: [DVec3; 8],
    d: [f64; 8],
    /// Inside flags of the box's 3x3x3 lattice of children's corners, when it was evaluated.
    lattice: Option<[bool; 27]>,
}

/// The full test of the 8 children of box `b`: the mask of full children, their centres
/// (world units relative to the origin) and the distances there.
///
/// The children's centre distances are two four-lane evaluations, and on estimate scenes the
/// parent's 3x3x3 corner lattice is seven, all 27 points at once once any child fails the
/// centre test: seven packets cost what 9-11 scalar evaluations do, where the lattice filled
/// lazily child by child took 19 on average (Mandelbulb zoom).
fn full_children(sh: &Shader, tree: &Octree, ev: &mut Probe, b: &BoxU) -> ChildTests {
    let (centres, d, mut full) = centre_test(sh, tree, ev, b);
    let mut lattice = None;
    if full != 0xff && sh.corner_test {
        // Inside flags of the parent's 3x3x3 lattice (the children's corners).
        let pts: [DVec3; 27] = std::array::from_fn(|i| lattice_point(tree, b, lattice_ijk(i)));
        let ins = sh.distances(ev, &pts).map(inside);
        let by_centre = full;
        for o in (0..8).filter(|o| by_centre >> o & 1 == 0) {
            if (0..8).any(|k| ins[corner_index(o, k)]) {
                full |= 1 << o;
            }
        }
        lattice = Some(ins);
    }
    ChildTests {
        full,
        centres,
        d,
        lattice,
    }
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
        c.idle = 0;
        let full = r.full >> o & 1 == 1;
        c.colour = if full { r.colours[o as usize] } else { 0 };
        // Empty children's planes are `NONE` (eval_children sets only the full ones').
        c.plane = r.planes[o as usize];
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
    let rc = tree.anchor.cell_of(&r.b);
    for o in 0..8u32 {
        let cb = rc.child(o as usize);
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
                let oc = mb.octant_towards(&target);
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
    // The children are marked visited; so must be every brick above them, or the first ray
    // that reaches them stops its marking walk at their (marked) brick and the enclosing
    // bricks are unloaded at the next unification, in view (a still camera's picture then
    // fell back to 15-pixel blocks every few frames).
    mark_visited(tree, id);
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
        let pb = tree.cell_of(p);
        free_children(tree, p, pb);
        tree.nodes[p as usize].set_flags(EMPTY);
        id = p;
    }
}

/// Evaluates the root and sets it full (with a colour) or empty.
pub fn init_root(tree: &mut Octree, sh: &Shader) {
    let mut ev = Probe::new();
    let b = tree.root_box();
    let c = tree.centre_local(&b);
    let hd = tree.root_size * 0.5 * 3f64.sqrt();
    let n = &mut tree.nodes[0];
    match sh.full(&mut ev, c, hd) {
        Some(v) => (n.colour, n.plane) = sh.colour(&mut ev, c, tree.root_size * 0.5, v.d),
        None => *n.flags.get_mut() |= EMPTY,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::shader::View;
    use fathom_core::camera_path::path_preset;

    #[test]
    fn packet_children_tests_match_point_by_point_ones() {
        // full_children decides the 8 children from two packets of centres and, on estimate
        // scenes, seven packets of the 3x3x3 corner lattice; point by point (f64), the same
        // points must give the same full children on boxes down to the zoom target. The
        // Mandelbulb's estimate is first-order at its surface and its centres alone find the
        // surface on this path, so its centre test is made a sign test (a margin of -1) to
        // make the corners decide some children.
        for (name, margin) in [("mandelbulb", -1.0), ("menger", DEFAULT_MARGIN)] {
            let p = path_preset(name).unwrap();
            let mut sh = Shader::new(&p.scene, margin).unwrap();
            sh.gradient_shading = false;
            let tree = Octree::new(DVec3::splat(-1.5), 3.0, 3, 1 << 12);
            sh.origin.hi = tree.root_min;
            let u = tree.to_u(p.path.target().unwrap());
            let mut pr = Probe::new();
            let (mut full, mut by_corner) = (0, 0);
            let mut b = BoxU::ROOT;
            for _ in 0..40 {
                let got = full_children(&sh, &tree, &mut pr, &b).full;
                let side = b.dim() * 0.5 * tree.root_size;
                let h = b.dim() * 0.5;
                let inside = |pr: &mut Probe, ijk: [usize; 3]| {
                    let q = [0, 1, 2].map(|a| b.min[a] + h * ijk[a] as f64);
                    let d = sh.distance(pr, tree.local_world(q));
                    d <= 0.0 || d.is_nan()
                };
                for o in 0..8 {
                    let c = tree.centre_local(&b.child(o));
                    let centre =
                        sh.full_distance(sh.distance(&mut pr, c), c, side * 0.75f64.sqrt());
                    let corner = sh.corner_test
                        && (0..8).any(|k| {
                            inside(&mut pr, [0, 1, 2].map(|a| (o >> a & 1) + (k >> a & 1)))
                        });
                    assert_eq!(
                        got >> o & 1 == 1,
                        centre || corner,
                        "{name} depth {} child {o}",
                        b.depth
                    );
                    full += (centre || corner) as u32;
                    by_corner += (corner && !centre) as u32;
                }
                b = b.child(b.octant_of(u));
            }
            assert!(full >= 40, "{name}: {full} full children");
            if name == "mandelbulb" {
                assert!(by_corner > 0, "the corner lattice was never needed");
            }
        }
    }

    #[test]
    fn a_clear_child_is_full_only_when_one_of_its_own_children_is() {
        // Down the Mandelbulb zoom's path, seen from its first camera: eval_children keeps the
        // full test's children except those whose own children all test empty and whose line
        // of sight passes their bounding sphere without meeting the surface or whose plane is
        // clear of their cube. Such children exist on this path (the shell in front of the
        // surface), and a clear child kept has a full child of its own. Children no wider
        // than the footprint of the ray that asked are final and keep the plain test.
        let p = path_preset("mandelbulb").unwrap();
        let mut sh = Shader::new(&p.scene, DEFAULT_MARGIN).unwrap();
        let tree = Octree::new(DVec3::splat(-1.5), 3.0, 3, 1 << 12);
        sh.origin.hi = tree.root_min;
        let target = p.path.target().unwrap();
        let cam = p.path.camera(0, 300, 1e15, 40.0);
        sh.view = View {
            eye: cam.eye - tree.root_min,
            scale: (target - cam.eye).length(),
        };
        let u = tree.to_u(target);
        let mut pr = Probe::new();
        let (mut kept_clear, mut dropped, mut passed_dropped) = (0, 0, 0);
        let mut b = BoxU::ROOT;
        for _ in 0..30 {
            // The path's box and its children: the shell lies beside the path, not on it.
            for x in std::iter::once(b).chain((0..8).map(|o| b.child(o))) {
                let plain = full_children(&sh, &tree, &mut pr, &x);
                let got = eval_children(&sh, &tree, &mut pr, (0, x), 0.0);
                // Children no wider than the asking ray's footprint keep the plain test.
                let footprint = x.dim() * 0.5;
                let fine = eval_children(&sh, &tree, &mut pr, (0, x), footprint);
                assert_eq!(fine.full, plain.full, "depth {}: final children", x.depth);
                assert_eq!(
                    got.full & !plain.full,
                    0,
                    "depth {}: a child not full",
                    x.depth
                );
                let h = x.dim() * 0.25 * tree.root_size;
                for o in (0..8).filter(|o| plain.full >> o & 1 == 1) {
                    let plane = sh.surface(&mut pr, plain.centres[o], h, plain.d[o]).plane;
                    let below = full_children(&sh, &tree, &mut pr, &x.child(o)).full;
                    let any = any_child_full(&sh, &tree, &mut pr, &x, o, &plain);
                    assert_eq!(any, below != 0, "depth {} child {o}", x.depth);
                    // Whether the line of sight passes the child's bounding sphere.
                    let c = [plain.centres[o]; 4];
                    let lines = sh.sight_lines(c, [true; 4], h);
                    let hd = h * 3f64.sqrt();
                    let near = sh.trace4(&mut pr, lines, h, hd, true)[0];
                    let passed = matches!(near, Sight::Passed(_));
                    let kept = got.full >> o & 1 == 1;
                    let want = below != 0 || !(passed || plane.is_clear());
                    assert_eq!(kept, want, "depth {} child {o}", x.depth);
                    kept_clear += (kept && plane.is_clear()) as u32;
                    dropped += !kept as u32;
                    passed_dropped += (!kept && passed) as u32;
                }
            }
            b = b.child(b.octant_of(u));
        }
        assert!(dropped > 0, "no clear child was dropped");
        assert!(
            passed_dropped > 0,
            "no child whose line passed it was dropped"
        );
        assert!(kept_clear > 0, "no clear child was kept");
    }
}
