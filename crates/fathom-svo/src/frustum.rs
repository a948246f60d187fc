//! Where every pixel ray of a tile can start: a front-to-back walk of the octree nodes that meet
//! the tile's frustum finds a distance before which none of its rays can stop, and the rays
//! start there, each in the leaf holding its point at that distance.
//!
//! It replaced a beam that walked the tile's four corner rays in lockstep through one chain of
//! leaves and stopped where they parted, which near a surface (leaves a pixel or two wide) is
//! long before the surface. This walk visits every node the frustum meets, so leaves that part
//! the corners do not stop it: only a node where some ray could stop does.
//!
//! **The frustum.** A pixel's direction is (up to rounding) a positive combination of its
//! tile's corner pixels' directions (the camera's unnormalised directions are affine in the
//! pixel coordinates), so every ray of the tile lies in the cone the corner rays span: the
//! intersection of the four half-spaces through the eye bounded by the planes of adjacent
//! corner rays. A box is skipped only when it lies beyond one of those planes, or behind the
//! eye along an axis every corner ray heads along, by more than a relative slack.
//!
//! **The bound.** A ray stops at a non-empty leaf (a hit, or a full leaf whose plane it may
//! pass) or at an inner node below its footprint (`side < t * lod`, the implicit LOD). Rays
//! are unit-speed, so a ray is at distance `t >= dist(eye, box)` anywhere in a box. For every
//! node the frustum meets, nearest first, the walk takes as a possible stop distance:
//! - `dist(eye, box)` for a non-empty leaf, and for an inner node already below the footprint
//!   there;
//! - `max(dist, side / lod)` for any other inner node a ray can still be inside at `side /
//!   lod` (its farthest corner is beyond that): a ray crossing it later stops on it.
//!
//! The smallest of these (and the distance at which the rays can first leave the node the walk
//! starts from, see [`Seed`]) is a lower bound of every tile ray's stop distance: a ray
//! stopping at `t` stops on a node that meets the frustum with `dist <= t`, whose ancestors
//! also meet it nearer, so the walk reaches it (nodes are skipped only when outside the
//! frustum or not nearer than the bound found so far).
//!
//! **Bit-identical results.** Each ray starts at `t` (the bound less a relative slack) in the
//! leaf holding its point `o + t d`, found by descending from the deepest node holding the
//! whole tile's points at `t`. When that point is at least a margin inside its leaf, the leaf
//! is the one the ray's traversal from the eye is in at `t`, the ray entered it before `t`,
//! and it leaves it at `max(exit, t)` with `exit > t`: from there it computes exactly the
//! distances and points it computes from the eye, and no LOD climb fires at `t` (its parent's
//! bound `side / lod` is above `t`). Rays whose point is within the margin of a face return
//! `None`, and the caller starts them at the skip node. The leaves the rays skip are marked
//! visited by the walk (it marks every empty leaf nearer than the bound), so unification sees
//! at least the visits the rays would have made.
//!
//! **Refinement.** A quadrant of a tile can walk again from its parent's start ([`Seed::within`]):
//! its rays are some of the parent's, the nodes wholly before the parent's start are skipped
//! (the parent's walk saw them), and its bound is usually deeper. It saves ray steps but not
//! render time (`docs/log/svo.md`), so by default tiles are not refined.

use crate::evict::mark_visited;
use crate::geometry::{BoxU, Ray};
use crate::octree::Octree;
use crate::traverse::{Hit, Request, walk_from};

/// Relative slack taken off the bound: far above the few ulps by which a ray's computed
/// distance or a pixel's direction can differ from the exact one.
const SLACK: f64 = 1.0 / (1u64 << 40) as f64;

/// Margin (relative to the coordinates' and distance's magnitude) by which a ray's start point
/// must be inside its leaf: ~8 ulps.
const MARGIN: f64 = 1.0 / (1u64 << 49) as f64;

