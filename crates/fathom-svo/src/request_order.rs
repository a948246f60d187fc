//! The order in which a frame's subdivision requests are served: the largest voxels on screen
//! first, those near the screen's centre counted larger ([`Fovea`]).
//!
//! A frame serves a few hundred of the thousands of leaves its rays found wider than their
//! pixels; the rest wait. Served purely by size on screen, a zoom spent much of its budget on
//! voxels near the edges of the view, which its next frames push off screen: zooming 3.5 % a
//! frame, a voxel halfway to the top edge leaves the view in 20 frames, one a tenth of the way
//! stays for 67 (a window's flight forward does the same). Weighting a request's
//! size on screen by its distance from the centre spends the budget where it lasts: on the
//! Mandelbulb's 400-frame zoom to 1e6 the frames' median similarity to the sphere tracer rose
//! from 0.190 to 0.260 at the same split budget, and half the budget with the fovea still
//! beats the whole without it (`docs/log/svo.md`, "Splits that stay on screen"). A still view
//! ends with the same tree whatever the order: only the order changes.

use crate::traverse::Request;
use glam::DVec3;
use rayon::prelude::*;

/// The default [`Fovea::weight`]: of the weights tried (0 to 64), the one whose zooms came
/// closest to the sphere tracer's frames (`docs/log/svo.md`).
pub const DEFAULT_FOVEA: f64 = 4.0;

/// Where the screen's centre is, to weight requests by their distance from it: a request's
/// priority is its size on screen divided by `1 + weight rho^2`, with `rho` the distance of
/// its box's centre from the screen's centre in half-heights of the view (1 at the top and
/// bottom edges, 1.67 in the corners of a 4:3 view).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Fovea {
    /// The eye, in the tree's local root units (as the requests' boxes).
    pub eye: [f64; 3],
    /// The view's unit forward direction.
    pub forward: DVec3,
    /// Tangent of half the vertical field of view.
    pub tan_half_fov: f64,
    /// Width over height of the view: `rho` is at most the corner's, `sqrt(1 + aspect^2)`.
    pub aspect: f64,
    /// How much nearer the centre counts: 0 serves the largest on screen first wherever they
    /// are; 4 counts a voxel at the top edge as a fifth of its size, [0, 64].
    pub weight: f64,
}

impl Fovea {
    /// No weighting: requests are served by size on screen alone.
    pub const NONE: Fovea = Fovea {
        eye: [0.0; 3],
        forward: DVec3::Z,
        tan_half_fov: 1.0,
        aspect: 1.0,
        weight: 0.0,
    };

    /// The square of `rho`, the distance of `r`'s box centre from the screen's centre in
    /// half-heights, at most the corner's (a ray met the box, so it is on screen): 0 for a
    /// box that reaches the plane of the eye (its centre within a half-diagonal of it, or
    /// behind), which is so close that it covers much of the view, the centre included.
    pub fn rho2(&self, r: &Request) -> f64 {
        let h = 0.5 * r.b.dim();
        let v = DVec3::from_array(std::array::from_fn(|a| r.b.min[a] + h - self.eye[a]));
        let along = v.dot(self.forward);
        if along.is_nan() || along <= h * 3f64.sqrt() {
            return 0.0;
        }
        // tan^2 of the angle off the axis, without a square root: |v|^2 / along^2 - 1.
        let tan2 = (v.length_squared() / (along * along) - 1.0).max(0.0);
        (tan2 / (self.tan_half_fov * self.tan_half_fov)).min(1.0 + self.aspect * self.aspect)
    }

    /// The priority of `r`: its size on screen ([`Request::footprint`]) divided by
    /// `1 + weight rho^2`; exactly the size on screen when `weight` is 0.
    pub fn priority(&self, r: &Request) -> f64 {
        if self.weight == 0.0 {
            return r.footprint();
        }
        r.footprint() / (1.0 + self.weight * self.rho2(r))
    }
}

