//! Phase 1 of a frame, the render: the tree read by every thread at once (rays write only
//! atomics that never change what another ray sees: link improvements, visited flags,
//! subdivision requests), wide voxels then drawn smooth.

use super::OctreeView;
use super::anchor::DeepEye;
use super::config::Traversal;
use super::image::{MAX_VOXEL_PX, SvoImage};
use super::pixels::{PixelRow, bands, zeroed};
use super::settling::settling_wide;
use super::tiles::{FineStarts, TileDrawing, TileScratch, refine_tile};
use crate::fill;
use crate::frustum::{StartPath, TileStack, cast_at, walk_root};
use crate::geometry::{BoxU, Ray, dim_at};
use crate::node::pack_rgb;
use crate::octree::Octree;
use crate::ray_grid::RayGrid;
use crate::request_order::Fovea;
use crate::shader::{Origin, View};
use crate::smooth;
use crate::traverse::{Hit, Request, cast_kdrestart, cast_neighbour};
use fathom_core::dd::Dd;
use fathom_core::{Camera, CameraFrame};
use glam::DVec3;
use rayon::prelude::*;

impl OctreeView {
    /// Phase 1: renders the tree as it is (read-only apart from atomics). Returns the image,
    /// the subdivision requests and (rays, hits, node steps).
    pub fn render(&mut self, cam: &Camera) -> (SvoImage, Vec<Request>, [u64; 3]) {
        self.render_deep(cam, &DeepEye::of(cam))
    }

    /// [`OctreeView::render`] for an eye known more precisely than f64 (see [`DeepEye`]).
    pub fn render_deep(
        &mut self,
        cam: &Camera,
        deep: &DeepEye,
    ) -> (SvoImage, Vec<Request>, [u64; 3]) {
        self.render_frame(cam, deep, self.drawing(), false).0
    }

    /// How a frame to be seen is drawn: its wide voxels smooth or blocky, as configured.
    pub(super) fn drawing(&self) -> Drawing {
        if self.cfg.smooth {
            Drawing::Smooth
        } else {
            Drawing::Blocky
        }
    }

    /// Hands an image this view rendered back, so the next render fills its buffers
    /// instead of new ones (optional: a caller done with each frame saves every render the
    /// allocation, see `FrameBuffers`).
    pub fn recycle(&mut self, img: SvoImage) {
        self.buffers.image = Some((img.colour, img.depth));
    }

    /// A frame's setup at a camera: places the anchor, the shader's origin and view, the skip
    /// node (clearing the eye's leaf), the LOD factor and the fovea. Returns the eye relative
    /// to the anchor (root units), the camera's frame and the LOD factor.
    pub(super) fn begin_frame(
        &mut self,
        cam: &Camera,
        deep: &DeepEye,
    ) -> ([f64; 3], CameraFrame, f64) {
        let frame = cam.frame();
        let scale = deep.scale.max(1e-300);
        let eye_u = self.eye_root_units(cam.eye, deep.eye_lo);
        self.place_anchor(&eye_u, scale);
        let origin = self.tree.anchor.origin();
        // The eye relative to the anchor (root units), and the anchor's world position.
        let o: [f64; 3] =
            std::array::from_fn(|a| (eye_u[a] - Dd::new(origin[a].0, origin[a].1)).hi);
        let deep = self.tree.anchor.depth > 0;
        let world: [Dd; 3] = std::array::from_fn(|a| {
            Dd::from(self.tree.root_min[a])
                + Dd::new(origin[a].0, origin[a].1) * Dd::from(self.tree.root_size)
        });
        self.shader.origin = if deep {
            Origin {
                hi: DVec3::new(world[0].hi, world[1].hi, world[2].hi),
                lo: DVec3::new(world[0].lo, world[1].lo, world[2].lo),
                deep: true,
            }
        } else {
            Origin {
                hi: self.tree.root_min,
                lo: DVec3::ZERO,
                deep: false,
            }
        };
        self.shader.view = View {
            eye: self.tree.local_world(o),
            scale,
        };
        self.update_skip(o);
        self.clear_eye(o);
        let (w, h) = (self.cfg.width, self.cfg.height);
        let lod = frame.pixel_angle(h) * self.cfg.fidelity;
        self.lod = lod;
        self.fovea = Fovea {
            eye: o,
            forward: frame.forward,
            tan_half_fov: frame.tan_half_fov,
            aspect: w as f64 / h as f64,
            weight: self.cfg.fovea,
        };
        (o, frame, lod)
    }