/// Most nodes one tile's walk visits (a guard: a walk cut short has no valid bound, and the
/// tile gets no start).
const MAX_VISITS: u32 = 1 << 14;

/// The frustum of a tile: the eye and the four side planes through it, each given by its
/// inward normal, spanned by the corner rays' directions.
struct Frustum {
    o: [f64; 3],
    n: [[f64; 3]; 4],
    /// L1 norm of each normal (for a box's farthest vertex along it).
    l1: [f64; 4],
    /// Per axis, +1 when every corner ray heads up the axis, -1 when every one heads down it,
    /// else 0: the frustum then lies on one side of the eye's plane across that axis.
    ahead: [f64; 3],
}

impl Frustum {
    /// The frustum of the corner rays `c` (pixel order: top left, top right, bottom left,
    /// bottom right), or `None` when their directions do not span a proper cone.
    fn of(c: &[Ray; 4]) -> Option<Frustum> {
        let cross = |a: [f64; 3], b: [f64; 3]| {
            [
                a[1] * b[2] - a[2] * b[1],
                a[2] * b[0] - a[0] * b[2],
                a[0] * b[1] - a[1] * b[0],
            ]
        };
        let dot = |a: [f64; 3], b: [f64; 3]| a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
        let axis: [f64; 3] = std::array::from_fn(|a| c.iter().map(|r| r.d[a]).sum());
        // Around the quad: top left, top right, bottom right, bottom left.
        let ring = [0, 1, 3, 2];
        let mut n = [[0.0; 3]; 4];
        for i in 0..4 {
            let (a, b) = (c[ring[i]].d, c[ring[(i + 1) % 4]].d);
            let mut v = cross(a, b);
            if dot(v, axis) < 0.0 {
                v = v.map(|x| -x);
            }
            n[i] = v;
        }
        // Every corner must be on the inner side of every plane (a proper, convex cone).
        for v in &n {
            if c.iter().any(|r| dot(*v, r.d) < -1e-12) || v.iter().any(|x| !x.is_finite()) {
                return None;
            }
        }
        Some(Frustum {
            o: c[0].o,
            n,
            l1: n.map(|v| v[0].abs() + v[1].abs() + v[2].abs()),
            ahead: std::array::from_fn(|a| {
                if c.iter().all(|r| r.d[a] > 0.0) {
                    1.0
                } else if c.iter().all(|r| r.d[a] < 0.0) {
                    -1.0
                } else {
                    0.0
                }
            }),
        })
    }
}

/// Distance from `o` to the nearest point of box `b`.
fn nearest(o: [f64; 3], b: &BoxU) -> f64 {
    let s = b.dim();
    let mut near = 0.0;
    for a in 0..3 {
        let lo = b.min[a] - o[a];
        let n = lo.max(-(lo + s)).max(0.0);
        near += n * n;
    }
    near.sqrt()
}

/// The smallest distance from the box `lo..=hi` (a point when they are equal) to a face of
/// box `b` containing it (negative when it is not contained).
fn room(b: &BoxU, lo: [f64; 3], hi: [f64; 3]) -> f64 {
    let s = b.dim();
    (0..3)
        .map(|a| (lo[a] - b.min[a]).min(b.min[a] + s - hi[a]))
        .fold(f64::INFINITY, f64::min)
}

/// Where a tile's rays start: node `id` (box `b`, a leaf or an inner node) holds every ray's
/// point at distance `t`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TileStart {
    /// The node.
    pub id: u32,
    /// Its box.
    pub b: BoxU,
    /// Distance (root units) at which the rays start.
    pub t: f64,
}

/// Scratch a worker keeps across tiles: the walk's stack of (node, box, squared nearest
/// distance).
pub type TileStack = Vec<(u32, BoxU, f64)>;