/// How many requests a [`RequestQueue`] puts in order at first: more than a frame's budget
/// splits (a few hundred), so a frame usually sorts no further.
pub const FIRST_SORTED: usize = 2048;

/// A frame's requests in serving order, sorted only as far as they are taken.
///
/// Served highest priority ([`Fovea::priority`]) first; ties by node id, so the order does not
/// depend on which ray claimed a leaf first beyond its distance. Size on screen is side over
/// the distance at which a ray reached the voxel: a zoom's frames lose their biggest blocks
/// first, not their shallowest (a shallow voxel far away can be smaller on screen than a deep
/// one in front of the eye).
///
/// Why not a plain sort: a Menger zoom's frames request 70-90 thousand leaves and split a few
/// hundred; sorting them all took 5-7 % of the zoom's run (about 2 ms of the 6 ms budget), and
/// the fovea leaves more requests waiting. Each priority (a division or two) is computed once,
/// on the caller's rayon pool; a selection puts the first [`FIRST_SORTED`] in front, and only
/// those are sorted, the next ones (twice as many each time) only if the budget reaches them.
/// The order taken is the one `f64::total_cmp` gives (descending), then ids: keys are unique,
/// so it does not depend on the selection or the sort.
pub struct RequestQueue {
    reqs: Vec<Request>,
    /// (priority key, node id, index into `reqs`), in serving order up to `sorted`.
    order: Vec<(std::cmp::Reverse<i64>, u32, u32)>,
    sorted: usize,
}

impl RequestQueue {
    /// The queue of `reqs` by `fovea`'s priorities, its first [`FIRST_SORTED`] in order.
    pub fn new(reqs: Vec<Request>, fovea: &Fovea) -> RequestQueue {
        let order = reqs
            .par_iter()
            .enumerate()
            .map(|(i, r)| {
                (
                    std::cmp::Reverse(total_order(fovea.priority(r))),
                    r.id,
                    i as u32,
                )
            })
            .collect();
        let mut q = RequestQueue {
            reqs,
            order,
            sorted: 0,
        };
        q.sort_to(FIRST_SORTED);
        q
    }

    /// Number of requests.
    pub fn len(&self) -> usize {
        self.order.len()
    }

    /// True when there are none.
    pub fn is_empty(&self) -> bool {
        self.order.is_empty()
    }

    /// Puts at least the first `end` requests (all, if fewer) in serving order.
    fn sort_to(&mut self, end: usize) {
        if end <= self.sorted {
            return;
        }
        let want = end.max(2 * self.sorted).min(self.order.len());
        let rest = &mut self.order[self.sorted..];
        let k = want - self.sorted;
        if k < rest.len() {
            rest.select_nth_unstable(k);
        }
        rest[..k].par_sort_unstable();
        self.sorted = want;
    }

    /// The requests at positions `start..end` of the serving order (`end` at most
    /// [`RequestQueue::len`]).
    pub fn take(&mut self, start: usize, end: usize) -> Vec<Request> {
        self.sort_to(end);
        self.order[start..end]
            .iter()
            .map(|&(_, _, i)| self.reqs[i as usize])
            .collect()
    }

    /// The requests from position `start` of the serving order on, in no particular order.
    pub fn from(&self, start: usize) -> impl Iterator<Item = &Request> {
        debug_assert!(start <= self.sorted || start >= self.order.len());
        self.order[start.min(self.order.len())..]
            .iter()
            .map(|&(_, _, i)| &self.reqs[i as usize])
    }
}