    /// The render, its wide voxels drawn as `drawing` says (a probe's image is not
    /// smoothed). When `marking`, it also returns the pixels not yet settled, for the next
    /// [`OctreeView::probe_settling`] (else an empty list).
    pub(super) fn render_frame(
        &mut self,
        cam: &Camera,
        deep: &DeepEye,
        drawing: Drawing,
        marking: bool,
    ) -> ((SvoImage, Vec<Request>, [u64; 3]), Vec<u32>) {
        let (o, frame, lod) = self.begin_frame(cam, deep);
        let (w, h) = (self.cfg.width, self.cfg.height);
        let n = (w * h) as usize;
        let (colour, depth) = self.buffers.image.take().unwrap_or_default();
        let (mut colour, mut depth) = (zeroed(colour, n), zeroed(depth, n));
        // Each pixel's box half-width for `Smoother::smooth` (0: keep the pixel).
        let mut half = zeroed(std::mem::take(&mut self.buffers.half), n);
        let tree = &self.tree;
        let skip = self.skip;
        let trav = self.cfg.traversal;
        let sky = self.sky;
        let size = tree.root_size;
        let pa = frame.pixel_angle(h);
        let grid = RayGrid::new(&frame, w, h);
        let reach = self.reach;
        let beam = self.cfg.beam as usize;
        // Tile starts serve the neighbour traversal; from outside the root, while they pay.
        let tiling = beam > 0 && trav == Traversal::Neighbour;
        let beams = tiling && (skip.is_some() || self.outside_tiles.allows());
        // A hit's voxel is smoothed when its side over its distance reaches this (never when
        // the image is not smoothed: no box widths are worked out).
        let wide = match drawing {
            Drawing::Smooth => smooth::MIN_WIDE_PX * pa,
            Drawing::Blocky | Drawing::Probe => f64::INFINITY,
        };
        // A pixel is marked not yet settled when its voxel's side over its distance reaches
        // this (for a settling loop's next probe, [`OctreeView::probe_settling`]).
        let unsettled = if marking {
            settling_wide(lod)
        } else {
            f64::INFINITY
        };
        // A pixel between lattice rays that met one voxel at least this wide (side over
        // distance) takes their hit ([`crate::fill`]); never in a probe.
        let fill_wide = match drawing {
            Drawing::Smooth | Drawing::Blocky if self.cfg.fill_px > 0.0 => self.cfg.fill_px * pa,
            _ => f64::INFINITY,
        };
        let rule = match drawing {
            Drawing::Smooth => fill::Rule::Blended,
            _ => fill::Rule::Shared,
        };
        let mut marks = zeroed(std::mem::take(&mut self.buffers.marks), n);
        // One pixel: its hit (or sky) into the row, the counts and the largest voxel (as the
        // largest side over distance, compared by cross-multiplying: no division per pixel).
        // Counts: rays cast, their hits, their steps, tile walks' steps, rays from the skip
        // node, pixels filled without a ray (`filled`: [`crate::fill::shared`]).
        let put = |x: usize,
                   d: DVec3,
                   hit: Hit,
                   row: &mut PixelRow,
                   c: &mut [u64; 6],
                   largest: &mut f64,
                   filled: bool| {
            c[0] += u64::from(!filled);
            c[5] += u64::from(filled);
            c[2] += hit.steps as u64;
            if hit.is_hit() {
                c[1] += u64::from(!filled);
                let side = dim_at(hit.depth);
                if side > *largest * hit.t {
                    *largest = side / hit.t;
                }
                if side >= wide * hit.t {
                    row.half[x] = smooth::half_width(side / (hit.t * pa));
                }
                if side >= unsettled * hit.t {
                    row.marks[x] = 1;
                }
                row.colour[x] = hit.colour;
                row.depth[x] = (hit.drawn * size) as f32;
            } else {
                row.colour[x] = sky_colour(&frame, d, sky);
                row.depth[x] = f32::INFINITY;
            }
        };
        let reduce = |(mut ra, ca, la): (Vec<Request>, [u64; 6], f64),
                      (rb, cb, lb): (Vec<Request>, [u64; 6], f64)| {
            ra.extend(rb);
            (ra, std::array::from_fn(|i| ca[i] + cb[i]), la.max(lb))
        };
        let tiles = TileDrawing {
            grid: &grid,
            o,
            lod,
            rule,
            wide: fill_wide,
        };
        let pixels = (
            &mut colour[..],
            &mut depth[..],
            &mut half[..],
            &mut marks[..],
        );
        let (reqs, counts, largest) = self.pool.install(|| {
            if beams {
                // Bands of `beam` rows, each cut into `beam`-wide tiles: a walk of the nodes
                // each tile's frustum meets finds where all its rays can start
                // (`frustum::tile_start`), its quadrants refine that start down to the finest
                // tiles, then each finest tile's rays are cast, each from the tile's start
                // (or from the skip node when its start point is too near a face).
                // The tiles' corner rays, one at a time.
                let ray = |x: usize, y: usize| {
                    let d = grid.dir(x, y);
                    Ray::new(o, [d.x, d.y, d.z], lod)
                };
                // The finest tiles: halve `beam` while it is even and the halves are at least
                // `beam_min` wide (so the finest tiles tile the image on a grid of their side).
                let mut fine = beam;
                while fine.is_multiple_of(2) && fine / 2 >= self.cfg.beam_min as usize {
                    fine /= 2;
                }
                // With the eye outside the root the walks start at the root (no ray stops
                // outside it).
                let from = match skip {
                    Some(skip) => walk_root(tree, skip, o, reach),
                    None => (0, tree.root_box()),
                };
                bands(pixels, w as usize, beam)
                    .enumerate()
                    .map(|(k, mut band)| {
                        let mut reqs = Vec::new();
                        let mut c = [0u64; 6];
                        let mut largest = 0f64;
                        let y0 = k * beam;
                        let y1 = y0 + band.rows() - 1;
                        let mut starts = FineStarts::new(w as usize, y0, y1, fine);
                        let last = (w as usize - 1, y1);
                        let mut stack = TileStack::new();
                        // Where the previous ray started from the eye entered the root.
                        let mut entry = None;
                        for x0 in (0..w as usize).step_by(beam) {
                            let tile = (x0, y0, beam);
                            let n = refine_tile(
                                tree,
                                &ray,
                                tile,
                                last,
                                from,
                                None,
                                &mut starts,
                                &mut stack,
                            );
                            c[2] += n;
                            c[3] += n;
                        }
                        let mut path = StartPath::default();
                        let mut scratch = TileScratch::default();
                        // A finest tile at a time, row by row inside it (or its lattice first,
                        // `crate::fill`): its rays share a start, so each keeps the previous
                        // ray's descent path (`StartPath`); cast row by row across the band,
                        // every `fine`th ray began a fresh descent at a tile boundary.
                        let mut from_skip = 0;
                        for x0 in (0..w as usize).step_by(fine) {
                            tiles.draw(
                                &mut band,
                                (x0, y0, fine),
                                &mut scratch,
                                |x, y, r| {
                                    starts
                                        .at(x, y)
                                        .and_then(|s| cast_at(tree, r, &s, &mut path, &mut reqs))
                                        .unwrap_or_else(|| {
                                            from_skip += 1;
                                            cast_neighbour(tree, r, skip, &mut entry, &mut reqs)
                                        })
                                },
                                |x, d, hit, row, filled| {
                                    put(x, d, hit, row, &mut c, &mut largest, filled)
                                },
                            );
                        }
                        c[4] += from_skip;
                        (reqs, c, largest)
                    })
                    .reduce(|| (Vec::new(), [0u64; 6], 0f64), reduce)
            } else {
                // Without tile starts: bands of rows cast left to right, or, when pixels are
                // filled, cut into tiles of `fill::TILE` pixels.
                let (side, across) = if tiles.fills() {
                    (fill::TILE, fill::TILE)
                } else {
                    (1, w as usize)
                };
                bands(pixels, w as usize, side)
                    .enumerate()
                    .map(|(k, mut band)| {
                        let mut reqs = Vec::new();
                        let mut c = [0u64; 6];
                        let mut largest = 0f64;
                        // Where the previous ray of this band entered the root (eye outside).
                        let mut entry = None;
                        let mut scratch = TileScratch::default();
                        for x0 in (0..w as usize).step_by(across) {
                            tiles.draw(
                                &mut band,
                                (x0, k * side, across),
                                &mut scratch,
                                |_, _, r| cast(tree, r, skip, &mut entry, trav, &mut reqs),
                                |x, d, hit, row, filled| {
                                    put(x, d, hit, row, &mut c, &mut largest, filled)
                                },
                            );
                        }
                        (reqs, c, largest)
                    })
                    .reduce(|| (Vec::new(), [0u64; 6], 0f64), reduce)
            }
        });
        self.beam_steps = counts[3];
        self.rays_from_skip = counts[4];
        self.filled = counts[5];
        if tiling && skip.is_none() {
            // Steps per ray cast, a tile walk's node visits counted twice (a visit tests a box
            // against the tile's frustum, more than a ray's step costs). Per ray, not per
            // pixel: the pixels tiled renders fill (`crate::fill`) cost no steps, and counting
            // them made tiles look cheaper than they are.
            let cost = (counts[2] + counts[3]) as f64 / counts[0].max(1) as f64;
            self.outside_tiles.record(beams, cost);
        }
        self.reach = median_hit(&depth, size);
        let marked = if marking {
            let marked = marks.iter().enumerate().filter(|&(_, &m)| m > 0);
            marked.map(|(i, _)| i as u32).collect()
        } else {
            Vec::new()
        };
        // (Only a smoothed drawing has a finite width: a ray met at distance 0 makes
        // `largest` infinite.)
        if wide.is_finite() && largest >= wide {
            self.pool.install(|| {
                self.smoother
                    .smooth(&mut colour, &half, w as usize, h as usize);
            });
        }
        self.buffers.half = half;
        self.buffers.marks = marks;
        let counts = [counts[0], counts[1], counts[2]];
        let img = SvoImage {
            width: w,
            height: h,
            colour,
            depth,
            largest_voxel_px: (largest / pa).min(MAX_VOXEL_PX),
        };
        ((img, reqs, counts), marked)
    }
}

