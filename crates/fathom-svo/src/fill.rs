//! Pixels filled from the rays around them where the octree's voxels are wide.
//!
//! A zoom shows voxels 4 to 16 pixels wide almost all the way (detail arrives a few hundred
//! subdivisions a frame; the 1000-frame Mandelbulb zoom to 1e15 had 80-95 % of its hit pixels
//! on voxels at least 4 pixels wide), yet the render cast one ray per pixel, each walking the
//! octree to meet the same voxel as its neighbours: the walks were three quarters of the
//! frame. A tile's rays are therefore cast on a lattice first (every other pixel of every other
//! row, and the tile's last row and column); a pixel between two (on a lattice row or column)
//! or four lattice rays that all stopped on the same voxel, at least [`OctreeViewConfig::fill_px`]
//! pixels wide at each, takes that voxel's colour and the lattice rays' mean distance without
//! a ray of its own. Any other pixel casts its ray. Renders with tile starts take their finest
//! tiles as the lattice's tiles; renders without them (the eye outside the root while tile
//! starts do not pay, or the kd-restart traversal) cut the frame into [`TILE`]-pixel squares.
//!
//! In frames drawn smooth the rule is wider ([`blended`]): lattice rays that met different
//! voxels, all that wide and at distances no further apart than the smallest one's side (one
//! surface, not an edge), give the pixels between them their mean colour and distances. The
//! smoothing that follows averages those pixels over boxes about as wide as their voxels (at
//! least three pixels across), so it blends the colours of neighbouring voxels anyway.
//!
//! What a filled pixel shows is what its ray would have met unless something smaller than the
//! lattice's two-pixel spacing stands in front of that voxel: the part of a voxel a ray stops
//! on (its cube, or the cube cut by its surface plane) is convex, so its outline on screen is
//! convex and holds every pixel between rays that met it; the colour is the voxel's, the same
//! for every ray that stops on it. Frames whose voxels are narrower than `fill_px` (settled
//! frames) cast every pixel and are unchanged, and so are probes (their requests and marks
//! must be every pixel's). The lattice ray that met a voxel asked for its split, as the
//! pixels filled from it would have.
//!
//! [`OctreeViewConfig::fill_px`]: crate::octree_view::OctreeViewConfig::fill_px

use crate::geometry::dim_at;
use crate::node::NONE;
use crate::traverse::Hit;

/// Default [`crate::octree_view::OctreeViewConfig::fill_px`]: pixels between lattice rays (two
/// pixels apart) are filled when the voxels they met are at least that wide. At 2 zooms look
/// as they do at 4 or with every pixel cast, and run faster (`docs/log/svo.md`).
pub const DEFAULT_FILL_PX: f64 = 2.0;

/// Side of the square tiles a render without tile starts casts its lattices in (renders with
/// tile starts use their finest tiles, [`crate::octree_view::DEFAULT_BEAM_MIN`] by default).
pub const TILE: usize = 16;

/// Lattice points in a run of `n` pixels (`n` >= 1): offsets 0, 2, 4, ... and the last.
#[inline(always)]
pub fn lattice_len(n: usize) -> usize {
    n / 2 + n % 2 + usize::from(n > 1 && n.is_multiple_of(2))
}

/// The lattice index of offset `i` in a run of `n` pixels, or `None` when `i` lies between two
/// lattice points (`i - 1` and `i + 1`, indices `i / 2` and `i / 2 + 1`).
#[inline(always)]
pub fn lattice_index(n: usize, i: usize) -> Option<usize> {
    if i.is_multiple_of(2) {
        Some(i / 2)
    } else if i + 1 == n {
        Some(i / 2 + 1)
    } else {
        None
    }
}

/// The offset of lattice point `k` in a run of `n` pixels.
#[inline(always)]
pub fn lattice_offset(n: usize, k: usize) -> usize {
    (2 * k).min(n - 1)
}

/// The hit a pixel between the lattice rays `hits` takes: when they all stopped on one voxel
/// whose side is at least `wide` times each one's distance (side over distance: its angular
/// width), that voxel with the rays' mean distances (met and drawn) and no steps of its own;
/// else `None`.
#[inline(always)]
pub fn shared(hits: &[Hit], wide: f64) -> Option<Hit> {
    let first = hits[0];
    if first.node == NONE {
        return None;
    }
    let side = dim_at(first.depth);
    let (mut t, mut drawn) = (0.0, 0.0);
    for h in hits {
        if h.node != first.node || side < wide * h.t {
            return None;
        }
        t += h.t;
        drawn += h.drawn;
    }
    let n = hits.len() as f64;
    Some(Hit {
        t: t / n,
        drawn: drawn / n,
        steps: 0,
        ..first
    })
}