/// Where a tile's walk begins: node `id` (box `b`) holds every ray of the tile from distance
/// `t0`, up to at least `bound`, and no ray of the tile stops before `t0`, nor on an ancestor
/// of `id` before `bound`.
#[derive(Clone, Copy, Debug)]
pub struct Seed {
    /// The node.
    pub id: u32,
    /// Its box.
    pub b: BoxU,
    /// Distance before which no ray of the tile stops.
    pub t0: f64,
    /// Distance before which no ray of the tile leaves the node or stops on an ancestor.
    pub bound: f64,
}

impl Seed {
    /// The seed of a tile (corner rays `c`) whose walk starts at the node `id` (box `b`)
    /// holding the eye, or at the root when the eye is outside it. The tile's rays leave it
    /// through a face whose plane at distance `h` from the eye some corner ray heads towards
    /// (the others are behind every ray: a direction's component along the face's normal is
    /// a positive combination of the corners'), no earlier than `h / m`, `m` the largest
    /// component a unit direction of the tile can have along the normal: at most 1, and at
    /// most the largest corner's over `cmin` (a convex combination of the corners is at least
    /// `cmin` long). The ancestors' LOD stops are at `2 side / lod` or later (capped there
    /// too; far beyond the box).
    /// With the eye outside the root, the root is the node and there is no bound (no ray
    /// stops outside the root, and it has no ancestors).
    pub fn at_eye(c: &[Ray; 4], (id, b): (u32, BoxU)) -> Seed {
        let o = c[0].o;
        let s = b.dim();
        if !b.contains(o) {
            return Seed {
                id,
                b,
                t0: 0.0,
                bound: if b.depth == 0 { f64::INFINITY } else { 0.0 },
            };
        }
        let cmin = cos_min(c);
        let mut bound = 2.0 * s / c[0].lod;
        for a in 0..3 {
            for (h, sign) in [(o[a] - b.min[a], -1.0), (b.min[a] + s - o[a], 1.0)] {
                let top = c.iter().map(|r| sign * r.d[a]).fold(f64::MIN, f64::max);
                if top <= 0.0 {
                    continue;
                }
                let m = if cmin > 0.0 {
                    (top / cmin).min(1.0)
                } else {
                    1.0
                };
                bound = bound.min(h / m * (1.0 - SLACK));
            }
        }
        Seed {
            id,
            b,
            t0: 0.0,
            bound,
        }
    }

    /// The seed of a part of a tile (corner rays `c`) whose start is `s`: the parent of the
    /// node `s` names (or the node itself at the root), holding the part's rays at `s.t`;
    /// they leave it no earlier than `s.t` plus the distance from their points to its faces,
    /// and an ancestor's LOD stop is no nearer than its `max(dist, side / lod)`.
    pub fn within(tree: &Octree, c: &[Ray; 4], s: &TileStart) -> Option<Seed> {
        let (mut id, mut b) = (s.id, s.b);
        if b.depth > 0 {
            id = tree.nodes[id as usize].parent;
            b = tree.anchor.parent(&b);
        }
        let (lo, hi) = points_box(c, s.t);
        let room = room(&b, lo, hi);
        if room.is_nan() || room <= 0.0 {
            return None;
        }
        let mut bound = s.t + room;
        let lod = c[0].lod;
        let o = c[0].o;
        let (mut aid, mut ab) = (id, b);
        while ab.depth > 0 && ab.dim() * 2.0 < bound * lod {
            aid = tree.nodes[aid as usize].parent;
            ab = tree.anchor.parent(&ab);
            bound = bound.min(nearest(o, &ab).max(ab.dim() / lod));
        }
        Some(Seed {
            id,
            b,
            t0: s.t,
            bound,
        })
    }
}