/// How a frame is drawn: its wide voxels smoothed or as blocks, or only probed for the
/// requests (no image wanted, wide voxels marked).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Drawing {
    Smooth,
    Blocky,
    Probe,
}

/// The median hit distance (root units) of a sample of a frame's pixels (`depth` in world
/// units, infinite for a miss; `size` the root's side), infinite when none hit.
fn median_hit(depth: &[f32], size: f64) -> f64 {
    let mut t: Vec<f32> = depth
        .iter()
        .step_by(61)
        .copied()
        .filter(|d| d.is_finite())
        .collect();
    if t.is_empty() {
        return f64::INFINITY;
    }
    let k = t.len() / 2;
    let (_, m, _) = t.select_nth_unstable_by(k, f32::total_cmp);
    *m as f64 / size
}

pub(super) fn cast(
    tree: &Octree,
    ray: &Ray,
    skip: Option<(u32, BoxU)>,
    entry: &mut Option<(u32, BoxU)>,
    trav: Traversal,
    reqs: &mut Vec<Request>,
) -> Hit {
    match trav {
        Traversal::Neighbour => cast_neighbour(tree, ray, skip, entry, reqs),
        Traversal::KdRestart => cast_kdrestart(tree, ray, skip.is_some(), reqs),
    }
}

/// The sphere tracer's sky (`fathom_trace::shade::Shading::sky`): a gradient on the square
/// root of the direction's height, so octree and tracer frames agree off the surface.
fn sky_colour(frame: &CameraFrame, d: DVec3, sky: ([f64; 3], [f64; 3])) -> u32 {
    let k = d.y.clamp(0.0, 1.0).sqrt();
    let _ = frame;
    pack_rgb(std::array::from_fn(|i| {
        sky.0[i] + (sky.1[i] - sky.0[i]) * k
    }))
}

