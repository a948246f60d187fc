//! The geometry the octree's modules share: boxes (exact lattice [`Cell`]s and f64
//! [`BoxU`]s relative to the anchor), rays, and where a ray enters or leaves a box.
//!
//! A leaf module: it depends on nothing else in the crate, so the node, plane, octree,
//! traversal and eviction modules can all use it without importing each other in a circle.
//! Boxes are half-open: a point on a shared face belongs to the box on its positive side.

/// A box by its exact lattice position: integer coordinates `ijk` at `depth` (root units
/// `ijk * 2^-depth`). Cells of the root are in `[0, 2^depth)`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Cell {
    /// Lattice coordinates of the minimum corner.
    pub ijk: [i128; 3],
    /// Depth below the root.
    pub depth: u8,
}

impl Cell {
    /// The root.
    pub const ROOT: Cell = Cell {
        ijk: [0; 3],
        depth: 0,
    };

    /// Child `octant` (bit 0: +x half, bit 1: +y, bit 2: +z).
    #[inline]
    pub fn child(&self, octant: usize) -> Cell {
        Cell {
            ijk: std::array::from_fn(|a| 2 * self.ijk[a] + (octant >> a & 1) as i128),
            depth: self.depth + 1,
        }
    }

    /// The cell at depth `d <= self.depth` that contains this one.
    #[inline]
    pub fn snapped(&self, d: u8) -> Cell {
        Cell {
            ijk: self.ijk.map(|i| i >> (self.depth - d)),
            depth: d,
        }
    }

    /// The same-size cell across face `f`.
    #[inline]
    pub fn across(&self, f: usize) -> Cell {
        let mut ijk = self.ijk;
        ijk[f >> 1] += if f & 1 == 1 { 1 } else { -1 };
        Cell {
            ijk,
            depth: self.depth,
        }
    }

    /// True when the cell lies inside the root.
    pub fn in_root(&self) -> bool {
        self.ijk.iter().all(|&i| i >= 0 && i < 1i128 << self.depth)
    }

    /// Lower and upper face of the cell along `axis`, as lattice coordinates at depth `d >=
    /// self.depth`.
    #[inline]
    pub fn span_at(&self, axis: usize, d: u8) -> (i128, i128) {
        let k = d - self.depth;
        (self.ijk[axis] << k, (self.ijk[axis] + 1) << k)
    }

    /// True when `other` lies inside this cell.
    pub fn encloses(&self, other: &Cell) -> bool {
        other.depth >= self.depth && other.snapped(self.depth) == *self
    }

    /// Octant of this cell's child on the way down to `other` (which it must enclose).
    #[inline]
    pub fn octant_towards(&self, other: &Cell) -> usize {
        let k = other.depth - self.depth - 1;
        (0..3).fold(0, |o, a| o | (((other.ijk[a] >> k) & 1) as usize) << a)
    }
}

/// A box in root units: its minimum corner and depth (side `2^-depth`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BoxU {
    /// Minimum corner.
    pub min: [f64; 3],
    /// Depth below the root.
    pub depth: u8,
}

impl BoxU {
    /// The root box under the default anchor (local coordinates = root units).
    pub const ROOT: BoxU = BoxU {
        min: [0.0; 3],
        depth: 0,
    };

    /// Side length `2^-depth`.
    #[inline(always)]
    pub fn dim(&self) -> f64 {
        dim_at(self.depth)
    }

    /// Box of child `octant` (bit 0: +x half, bit 1: +y, bit 2: +z).
    #[inline(always)]
    pub fn child(&self, octant: usize) -> BoxU {
        let h = dim_at(self.depth + 1);
        let mut min = self.min;
        for (a, m) in min.iter_mut().enumerate() {
            if octant >> a & 1 == 1 {
                *m += h;
            }
        }
        BoxU {
            min,
            depth: self.depth + 1,
        }
    }

    /// The box at depth `d <= self.depth` that contains this one, for lattices that have a corner
    /// at local 0 (depths at or below the anchor's; [`Anchor::snap`](crate::octree::Anchor::snap)
    /// handles the rest).
    #[inline(always)]
    pub fn snapped(&self, d: u8) -> BoxU {
        let s = dim_at(d);
        // Scaling by a power of two is exact, so this equals `(m / s).floor() * s`.
        let inv = f64::from_bits((1023 + d as u64) << 52);
        BoxU {
            min: self.min.map(|m| (m * inv).floor() * s),
            depth: d,
        }
    }

    /// Half-open containment of a point.
    #[inline(always)]
    pub fn contains(&self, p: [f64; 3]) -> bool {
        let s = self.dim();
        (0..3).all(|a| p[a] >= self.min[a] && p[a] < self.min[a] + s)
    }

    /// Octant of the child containing `p` (assumes the box contains `p`).
    #[inline(always)]
    pub fn octant_of(&self, p: [f64; 3]) -> usize {
        let h = dim_at(self.depth + 1);
        let mut o = 0;
        for a in 0..3 {
            if p[a] >= self.min[a] + h {
                o |= 1 << a;
            }
        }
        o
    }