/// A lower bound of the length of any convex combination of the corner rays' unit directions
/// `c` (their components along the unit vector of their sum, the smallest of them, less a
/// relative slack); 0 or less (or NaN) when they do not lie in one half-space.
fn cos_min(c: &[Ray; 4]) -> f64 {
    let axis: [f64; 3] = std::array::from_fn(|a| c.iter().map(|r| r.d[a]).sum());
    let len = (axis[0] * axis[0] + axis[1] * axis[1] + axis[2] * axis[2]).sqrt();
    c.iter()
        .map(|r| (r.d[0] * axis[0] + r.d[1] * axis[1] + r.d[2] * axis[2]) / len)
        .fold(f64::INFINITY, f64::min)
        * (1.0 - SLACK)
}

/// The box of the points at distance `t` of every ray between the corner rays `c`: the corner
/// points' box widened by the bulge of the sphere of radius `t` between them and a margin.
fn points_box(c: &[Ray; 4], t: f64) -> ([f64; 3], [f64; 3]) {
    let pts = c.map(|r| std::array::from_fn::<f64, 3, _>(|a| r.o[a] + t * r.d[a]));
    let cmin = cos_min(c);
    let mag = t + c[0].o.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    let pad = t * (1.0 - cmin).max(0.0) + mag * MARGIN;
    let lo = std::array::from_fn(|a| pts.iter().map(|p| p[a]).fold(f64::MAX, f64::min) - pad);
    let hi = std::array::from_fn(|a| pts.iter().map(|p| p[a]).fold(f64::MIN, f64::max) + pad);
    (lo, hi)
}