/// The hit a pixel between the lattice rays `hits` (two or four) takes in a frame drawn
/// smooth: when each stopped on a voxel whose side is at least `wide` times its distance, and
/// their distances differ by no more than the smallest of those voxels' sides (one surface,
/// not an edge in front of another), their mean colour and distances, with the smallest voxel's
/// depth (so the pixel is smoothed no wider than its narrowest neighbour); else `None`. Over
/// pixels of voxels this wide the smoothing filter averages boxes at least five pixels across
/// ([`crate::smooth`]), so the colours of voxels next to each other are blended anyway.
#[inline(always)]
pub fn blended(hits: &[Hit], wide: f64) -> Option<Hit> {
    let mut sums = [0u32; 4];
    let (mut t, mut drawn, mut t_min, mut t_max, mut depth) = (0.0, 0.0, f64::INFINITY, 0f64, 0u8);
    for h in hits {
        if h.node == NONE || dim_at(h.depth) < wide * h.t {
            return None;
        }
        for (s, b) in sums.iter_mut().zip(h.colour.to_le_bytes()) {
            *s += u32::from(b);
        }
        t += h.t;
        drawn += h.drawn;
        t_min = t_min.min(h.t);
        t_max = t_max.max(h.t);
        depth = depth.max(h.depth);
    }
    if t_max - t_min > dim_at(depth) {
        return None;
    }
    let n = hits.len() as u32;
    let colour = u32::from_le_bytes(sums.map(|s| ((s + n / 2) / n) as u8));
    Some(Hit {
        t: t / n as f64,
        drawn: drawn / n as f64,
        colour,
        node: hits[0].node,
        steps: 0,
        depth,
    })
}

/// Which rule fills a pixel: [`shared`] (frames drawn as blocks) or [`blended`] (smooth).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Rule {
    /// One voxel met by every lattice ray around the pixel.
    Shared,
    /// Wide voxels of one surface, their colours averaged.
    Blended,
}

impl Rule {
    /// The hit a pixel between the lattice rays `hits` takes, if any (see [`shared`] and
    /// [`blended`]).
    #[inline(always)]
    pub fn fill(self, hits: &[Hit], wide: f64) -> Option<Hit> {
        match self {
            Rule::Shared => shared(hits, wide),
            Rule::Blended => blended(hits, wide),
        }
    }
}

/// The order a tile's `rows` rows are visited in: the lattice rows first (every other row
/// and the last), then the rows between them (each needs the lattice rows on both sides).
pub fn row_order(rows: usize) -> impl Iterator<Item = usize> {
    let lattice = (0..rows).filter(move |&j| lattice_index(rows, j).is_some());
    lattice.chain((1..rows).step_by(2).filter(move |&j| j + 1 < rows))
}

/// One visit of a tile's row of `n` pixels, `nx` lattice points a row, in the order a row is
/// visited: on a lattice row (index `ky`, its hits to be stored at `lattice[ky * nx..]`) the
/// lattice points first, then the pixels between them; on a row between lattice rows `ky`
/// and `ky + 1`, left to right. Returns the pixel's offset in the row and, for a pixel that
/// is not a lattice point, the hit `rule` fills it with from `lattice`'s hits around it.
#[inline(always)]
#[allow(clippy::too_many_arguments)]
pub fn visit(
    lattice: &[Hit],
    n: usize,
    nx: usize,
    on_lattice: bool,
    ky: usize,
    step: usize,
    rule: Rule,
    wide: f64,
) -> (usize, Option<Hit>) {
    if on_lattice {
        if step < nx {
            return (lattice_offset(n, step), None);
        }
        let i = 2 * (step - nx) + 1;
        let k = ky * nx + i / 2;
        return (i, rule.fill(&lattice[k..k + 2], wide));
    }
    let (up, down) = (ky * nx, (ky + 1) * nx);
    let hit = match lattice_index(n, step) {
        Some(k) => rule.fill(&[lattice[up + k], lattice[down + k]], wide),
        None => {
            let (a, b) = (up + step / 2, down + step / 2);
            let four = [lattice[a], lattice[a + 1], lattice[b], lattice[b + 1]];
            rule.fill(&four, wide)
        }
    };
    (step, hit)
}

