//! The marching-cubes case table, derived here from one rule per cube face instead of typed in.
//!
//! A cell's 8 corners are inside (`d < 0`) or outside. On each face the contour is fixed by the
//! face's four corners alone: no segment (all alike), one segment cutting off the odd corner,
//! one segment between two adjacent pairs, or, for the ambiguous diagonal face, two segments
//! each cutting off an *inside* corner (inside corners never connect across a face). Because
//! the rule looks at nothing but the face, the two cells sharing a face agree on its segments,
//! which is what makes the surface watertight. Every sign-changing cube edge ends exactly one
//! segment on each of its two faces, so the segments link into closed loops; each loop is one
//! disk-shaped patch of surface in the cell (the connected components that manifold dual
//! contouring needs, and the polygons marching cubes fans into triangles).
//!
//! Segments are directed so that, seen from outside the cell through that face, the inside
//! corner lies to the left; the neighbour cell sees the same segment through the face from the
//! other side and so traverses it the other way. Loops are therefore consistently oriented;
//! reversed, their fans face outward (from `d < 0` towards `d > 0`), which the tests check.
//!
//! Why our own code: the usual 256-row table (Lorensen and Cline, Bourke) carries triangles
//! only; we also need each case's loops (patches), and deriving both from the face rule keeps
//! them consistent by construction.

use std::sync::LazyLock;

/// The corner at bit pattern `c` (bit 0: x, bit 1: y, bit 2: z) as 0/1 coordinates.
pub fn corner(c: usize) -> [usize; 3] {
    [c & 1, (c >> 1) & 1, (c >> 2) & 1]
}

/// The 12 cube edges as (axis, lower corner); the upper corner adds `1 << axis`.
pub static EDGES: LazyLock<[(usize, usize); 12]> = LazyLock::new(|| {
    let mut e = [(0, 0); 12];
    for axis in 0..3 {
        let (b, c) = ((axis + 1) % 3, (axis + 2) % 3);
        for k in 0..4 {
            e[axis * 4 + k] = (axis, (k & 1) << b | ((k >> 1) & 1) << c);
        }
    }
    e
});

/// The edge between corners `a` and `b` (which must differ in one bit).
fn edge_between(a: usize, b: usize) -> usize {
    let lo = a.min(b);
    let axis = (a ^ b).trailing_zeros() as usize;
    EDGES
        .iter()
        .position(|&(ax, c)| ax == axis && c == lo)
        .expect("corners differ in one bit")
}

/// One case: its loops, each an ordered list of cube edges (0..12), oriented outward.
#[derive(Clone, Debug, Default)]
pub struct Case {
    pub loops: Vec<Vec<u8>>,
    /// For each cube edge, the loop it belongs to (255 when the edge has no sign change).
    pub loop_of_edge: [u8; 12],
}

/// The 256 cases, indexed by the inside mask (bit `c` set when corner `c` is inside).
pub static CASES: LazyLock<Vec<Case>> = LazyLock::new(|| (0..256).map(build_case).collect());

/// A face's corners in cyclic order, counter-clockwise seen from outside the cube.
fn face_corners(axis: usize, side: usize) -> [usize; 4] {
    let (b, c) = ((axis + 1) % 3, (axis + 2) % 3);
    let base = side << axis;
    // Counter-clockwise around +axis in the (b, c) plane; seen from outside a side-0 face
    // (looking along +axis) that is clockwise, so reverse it.
    let ccw = [base, base | 1 << b, base | 1 << b | 1 << c, base | 1 << c];
    if side == 1 {
        ccw
    } else {
        [ccw[0], ccw[3], ccw[2], ccw[1]]
    }
}