/// The start of the tile whose corner pixels cast the rays `c`, walking from `seed`, and the
/// nodes the walk visited. `None` when no start was found (the rays then start the old way).
pub fn tile_start(
    tree: &Octree,
    c: &[Ray; 4],
    seed: &Seed,
    stack: &mut TileStack,
) -> (Option<TileStart>, u32) {
    let Some(fr) = Frustum::of(c) else {
        return (None, 0);
    };
    let lod = c[0].lod;
    let nodes = &tree.nodes;
    let mut best = seed.bound;
    if best.is_nan() || best <= 0.0 {
        return (None, 0);
    }
    let t0 = seed.t0;
    // Distances are compared squared (no square root per child); `best2` follows `best`.
    let mut best2 = best * best;
    let t02 = t0 * t0;
    let lod2 = lod * lod;
    // The eye's largest coordinate, for the culling tolerance below.
    let eye_mag = fr.o.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    stack.clear();
    stack.push((seed.id, seed.b, 0.0));
    let mut visits = 0u32;
    while let Some((id, b, near2)) = stack.pop() {
        if near2 >= best2 {
            continue;
        }
        visits += 1;
        if visits > MAX_VISITS {
            return (None, visits);
        }
        let n = &nodes[id as usize];
        if n.is_leaf() {
            if n.is_empty() {
                mark_visited(tree, id);
            } else {
                best = near2.sqrt();
                best2 = near2;
            }
            continue;
        }
        let side = b.dim();
        if side * side < near2 * lod2 {
            best = near2.sqrt();
            best2 = near2;
            continue;
        }
        // The box's centre relative to the eye, its children's half side `q`, and each side
        // plane's height of the centre.
        let h = 0.5 * side;
        let q = 0.5 * h;
        let pc: [f64; 3] = std::array::from_fn(|a| b.min[a] + h - fr.o[a]);
        let far2: f64 = pc.iter().map(|x| (x.abs() + h) * (x.abs() + h)).sum();
        if side * side < far2 * lod2 * (1.0 + SLACK) {
            let cand = near2.sqrt().max(side / lod);
            if cand < best {
                best = cand;
                best2 = cand * cand;
            }
        }
        // The tolerance covers the slack on distances and the rounding of the traversal's
        // points, which is relative to the coordinates (far larger than the distances when the
        // eye is far from the anchor): a ray passing within that of a box may enter it.
        let mag = pc[0].abs() + pc[1].abs() + pc[2].abs() + h;
        let eps = mag * SLACK + (eye_mag + mag) * MARGIN;
        let dots: [f64; 4] = std::array::from_fn(|i| {
            let v = fr.n[i];
            v[0] * pc[0] + v[1] * pc[1] + v[2] * pc[2]
        });
        let tol: [f64; 4] = std::array::from_fn(|i| -fr.l1[i] * eps);
        // The children that meet the frustum nearer than the bound and do not lie wholly
        // before `t0` (the seed's tile walk saw them: no stop there), pushed farthest first.
        let mut kids = [(0u32, BoxU::ROOT, 0.0f64); 8];
        let mut k = 0;
        for oc in 0..8 {
            let sg = |a: usize| if oc >> a & 1 == 1 { q } else { -q };
            let cc = [pc[0] + sg(0), pc[1] + sg(1), pc[2] + sg(2)];
            let meets = (0..4).all(|i| {
                let v = fr.n[i];
                dots[i] + v[0] * sg(0) + v[1] * sg(1) + v[2] * sg(2) + q * fr.l1[i] >= tol[i]
            }) && (0..3).all(|a| fr.ahead[a] * cc[a] + q >= -eps);
            if !meets {
                continue;
            }
            let mut cn2 = 0.0;
            let mut cf2 = 0.0;
            for x in cc {
                let d = (x.abs() - q).max(0.0);
                let f = x.abs() + q;
                cn2 += d * d;
                cf2 += f * f;
            }
            if cn2 >= best2 || cf2 < t02 {
                continue;
            }
            let mut j = k;
            while j > 0 && kids[j - 1].2 < cn2 {
                kids[j] = kids[j - 1];
                j -= 1;
            }
            kids[j] = (n.children + oc as u32, b.child(oc), cn2);
            k += 1;
        }
        stack.extend_from_slice(&kids[..k]);
    }
    let mut t = (best * (1.0 - SLACK)).max(t0);
    if t.is_nan() || t <= 0.0 || !t.is_finite() {
        return (None, visits);
    }
    // The deepest node holding every ray's point at `t`. When the bound is the seed's own
    // (the rays leave it first), the points' box, widened by the bulge, crosses its face:
    // any earlier distance is a valid start too, so step back until the box fits.
    let (mut lo, mut hi) = points_box(c, t);
    let mut tries = 0;
    while !(seed.b.contains(lo) && seed.b.contains(hi)) {
        tries += 1;
        if tries > 8 {
            return (None, visits);
        }
        t = t0 + (t - t0) * 0.75;
        (lo, hi) = points_box(c, t);
    }
    let (mut id, mut b) = (seed.id, seed.b);
    while !nodes[id as usize].is_leaf() {
        let oc = b.octant_of(lo);
        if b.octant_of(hi) != oc {
            break;
        }
        id = nodes[id as usize].children + oc as u32;
        b = b.child(oc);
    }
    (Some(TileStart { id, b, t }), visits)
}

/// Earlier distances (fractions of the tile's start distance) a ray tries when its point at
/// the start distance is within the margin of a face: any distance before the bound is a
/// valid start, and a step back of a thousandth moves the point by about a leaf.
const RETRIES: [f64; 2] = [1.0 - 1.0 / 1024.0, 1.0 - 1.0 / 32.0];

/// The neighbour traversal of pixel ray `r` from its tile's start `s`: the hit the ray's
/// traversal from the eye finds, after fewer steps; `None` when its point at the start
/// distance, and at the `RETRIES`, is within the margin of a face of its leaf (or outside
/// `s`), so the caller must start it at the skip node.
///
/// Inlined into the render loop: called, the pixel's ray was built on the stack one component
/// at a time and read back two at a time, a store-forwarding stall on every ray.
#[inline(always)]
pub fn cast_at(
    tree: &Octree,
    r: &Ray,
    s: &TileStart,
    path: &mut StartPath,
    reqs: &mut Vec<Request>,
) -> Option<Hit> {
    let (id, b, t, p, steps) = start_leaf(tree, r, s, s.t, path)
        .or_else(|| start_leaf(tree, r, s, s.t * RETRIES[0], path))
        .or_else(|| start_leaf(tree, r, s, s.t * RETRIES[1], path))?;
    let mut hit = walk_from(tree, r, id, b, t, p, reqs);
    hit.steps += steps;
    Some(hit)
}