/// Visits each pixel of a tile `n` pixels wide and `rows` high once, the lattice points
/// before the pixels between them ([`row_order`], [`visit`]): `pixel(j, i, filled)` gets the
/// pixel's row and offset in the tile and the hit `rule` fills it with, if any, and returns
/// the pixel's hit (`filled`'s, or its ray's); lattice points' hits are kept in `lattice` for
/// the pixels between them.
#[inline(always)]
pub fn tile(
    lattice: &mut Vec<Hit>,
    n: usize,
    rows: usize,
    rule: Rule,
    wide: f64,
    mut pixel: impl FnMut(usize, usize, Option<Hit>) -> Hit,
) {
    let nx = lattice_len(n);
    lattice.clear();
    lattice.resize(nx * lattice_len(rows), Hit::miss(0));
    for j in row_order(rows) {
        let on_lattice = lattice_index(rows, j);
        let on = on_lattice.is_some();
        // A row between lattice rows sits between rows `j / 2` and `j / 2 + 1`.
        let ky = on_lattice.unwrap_or(j / 2);
        for step in 0..n {
            let (i, filled) = visit(lattice, n, nx, on, ky, step, rule, wide);
            let hit = pixel(j, i, filled);
            if on && step < nx {
                lattice[ky * nx + step] = hit;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_tile_visits_each_pixel_once_after_the_lattice_points_around_it() {
        for (n, rows) in [(16, 16), (16, 5), (7, 1), (1, 4), (2, 2), (9, 3)] {
            let nx = lattice_len(n);
            let ny = lattice_len(rows);
            // Each lattice slot holds a distinct voxel, so nothing is filled; record the
            // order of visits instead.
            let mut seen = vec![false; n * rows];
            let mut cast = vec![false; nx * ny];
            for j in row_order(rows) {
                let on = lattice_index(rows, j);
                let ky = on.unwrap_or(j / 2);
                if on.is_none() {
                    assert!(cast[ky * nx..(ky + 2) * nx].iter().all(|&c| c), "row {j}");
                }
                for step in 0..n {
                    let lattice = vec![hit(1, 4, 1.0); nx * ny];
                    let (i, fill) =
                        visit(&lattice, n, nx, on.is_some(), ky, step, Rule::Shared, 0.0);
                    assert!(!seen[j * n + i], "({i}, {j}) twice");
                    seen[j * n + i] = true;
                    let point = on.is_some() && lattice_index(n, i).is_some();
                    assert_eq!(fill.is_none(), point, "({i}, {j}) of {n} x {rows}");
                    if point {
                        assert_eq!(step, lattice_index(n, i).unwrap(), "lattice first");
                        cast[ky * nx + step] = true;
                    }
                }
            }
            assert!(seen.iter().all(|&s| s), "{n} x {rows}: a pixel not visited");
        }
    }

    #[test]
    fn a_tile_casts_its_lattice_and_fills_between_rays_on_one_wide_voxel() {
        let mut lattice = Vec::new();
        for (n, rows) in [(16, 16), (16, 5), (7, 1), (1, 4), (9, 3)] {
            // Every ray meets voxel 1 (wide) but the lattice ray of pixel (4, 2), which meets
            // voxel 2: the pixels next to it (between it and other lattice rays) cast theirs.
            let odd = (4, 2);
            let mut cast = vec![0u8; n * rows];
            tile(&mut lattice, n, rows, Rule::Shared, 0.01, |j, i, filled| {
                let own = if (i, j) == odd { 2 } else { 1 };
                if filled.is_none() {
                    cast[j * n + i] += 1;
                    return hit(own, 4, 1.0);
                }
                assert_eq!(filled.unwrap().node, own, "({i}, {j}) of {n} x {rows}");
                filled.unwrap()
            });
            for j in 0..rows {
                for i in 0..n {
                    let point = lattice_index(n, i).is_some() && lattice_index(rows, j).is_some();
                    let near = i.abs_diff(odd.0) <= 1 && j.abs_diff(odd.1) <= 1;
                    let want = u8::from(point || (near && n > odd.0 && rows > odd.1));
                    assert_eq!(cast[j * n + i], want, "({i}, {j}) of {n} x {rows}");
                }
            }
        }
    }

    #[test]
    fn the_lattice_is_every_other_pixel_and_the_last() {
        for n in 1..40 {
            let points: Vec<usize> = (0..lattice_len(n)).map(|k| lattice_offset(n, k)).collect();
            let mut want: Vec<usize> = (0..n).step_by(2).collect();
            if want.last() != Some(&(n - 1)) {
                want.push(n - 1);
            }
            assert_eq!(points, want, "n = {n}");
            for i in 0..n {
                match lattice_index(n, i) {
                    Some(k) => assert_eq!(points[k], i, "n = {n}, i = {i}"),
                    None => {
                        let k = i / 2;
                        assert_eq!((points[k], points[k + 1]), (i - 1, i + 1), "n = {n}");
                    }
                }
            }
        }
    }

    fn hit(node: u32, depth: u8, t: f64) -> Hit {
        Hit {
            t,
            drawn: t,
            colour: 0xff336699,
            node,
            steps: 7,
            depth,
        }
    }

    #[test]
    fn a_pixel_is_filled_only_between_rays_on_one_wide_voxel() {
        // Depth 4: side 1/16 root units; at distance 1 that is 0.0625 radians.
        let wide = 0.05;
        let h = shared(&[hit(9, 4, 1.0), hit(9, 4, 1.2)], wide).unwrap();
        assert_eq!((h.node, h.colour, h.depth, h.steps), (9, 0xff336699, 4, 0));
        assert!((h.t - 1.1).abs() < 1e-12);
        // Drawn at the mean of where the rays reached the voxel's plane, sized by where
        // they met it.
        let far = |t: f64, drawn: f64| Hit {
            drawn,
            ..hit(9, 4, t)
        };
        let h = shared(&[far(1.0, 1.1), far(1.2, 1.5)], wide).unwrap();
        assert!((h.t - 1.1).abs() < 1e-12 && (h.drawn - 1.3).abs() < 1e-12);
        let h = blended(&[far(1.0, 1.1), far(1.02, 1.5)], wide).unwrap();
        assert!((h.t - 1.01).abs() < 1e-12 && (h.drawn - 1.3).abs() < 1e-12);
        // Another voxel, a miss, or one ray too far for the voxel to be wide: cast.
        assert!(shared(&[hit(9, 4, 1.0), hit(10, 4, 1.0)], wide).is_none());
        assert!(
            shared(
                &[Hit {
                    t: f64::INFINITY,
                    ..hit(NONE, 0, 1.0)
                }; 2],
                wide
            )
            .is_none()
        );
        assert!(shared(&[hit(9, 4, 1.0), hit(9, 4, 1.3)], wide).is_none());
        let four = [
            hit(3, 4, 1.0),
            hit(3, 4, 1.0),
            hit(3, 4, 1.0),
            hit(4, 4, 1.0),
        ];
        assert!(shared(&four, wide).is_none());
        assert!(shared(&four[..3], wide).is_some());
    }

    #[test]
    fn a_smooth_frame_blends_wide_voxels_of_one_surface_only() {
        let wide = 0.05;
        let a = Hit {
            colour: 0xff000010,
            ..hit(1, 4, 1.0)
        };
        let b = Hit {
            colour: 0xff0000f0,
            ..hit(2, 4, 1.04)
        };
        let h = blended(&[a, b], wide).unwrap();
        assert_eq!((h.colour, h.depth, h.steps), (0xff000080, 4, 0));
        assert!((h.t - 1.02).abs() < 1e-12);
        // The smaller voxel sets the depth; distances further apart than its side (1/32) are
        // two surfaces, one in front of the other.
        let c = hit(3, 5, 1.02);
        assert_eq!(blended(&[a, c], 0.03).unwrap().depth, 5);
        assert!(blended(&[a, Hit { t: 1.04, ..c }], 0.03).is_none());
        // A narrow voxel or a miss among them: cast.
        assert!(blended(&[a, c], wide).is_none());
        assert!(
            blended(
                &[
                    a,
                    Hit {
                        t: f64::INFINITY,
                        ..hit(NONE, 0, 1.0)
                    }
                ],
                wide
            )
            .is_none()
        );
    }
}