fn build_case(mask: usize) -> Case {
    let inside = |c: usize| mask >> c & 1 == 1;
    // next[edge] = the edge the outgoing segment from `edge` leads to.
    let mut next = [u8::MAX; 12];
    for axis in 0..3 {
        for side in 0..2 {
            let f = face_corners(axis, side);
            let ins: Vec<bool> = f.iter().map(|&c| inside(c)).collect();
            // The face's edge i joins f[i] and f[i + 1].
            let fe = |i: usize| edge_between(f[i % 4], f[(i + 1) % 4]) as u8;
            let count = ins.iter().filter(|&&b| b).count();
            let mut segs: Vec<(u8, u8)> = Vec::new();
            if count == 2 && ins[0] == ins[2] {
                // Ambiguous: cut off each inside corner.
                for (i, &inside) in ins.iter().enumerate() {
                    if inside {
                        // Corner f[i] is between face edges i-1 and i.
                        segs.push(cut(i, true, &fe));
                    }
                }
            } else if count == 1 || count == 3 {
                let odd = (0..4).find(|&i| ins[i] == (count == 1)).unwrap();
                segs.push(cut(odd, ins[odd], &fe));
            } else if count == 2 {
                // Adjacent pair: the two crossing edges are the ones whose ends differ.
                let crossing: Vec<usize> = (0..4).filter(|&i| ins[i] != ins[(i + 1) % 4]).collect();
                let (i, j) = (crossing[0], crossing[1]);
                // Edge i joins f[i] and f[i+1]. With the corners counter-clockwise seen from
                // outside, walking from edge j to edge i keeps f[i+1]..f[j] on the left.
                if ins[(i + 1) % 4] {
                    segs.push((fe(j), fe(i)));
                } else {
                    segs.push((fe(i), fe(j)));
                }
            }
            for (a, b) in segs {
                assert_eq!(
                    next[a as usize],
                    u8::MAX,
                    "edge {a} leaves twice (case {mask})"
                );
                next[a as usize] = b;
            }
        }
    }
    let mut case = Case {
        loops: Vec::new(),
        loop_of_edge: [u8::MAX; 12],
    };
    for start in 0..12 {
        if next[start] == u8::MAX || case.loop_of_edge[start] != u8::MAX {
            continue;
        }
        let id = case.loops.len() as u8;
        let mut lp = Vec::new();
        let mut e = start;
        loop {
            case.loop_of_edge[e] = id;
            lp.push(e as u8);
            e = next[e] as usize;
            if e == start {
                break;
            }
        }
        // Inside on the left, seen from outside the cell, runs clockwise around the outward
        // normal; reversed, the loop's fan faces outward.
        lp.reverse();
        // Marching cubes fans each loop from its first edge. A fan diagonal between two edges
        // of one cube face could be drawn by the neighbour across that face too (a loop that
        // crosses an ambiguous face twice), and more than two triangles would share it; start
        // the fan where none of its diagonals lies on a face. Every case has such a start
        // (tested).
        let n = lp.len();
        let start = (0..n)
            .find(|&s| (2..n - 1).all(|i| !on_one_face(lp[s], lp[(s + i) % n])))
            .unwrap_or(0);
        lp.rotate_left(start);
        case.loops.push(lp);
    }
    case
}

/// Whether cube edges `a` and `b` lie on a common face (the only way two edges are also edges
/// of one other cell).
fn on_one_face(a: u8, b: u8) -> bool {
    let faces = |e: u8| {
        let (axis, c) = EDGES[e as usize];
        [1, 2].map(|k| {
            let f = (axis + k) % 3;
            (f, c >> f & 1)
        })
    };
    let fb = faces(b);
    faces(a).iter().any(|f| fb.contains(f))
}

/// The segment cutting off corner `f[i]` (between face edges i-1 and i), directed so the
/// inside lies on the left seen from outside: around an inside corner the segment runs from
/// edge i to edge i-1 (the corner is on its left going counter-clockwise), around an outside
/// corner the other way.
fn cut(i: usize, corner_inside: bool, fe: &dyn Fn(usize) -> u8) -> (u8, u8) {
    let before = fe(i + 3);
    let after = fe(i);
    if corner_inside {
        (after, before)
    } else {
        (before, after)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_sign_changing_edge_is_on_exactly_one_loop() {
        for (mask, case) in CASES.iter().enumerate() {
            for (e, &(axis, c)) in EDGES.iter().enumerate() {
                let changes = (mask >> c & 1) != (mask >> (c | 1 << axis) & 1);
                assert_eq!(
                    case.loop_of_edge[e] != u8::MAX,
                    changes,
                    "case {mask} edge {e}"
                );
            }
            let total: usize = case.loops.iter().map(Vec::len).sum();
            assert_eq!(
                total,
                (0..12).filter(|&e| case.loop_of_edge[e] != u8::MAX).count()
            );
            assert!(case.loops.iter().all(|l| l.len() >= 3), "case {mask}");
        }
        assert!(CASES[0].loops.is_empty() && CASES[255].loops.is_empty());
    }

    /// No fan diagonal joins two edges of one face, so no other cell can draw it too.
    #[test]
    fn fan_diagonals_never_lie_on_a_face() {
        let mut longer = 0;
        for (mask, case) in CASES.iter().enumerate() {
            for lp in &case.loops {
                for i in 2..lp.len() - 1 {
                    assert!(!on_one_face(lp[0], lp[i]), "case {mask} loop {lp:?}");
                }
                longer += usize::from(lp.len() > 3);
            }
        }
        // The check can fail: adjacent loop edges do share a face.
        assert!(on_one_face(CASES[1].loops[0][0], CASES[1].loops[0][1]));
        assert!(longer > 0, "no loop has a diagonal to check");
    }

    /// The loop around a lone inside corner, fanned, faces away from that corner.
    #[test]
    fn loops_face_outward() {
        let mid = |e: u8| {
            let (axis, c) = EDGES[e as usize];
            let mut p = corner(c).map(|v| v as f64);
            p[axis] += 0.5;
            glam::DVec3::from(p)
        };
        for c in 0..8 {
            for (mask, towards_inside) in [(1 << c, -1.0), (255 ^ 1 << c, 1.0)] {
                let lp = &CASES[mask].loops[0];
                let (a, b, d) = (mid(lp[0]), mid(lp[1]), mid(lp[2]));
                let n = (b - a).cross(d - a);
                let to_corner = glam::DVec3::from(corner(c).map(|v| v as f64)) - a;
                assert!(
                    n.dot(to_corner) * towards_inside > 0.0,
                    "case {mask}: normal {n:?}"
                );
            }
        }
    }
}