#[cfg(test)]
mod frame_buffers_tests {
    use super::*;
    use crate::octree_view::OctreeViewConfig;

    #[test]
    fn a_render_into_reused_buffers_draws_what_fresh_buffers_draw() {
        // Every pixel cast: from outside the root the second render goes without tiles to
        // compare their cost, and only tiled renders fill pixels.
        let cfg = OctreeViewConfig {
            width: 96,
            height: 72,
            threads: 2,
            fill_px: 0.0,
            ..OctreeViewConfig::default()
        };
        let mut ex = OctreeView::new(&fathom_core::scenes::menger(8), cfg).unwrap();
        let cam = Camera {
            eye: DVec3::new(1.9, 1.7, 1.5),
            target: DVec3::new(0.6, 0.5, 0.4),
            up: DVec3::Y,
            fov: 50.0,
        };
        // Few frames settled: voxels wide enough to be smoothed, so every buffer is used.
        ex.settle(&cam, 3);
        let render = |ex: &mut OctreeView| {
            let ((img, reqs, _), marked) =
                ex.render_frame(&cam, &DeepEye::of(&cam), Drawing::Smooth, true);
            ex.release_requests(&reqs);
            (img, marked)
        };
        let (fresh, marked) = render(&mut ex);
        assert!(fresh.largest_voxel_px >= 2.0, "{}", fresh.largest_voxel_px);
        assert!(
            !marked.is_empty() && marked.len() < 96 * 72,
            "{}",
            marked.len()
        );
        // Buffers full of what no render leaves: each must be cleared or overwritten.
        let n = 96 * 72;
        ex.buffers.half = vec![200; n];
        ex.buffers.marks = vec![1; n];
        ex.recycle(SvoImage {
            width: 96,
            height: 72,
            colour: vec![0x1234_5678; n],
            depth: vec![-1.0; n],
            largest_voxel_px: 0.0,
        });
        let (reused, marked_again) = render(&mut ex);
        assert!(
            reused == fresh,
            "a render into reused buffers differs from a fresh one"
        );
        assert_eq!(marked_again, marked);
    }
}