/// The descent that found the previous start leaf from the same tile start (node, box and
/// distance): the nodes from that node down to the leaf. Neighbouring rays' start points are
/// about a pixel apart, so the next ray's leaf is usually the same leaf or a near relative;
/// the ray climbs this path to the deepest node holding its point, or to the start node (box
/// tests, no node loads), and descends from there. A descent from the tile's start node took
/// about three steps a ray, a third of the Mandelbulb zoom's. The leaf found is the same: a
/// box holds the point, and every node above it on the path passed the footprint test at
/// the same distance and LOD factor (one per frame).
#[derive(Debug, Default)]
pub struct StartPath {
    /// Tile start node, its box and the start distance (bits) the path belongs to. The box
    /// too: refined tiles rebuild their start boxes from a snap, so two tiles could in
    /// principle give one node boxes that differ in a last bit.
    key: Option<(u32, BoxU, u64)>,
    /// The descent, from the tile start node down.
    path: Vec<(u32, BoxU)>,
}

/// The leaf (id, box) holding ray `r`'s point at distance `t`, found by descending from the
/// deepest node of `path` that holds the point (the tile's start node when the path is for
/// another start), with `t`, the point and the descent's steps; `None` when the point is not
/// a margin inside the leaf, or the leaf is not empty, or it or its parent is below the
/// footprint (none of which a valid start meets; checked so that a bound off by a rounding
/// never starts a ray inside a stop).
#[inline(always)]
fn start_leaf(
    tree: &Octree,
    r: &Ray,
    s: &TileStart,
    t: f64,
    path: &mut StartPath,
) -> Option<(u32, BoxU, f64, [f64; 3], u32)> {
    let p: [f64; 3] = std::array::from_fn(|a| r.o[a] + t * r.d[a]);
    let nodes = &tree.nodes;
    let key = Some((s.id, s.b, t.to_bits()));
    if path.key != key {
        path.key = key;
        path.path.clear();
        path.path.push((s.id, s.b));
    }
    let path = &mut path.path;
    while path.len() > 1 && !path[path.len() - 1].1.contains(p) {
        path.pop();
    }
    let (mut id, mut b) = path[path.len() - 1];
    let mut steps = 0;
    while !nodes[id as usize].is_leaf() {
        if b.dim() < t * r.lod {
            return None;
        }
        let oc = b.octant_of(p);
        id = nodes[id as usize].children + oc as u32;
        b = b.child(oc);
        path.push((id, b));
        steps += 1;
    }
    if !nodes[id as usize].is_empty() || (b.depth > 0 && 2.0 * b.dim() < t * r.lod) {
        return None;
    }
    // A point outside `s` is outside the leaf too: this also rejects it.
    let m = (t + p.iter().fold(0.0f64, |m, x| m.max(x.abs()))) * MARGIN;
    let side = b.dim();
    if (0..3).any(|a| p[a] < b.min[a] + m || p[a] > b.min[a] + side - m) {
        return None;
    }
    Some((id, b, t, p, steps))
}

/// The node to start the frame's tile walks from: the smallest ancestor of the eye's leaf
/// `skip` whose nearest face is at least `reach` from the eye `o` (or the root). With `reach`
/// the last frame's median hit distance, most tiles find their bound inside it, and the walks
/// do not descend from the root on every tile.
pub fn walk_root(tree: &Octree, skip: (u32, BoxU), o: [f64; 3], reach: f64) -> (u32, BoxU) {
    let (mut id, mut b) = skip;
    loop {
        if room(&b, o, o) >= reach || b.depth == 0 {
            return (id, b);
        }
        id = tree.nodes[id as usize].parent;
        b = tree.anchor.parent(&b);
    }
}