/// `f64::total_cmp` as a key: the bits with the sign's meaning folded in, as that function
/// compares them.
fn total_order(x: f64) -> i64 {
    let bits = x.to_bits() as i64;
    bits ^ ((((bits >> 63) as u64) >> 1) as i64)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::BoxU;

    fn ids(r: Vec<Request>) -> Vec<u32> {
        r.iter().map(|q| q.id).collect()
    }

    /// The box of depth `d` along the root's first corner.
    fn corner(d: u8) -> BoxU {
        (0..d).fold(BoxU::ROOT, |b, _| b.child(0))
    }

    #[test]
    fn the_request_order_is_total_cmp_then_id() {
        // Footprints with ties, zeros of both signs, infinities (t = 0) and a NaN.
        let ts = [0.5, 0.0, -0.0, 1e-300, 2.0, 0.5, f64::NAN, 3.0, 1e300, 0.25];
        let r: Vec<Request> = (0..200u32)
            .map(|i| Request {
                id: (i * 7919) % 1000,
                b: corner((i % 5) as u8),
                t: ts[(i as usize * 31) % ts.len()],
            })
            .collect();
        let mut want = r.clone();
        want.sort_by(|a, b| {
            b.footprint()
                .total_cmp(&a.footprint())
                .then(a.id.cmp(&b.id))
        });
        let n = r.len();
        let r = RequestQueue::new(r, &Fovea::NONE).take(0, n);
        let key = |q: &Request| (q.footprint().to_bits(), q.id);
        assert_eq!(
            r.iter().map(key).collect::<Vec<_>>(),
            want.iter().map(key).collect::<Vec<_>>()
        );
    }

    #[test]
    fn a_queue_taken_in_pieces_past_its_first_sort_is_the_full_sort() {
        // More requests than the first selection puts in order, with ties in footprint (ids
        // decide), taken in pieces that cross the sorted prefix; the rest is the remainder.
        let n = 3 * FIRST_SORTED + 77;
        let r: Vec<Request> = (0..n as u32)
            .map(|i| {
                let j = (i as u64 * 2654435761 % n as u64) as u32;
                Request {
                    id: j,
                    b: corner((j % 7) as u8),
                    t: 1.0 + (j % 13) as f64,
                }
            })
            .collect();
        let mut want = r.clone();
        want.sort_by(|a, b| {
            LOOK_Z
                .priority(b)
                .total_cmp(&LOOK_Z.priority(a))
                .then(a.id.cmp(&b.id))
        });
        let mut q = RequestQueue::new(r, &LOOK_Z);
        assert_eq!(q.len(), n);
        let mut got = Vec::new();
        for (a, b) in [
            (0, 100),
            (100, FIRST_SORTED + 5),
            (FIRST_SORTED + 5, 2 * FIRST_SORTED),
        ] {
            got.extend(q.take(a, b));
        }
        assert_eq!(ids(got), ids(want[..2 * FIRST_SORTED].to_vec()));
        let mut rest: Vec<u32> = q.from(2 * FIRST_SORTED).map(|r| r.id).collect();
        rest.sort_unstable();
        let mut want_rest = ids(want[2 * FIRST_SORTED..].to_vec());
        want_rest.sort_unstable();
        assert_eq!(rest, want_rest);
        assert_eq!(
            ids(q.take(2 * FIRST_SORTED, n)),
            ids(want[2 * FIRST_SORTED..].to_vec())
        );
    }

    #[test]
    fn without_a_fovea_requests_are_served_largest_on_screen_first() {
        // A deep voxel close to the eye is larger on screen than a shallow one far away.
        let r = vec![
            Request {
                id: 1,
                b: corner(2),
                t: 100.0,
            },
            Request {
                id: 2,
                b: corner(6),
                t: 0.001,
            },
            Request {
                id: 3,
                b: corner(3),
                t: 1.0,
            },
        ];
        assert_eq!(
            ids(RequestQueue::new(r, &Fovea::NONE).take(0, 3)),
            [2, 3, 1]
        );
    }

    /// A request for the box of side 1/8 centred `off` units off the axis of a fovea that
    /// looks along +z from 4 units in front of it (root units), hit at distance 4.
    fn off_axis(id: u32, off: f64) -> Request {
        let s = 0.125;
        Request {
            id,
            b: BoxU {
                min: [off - 0.5 * s, -0.5 * s, -0.5 * s],
                depth: 3,
            },
            t: 4.0,
        }
    }

    const LOOK_Z: Fovea = Fovea {
        eye: [0.0, 0.0, -4.0],
        forward: DVec3::Z,
        // A 90-degree view: rho is the tangent of the angle off the axis.
        tan_half_fov: 1.0,
        aspect: 4.0 / 3.0,
        weight: DEFAULT_FOVEA,
    };

    #[test]
    fn rho_is_the_distance_from_the_screen_centre_in_half_heights() {
        // Centres 0, 2 and 4 units off the axis at 4 units ahead: tangents 0, 0.5 and 1.
        for (off, rho) in [(0.0, 0.0), (2.0, 0.5), (4.0, 1.0)] {
            let got = LOOK_Z.rho2(&off_axis(0, off));
            assert!((got - rho * rho).abs() < 1e-12, "off {off}: rho^2 {got}");
        }
        // Half the field of view's tangent doubles rho.
        let narrow = Fovea {
            tan_half_fov: 0.5,
            ..LOOK_Z
        };
        assert!((narrow.rho2(&off_axis(0, 2.0)) - 1.0).abs() < 1e-12);
        // Far off the axis, rho is held at the corner's (5/3 in a 4:3 view).
        let got = LOOK_Z.rho2(&off_axis(0, 40.0));
        assert!((got - 25.0 / 9.0).abs() < 1e-12, "rho^2 {got}");
        // A box that reaches the plane of the eye counts as central: its centre level with
        // the eye, within a half-diagonal in front of it (so far off the axis, the corner's
        // rho if it did not), or behind.
        let mut beside = off_axis(0, 3.0);
        let s = beside.b.dim();
        for centre_z in [-4.0, -4.0 + 0.8 * s, -6.0] {
            beside.b.min[2] = centre_z - 0.5 * s;
            assert_eq!(LOOK_Z.rho2(&beside), 0.0, "centre at z = {centre_z}");
        }
        beside.b.min[2] = -4.0 + 0.9 * s - 0.5 * s;
        let got = LOOK_Z.rho2(&beside);
        assert!(
            (got - 25.0 / 9.0).abs() < 1e-12,
            "just past the half-diagonal: {got}"
        );
        // A voxel the eye is at (t = 0, infinitely large on screen) comes first anywhere.
        let mut at_eye = off_axis(0, 40.0);
        at_eye.t = 0.0;
        assert_eq!(LOOK_Z.priority(&at_eye), f64::INFINITY);
    }

    #[test]
    fn a_fovea_serves_a_voxel_at_the_centre_before_a_larger_one_at_the_edge() {
        // The edge voxel is 4 times the centre one's size on screen (hit at a quarter of the
        // distance); at the edge (rho 1) it counts 1 / (1 + 4) of that, 0.8 of the centre's.
        let centre = off_axis(1, 0.0);
        let mut edge = off_axis(2, 4.0);
        edge.t = 1.0;
        assert!(edge.footprint() > 3.9 * centre.footprint());
        let r = vec![edge, centre];
        assert_eq!(
            ids(RequestQueue::new(r.clone(), &LOOK_Z).take(0, 2)),
            [1, 2]
        );
        // Without the fovea, or with a weight too small to outweigh 4 times the size, the
        // edge voxel comes first.
        for fovea in [
            Fovea::NONE,
            Fovea {
                weight: 2.0,
                ..LOOK_Z
            },
        ] {
            assert_eq!(ids(RequestQueue::new(r.clone(), &fovea).take(0, 2)), [2, 1]);
        }
        // A zero weight gives the size on screen exactly.
        let none = Fovea {
            weight: 0.0,
            ..LOOK_Z
        };
        assert_eq!(none.priority(&edge).to_bits(), edge.footprint().to_bits());
    }
}