#[cfg(test)]
mod fill_tests {
    use super::*;
    use crate::octree_view::OctreeViewConfig;
    use crate::octree_view::outside_tiles::OutsideTiles;

    fn menger_view() -> (OctreeView, Camera) {
        let cfg = OctreeViewConfig {
            width: 128,
            height: 96,
            threads: 2,
            ..OctreeViewConfig::default()
        };
        let ex = OctreeView::new(&fathom_core::scenes::menger(8), cfg).unwrap();
        let cam = Camera {
            eye: DVec3::new(1.9, 1.7, 1.5),
            target: DVec3::new(0.6, 0.5, 0.4),
            up: DVec3::Y,
            fov: 50.0,
        };
        (ex, cam)
    }

    /// The frame drawn as `drawing` with `fill_px`, with tile starts or without (`tiled`),
    /// and the pixels filled without a ray.
    fn render(
        ex: &mut OctreeView,
        cam: &Camera,
        drawing: Drawing,
        fill_px: f64,
        tiled: bool,
    ) -> (SvoImage, u64) {
        ex.cfg.fill_px = fill_px;
        // From outside the root (as here) renders may alternate to compare: fix the choice.
        ex.outside_tiles = OutsideTiles {
            from: if tiled { 0 } else { u64::MAX },
            ..OutsideTiles::default()
        };
        let ((img, reqs, counts), _) = ex.render_frame(cam, &DeepEye::of(cam), drawing, false);
        ex.release_requests(&reqs);
        assert_eq!(
            counts[0] + ex.filled,
            128 * 96,
            "every pixel cast or filled"
        );
        assert_eq!(ex.beam_steps > 0, tiled, "tile starts used");
        (img, ex.filled)
    }