    /// The same-size box across face `f`.
    #[inline(always)]
    pub fn across(&self, f: usize) -> BoxU {
        let a = f >> 1;
        let delta = if f & 1 == 1 { self.dim() } else { -self.dim() };
        let c = |i: usize| {
            if i == a {
                self.min[i] + delta
            } else {
                self.min[i]
            }
        };
        BoxU {
            min: [c(0), c(1), c(2)],
            depth: self.depth,
        }
    }
}

/// Side of a box at depth `d`: `2^-d` (exact).
#[inline(always)]
pub fn dim_at(d: u8) -> f64 {
    f64::from_bits((1023 - d as u64) << 52)
}

/// A ray in root units.
#[derive(Clone, Copy, Debug)]
pub struct Ray {
    /// Origin.
    pub o: [f64; 3],
    /// Unit direction.
    pub d: [f64; 3],
    /// Implicit-LOD factor: a node is below the pixel footprint when `side < t * lod`.
    pub lod: f64,
    /// `1 / d` per axis.
    pub inv: [f64; 3],
}

impl Ray {
    /// A ray from `o` along unit `d` with LOD factor `lod`.
    pub fn new(o: [f64; 3], d: [f64; 3], lod: f64) -> Ray {
        Ray {
            o,
            d,
            lod,
            inv: d.map(|x| 1.0 / x),
        }
    }
}

/// Entry distance into the root (box `root`, local units) and the point just inside it, or
/// `None` when the ray misses. Uses the ray's reciprocal direction (no divisions). Inlined:
/// returned through memory, the point's components written one by one were read back as one
/// wide load by the caller, stalling store forwarding on every ray.
#[inline(always)]
pub(crate) fn enter_root(r: &Ray, root: &BoxU) -> Option<(f64, [f64; 3])> {
    let mut t0 = 0.0f64;
    let mut t1 = f64::INFINITY;
    let mut axis = 3;
    for a in 0..3 {
        let (min, max) = (root.min[a], root.min[a] + 1.0);
        if r.d[a] == 0.0 {
            if r.o[a] < min || r.o[a] >= max {
                return None;
            }
            continue;
        }
        let lo = (min - r.o[a]) * r.inv[a];
        let hi = (max - r.o[a]) * r.inv[a];
        let (n, f) = if r.d[a] > 0.0 { (lo, hi) } else { (hi, lo) };
        if n > t0 {
            t0 = n;
            axis = a;
        }
        t1 = t1.min(f);
    }
    if t0 > t1 {
        return None;
    }
    // Clamp into the root like `exit` does: within an ulp of a root edge, `o + t0 d` can round
    // outside, which would turn a hit on a root face into a miss. The entry face's coordinate
    // is the face itself. Built component by component, as in `exit`: an indexed store into
    // the array, read whole when the result is returned, stalled store forwarding on every
    // ray (with the eye outside the root this function was 16 % of a Menger zoom's run).
    let c = |a: usize| {
        let hi = below(root.min[a] + 1.0);
        if a == axis {
            if r.d[a] > 0.0 { root.min[a] } else { hi }
        } else {
            clamp(r.o[a] + t0 * r.d[a], root.min[a], hi)
        }
    };
    Some((t0, [c(0), c(1), c(2)]))
}

/// `x.next_down()` for the finite box coordinates `exit` uses, without the NaN and infinity
/// checks of the general function: one integer decrement for `x > 0` (local coordinates can
/// be negative: those take the general function).
#[inline(always)]
fn below(x: f64) -> f64 {
    if x > 0.0 {
        f64::from_bits(x.to_bits() - 1)
    } else {
        x.next_down()
    }
}

/// `x.clamp(lo, hi)` without its `lo <= hi` assertion (NaN stays NaN, as with `clamp`).
#[inline(always)]
fn clamp(x: f64, lo: f64, hi: f64) -> f64 {
    let y = if x < lo { lo } else { x };
    if y > hi { hi } else { y }
}

/// Exit distance of the ray from box `b`, the exit face, and the point just across it.
#[inline(always)]
pub(crate) fn exit(r: &Ray, b: &BoxU, t: f64) -> (f64, usize, [f64; 3]) {
    let s = b.dim();
    let mut best = f64::INFINITY;
    let mut axis = 0;
    for a in 0..3 {
        let da = r.d[a];
        if da == 0.0 {
            continue;
        }
        let face = if da > 0.0 { b.min[a] + s } else { b.min[a] };
        // Multiplying by the precomputed reciprocal: both traversals do the same, so their
        // results stay identical.
        let ta = (face - r.o[a]) * r.inv[a];
        if ta < best {
            best = ta;
            axis = a;
        }
    }
    let t = best.max(t);
    let pos = r.d[axis] > 0.0;
    let face = if pos {
        b.min[axis] + s
    } else {
        below(b.min[axis])
    };
    // Built component by component (no indexed store into an array that is then read whole:
    // that stalls store forwarding in this hot loop). The other coordinates are clamped into
    // this box: at an edge the exit distance equals `t`, and `o + t d` rounded can land on the
    // far side of a face the ray already crossed; without the clamp two leaves at an edge sent
    // the ray back and forth until the step guard declared a miss (seen at zoom 1e11).
    let c = |a: usize| {
        if a == axis {
            face
        } else {
            clamp(r.o[a] + t * r.d[a], b.min[a], below(b.min[a] + s))
        }
    };
    let p = [c(0), c(1), c(2)];
    (t, 2 * axis + pos as usize, p)
}