    #[test]
    fn filled_pixels_show_what_their_rays_would() {
        let (mut ex, cam) = menger_view();
        // Five frames settled: voxels up to ~10 pixels wide, most narrower than 4.
        ex.settle(&cam, 5);
        let n = 128 * 96;
        let mut filled_at = Vec::new();
        // With tile starts and without (their lattices' tiles differ in general: the finest
        // tiles, or `fill::TILE` squares), filling from voxels at least 4 pixels wide or 2.
        for (tiled, px) in [(true, 4.0), (false, 4.0), (true, 2.0), (false, 2.0)] {
            // Drawn as blocks, a filled pixel takes the voxel its lattice rays all met: the
            // same colour and nearly the same depth as its own ray, but for what stands in
            // front of that voxel between rays two pixels apart (here 1 pixel of 12288 at 4
            // pixels, 8 at 2).
            let (cast, none) = render(&mut ex, &cam, Drawing::Blocky, 0.0, tiled);
            let (filled, count) = render(&mut ex, &cam, Drawing::Blocky, px, tiled);
            assert_eq!(none, 0);
            assert!(count as usize > n / 25, "{count} of {n} pixels filled");
            filled_at.push(count);
            let differ = (0..n)
                .filter(|&i| cast.colour[i] != filled.colour[i])
                .count();
            assert!(differ <= n / 200, "{differ} of {n} pixels differ");
            let far = (0..n)
                .filter(|&i| (cast.depth[i] - filled.depth[i]).abs() > 0.05 * cast.depth[i])
                .count();
            assert!(far <= n / 200, "{far} of {n} pixels have depths 5 % apart");
            // Drawn smooth, neighbouring wide voxels of one surface blend too: more pixels
            // are filled (1438 here at 4 pixels, 2992 at 2) and the smoothed frame changes by
            // a third of a level in 255 (a level at 2 pixels).
            let (cast, _) = render(&mut ex, &cam, Drawing::Smooth, 0.0, tiled);
            let (filled, more) = render(&mut ex, &cam, Drawing::Smooth, px, tiled);
            assert!(more > count, "{more} filled smooth, {count} as blocks");
            let error = (0..n)
                .map(|i| {
                    let (a, b) = (cast.colour[i].to_le_bytes(), filled.colour[i].to_le_bytes());
                    (0..3).map(|c| a[c].abs_diff(b[c]) as f64).sum::<f64>() / 3.0
                })
                .sum::<f64>()
                / n as f64;
            assert!(error < 2.0, "{px} px: mean error {error} levels of 255");
        }
        // Voxels 2 to 4 pixels wide fill too at 2 (510 pixels at 4, 854 at 2).
        assert!(filled_at[2] > filled_at[0], "{filled_at:?}");
    }

    #[test]
    fn a_settled_frame_casts_every_pixel() {
        let (mut ex, cam) = menger_view();
        ex.settle(&cam, 400);
        for tiled in [true, false] {
            let (cast, _) = render(&mut ex, &cam, Drawing::Smooth, 0.0, tiled);
            let px = fill::DEFAULT_FILL_PX;
            let (filled, count) = render(&mut ex, &cam, Drawing::Smooth, px, tiled);
            assert!(cast.largest_voxel_px < px, "{}", cast.largest_voxel_px);
            assert_eq!(count, 0);
            assert!(filled == cast);
        }
    }
}
