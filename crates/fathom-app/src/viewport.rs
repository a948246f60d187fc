//! The viewport's frame scheduling: which frame to ask the worker for next, and which to show.
//!
//! While the view moves (camera, scene or settings: its *key* changes), frames render at the
//! dynamic scale ([`crate::scale::RenderScale`]) and the newest view is asked for as soon as
//! the previous frame is back, so the screen follows at about the target frame time. When the
//! view holds still, the frame is refined: full resolution, then supersampled. A refinement
//! that goes stale (the view moved again) is cancelled at once; an interactive frame is let
//! finish (it is short) unless it has run past twice the target. Octree frames step the tree
//! instead, at full resolution (the octree holds its frame time by its subdivision budget),
//! until it asks for no more subdivision; their subdivision takes what the render leaves of
//! the target frame time. Once such a view has held still for [`OCTREE_STILL_DELAY_MS`],
//! its steps subdivide for [`Viewport::octree_still_budget`] target frame times each, going
//! on past their render's requests to the pixels it left unsettled: nothing on screen moves,
//! so detail matters more than the frame rate, and a moving view's budget (a tenth of a
//! frame) took minutes to settle a Mandelbulb. Those steps are cancelled as soon as the view
//! moves again, and their subdivision stops at its next batch.
//!
//! A path-traced view ([`Backend::Path`]) shows the preview tracer while it moves; once the
//! view is still, each job adds samples to the session's accumulator for
//! [`PATH_JOB_FRAMES`] target frame times (one pass at least) and shows the image so far,
//! until the request's samples per pixel are reached. Moving or editing starts over.
//!
//! A GPU frame cannot be cancelled once submitted, so on the GPU the first refinement waits
//! until the view has held still for [`GPU_REFINE_DELAY_MS`]: a slider dragged slowly (or a
//! camera nudged key by key) would otherwise start a full-resolution frame between two of its
//! steps and the next step would wait for it. The CPU tracer's refinements start at once (they
//! stop at the next tile when the view moves).

use crate::scale::RenderScale;
use crate::worker::{FrameDone, FrameFailure, FrameJob, Picture, Stage, Worker};
use fathom_core::Camera;
use fathom_render::{Backend, CancelToken, RenderRequest, Stats};
use std::hash::{Hash, Hasher};
use std::time::Instant;

/// How long the view must hold still before the GPU starts refining it, ms.
pub const GPU_REFINE_DELAY_MS: f64 = 150.0;

/// How long an octree view must hold still before its steps take the still budget, ms (a
/// camera nudged key by key, or a slider dragged slowly, keeps the moving budget).
pub const OCTREE_STILL_DELAY_MS: f64 = 150.0;

/// A still octree view's subdivision per step, in target frame times
/// ([`Viewport::octree_still_budget`]'s default): at a 33 ms target, about 130 ms of splits
/// after each render, so the picture refines several times a second while most of the time
/// goes to detail.
pub const OCTREE_STILL_BUDGET: f64 = 4.0;

/// A still path-traced view's job: samples for this many target frame times.
pub const PATH_JOB_FRAMES: f64 = 8.0;

/// A still path-traced view's job takes samples for at least this long, ms.
pub const PATH_JOB_MIN_MS: f64 = 250.0;

/// A frame being rendered.
struct InFlight {
    id: u64,
    key: u64,
    stage: Stage,
    cancel: CancelToken,
    sent: Instant,
    progress: std::sync::Arc<std::sync::atomic::AtomicU64>,
}

/// The frame on screen.
pub struct Shown {
    /// The view it is of ([`view_key`]).
    pub key: u64,
    /// Its refinement stage.
    pub stage: Stage,
    /// Its pixel size and the request it was rendered with.
    pub request: RenderRequest,
    /// What it cost.
    pub stats: Stats,
    /// The scene generation it shows.
    pub generation: u64,
    /// Render time of the frame, ms.
    pub ms: f64,
    /// Octree subdivisions still asked for, for stepped octree frames.
    pub octree_requests: Option<u64>,
    /// The fraction of the viewport's resolution it was rendered at (1: full resolution).
    pub scale: f64,
}

/// Frame scheduling and the texture on screen.
pub struct Viewport {
    /// The dynamic resolution scale that holds the target frame time.
    pub scale: RenderScale,
    /// Supersampling of the last refinement (1: stop at full resolution).
    pub refine_supersample: u32,
    /// A still octree view's subdivision time per step, in target frame times (0: the moving
    /// view's budget, a frame rate held while nothing moves).
    pub octree_still_budget: f64,
    in_flight: Option<InFlight>,
    /// The frame on screen, if any.
    pub shown: Option<Shown>,
    /// The frame on screen as an egui texture.
    pub texture: Option<egui::TextureHandle>,
    next_id: u64,
    /// When the view key last changed (the view has held still since).
    pub still_since: Option<Instant>,
    /// From the view holding still to its first full-resolution frame, ms.
    pub full_after_still_ms: Option<f64>,
    /// The last error a frame reported.
    pub error: Option<String>,
    /// The key whose stillness `still_since` times.
    still_key: Option<u64>,
    /// A view whose frame was lost with its worker: not asked for again until the view changes.
    failed_key: Option<u64>,
}

/// The view a frame is of: everything that changes its pixels.
pub fn view_key(camera: &Camera, generation: u64, request: &RenderRequest) -> u64 {
    let mut h = std::collections::hash_map::DefaultHasher::new();
    format!("{camera:?}").hash(&mut h);
    generation.hash(&mut h);
    // The size and supersampling are chosen per frame; the rest of the request is the view.
    let r = RenderRequest {
        width: 0,
        height: 0,
        supersample: 1,
        ..request.clone()
    };
    serde_json::to_string(&r).unwrap_or_default().hash(&mut h);
    h.finish()
}

impl Viewport {
    /// A viewport holding `target_ms` per frame while moving, nothing on screen yet.
    pub fn new(target_ms: f64) -> Viewport {
        Viewport {
            scale: RenderScale::new(target_ms),
            refine_supersample: 2,
            octree_still_budget: OCTREE_STILL_BUDGET,
            in_flight: None,
            shown: None,
            texture: None,
            next_id: 0,
            still_since: None,
            full_after_still_ms: None,
            error: None,
            still_key: None,
            failed_key: None,
        }
    }

    /// Whether the frame on screen is the final refinement of `key` (nothing more to do).
    pub fn settled(&self, key: u64) -> bool {
        self.in_flight.is_none()
            && self.shown.as_ref().is_some_and(|s| {
                s.key == key
                    && match (s.octree_requests, s.stats.path) {
                        (Some(r), _) => r == 0,
                        (None, Some(p)) => p.samples_per_pixel >= s.request.path.spp,
                        (None, None) => s.stage == self.last_stage(),
                    }
            })
    }

    fn last_stage(&self) -> Stage {
        if self.refine_supersample > 1 {
            Stage::Supersampled
        } else {
            Stage::Full
        }
    }

    /// Takes a finished frame: shows it if it is the one asked for. Returns its picture's
    /// image to upload, if shown.
    pub fn accept(&mut self, done: FrameDone) -> Option<egui::ColorImage> {
        let current = self.in_flight.as_ref().is_some_and(|f| f.id == done.id);
        if current {
            self.in_flight = None;
        }
        match done.result {
            Ok(Picture { image, stats }) => {
                if done.stage == Stage::Interactive && done.request.backend != Backend::Octree {
                    self.scale.update(done.scale, done.ms);
                }
                // (Octree frames are at full resolution from the first; their still steps
                // are marked full only to be cancelled at once.)
                if done.stage >= Stage::Full
                    && done.request.backend != Backend::Octree
                    && self.full_after_still_ms.is_none()
                    && let Some(t) = self.still_since
                {
                    self.full_after_still_ms = Some(t.elapsed().as_secs_f64() * 1e3);
                }
                self.error = None;
                self.shown = Some(Shown {
                    key: done.key,
                    stage: done.stage,
                    request: done.request,
                    stats,
                    generation: done.generation,
                    ms: done.ms,
                    octree_requests: done.octree_requests,
                    scale: done.scale,
                });
                Some(image)
            }
            Err(FrameFailure::Cancelled) => None,
            Err(FrameFailure::Error(e)) => {
                self.error = Some(e);
                // Do not retry the same view in a loop: mark it shown at its final stage.
                if let Some(s) = &mut self.shown {
                    s.key = done.key;
                    s.stage = Stage::Supersampled;
                    s.octree_requests = Some(0);
                }
                None
            }
        }
    }

    /// Decides the next job for the view `key` of `camera` in a `w` x `h` viewport with the
    /// settings of `base` (whose size is ignored), and sends it. Call once per window frame.
    pub fn schedule(
        &mut self,
        worker: &Worker,
        key: u64,
        camera: &Camera,
        base: &RenderRequest,
        (w, h): (u32, u32),
    ) {
        if w == 0 || h == 0 {
            return; // minimised or collapsed: nothing to draw
        }
        if self.failed_key == Some(key) {
            return;
        }
        self.failed_key = None;
        if self.shown.as_ref().is_none_or(|s| s.key != key)
            && self.in_flight.as_ref().is_none_or(|f| f.key != key)
        {
            // The view changed: restart the clock of "time to full resolution".
            if self.still_key != Some(key) {
                self.still_key = Some(key);
                self.still_since = Some(Instant::now());
                self.full_after_still_ms = None;
            }
        }
        if let Some(f) = &self.in_flight {
            let stale = f.key != key;
            let overdue = f.sent.elapsed().as_secs_f64() * 1e3 > 2.0 * self.scale.target_ms();
            if stale && (f.stage != Stage::Interactive || overdue) {
                f.cancel.cancel();
                self.in_flight = None;
            } else {
                return;
            }
        }
        let octree = base.backend == Backend::Octree;
        let path = base.backend == Backend::Path;
        let still_ms = self
            .still_since
            .map_or(f64::INFINITY, |t| t.elapsed().as_secs_f64() * 1e3);
        let stage = match &self.shown {
            Some(s) if s.key == key => {
                if octree {
                    if s.octree_requests == Some(0) {
                        return;
                    }
                    // A still view's step: the long budget, cancelled when the view moves.
                    if self.octree_still_budget > 0.0 && still_ms >= OCTREE_STILL_DELAY_MS {
                        Stage::Full
                    } else {
                        Stage::Interactive
                    }
                } else if path {
                    // Accumulate while still: each job adds samples for a while.
                    if s.stats
                        .path
                        .is_some_and(|p| p.samples_per_pixel >= base.path.spp)
                    {
                        return;
                    }
                    Stage::Full
                } else if s.stage == Stage::Interactive {
                    if base.backend == Backend::Gpu && still_ms < GPU_REFINE_DELAY_MS {
                        return;
                    }
                    Stage::Full
                } else if s.stage == Stage::Full && self.refine_supersample > 1 {
                    Stage::Supersampled
                } else {
                    return;
                }
            }
            _ => Stage::Interactive,
        };
        let (fw, fh, ss, scale) = match stage {
            _ if octree => (w, h, 1, 1.0),
            Stage::Interactive => {
                let s = self.scale.scale();
                let (sw, sh) = RenderScale::size(w, h, s);
                (sw, sh, 1, s)
            }
            Stage::Full => (w, h, 1, 1.0),
            Stage::Supersampled => (w, h, self.refine_supersample, 1.0),
        };
        // Stereo: the viewport shows the whole layout, each eye with the viewport's own shape
        // (side by side: half as wide and half as high, so neither eye is cropped or
        // squeezed; the pair is drawn letterboxed).
        let (fw, fh) = match base.projection {
            fathom_core::Projection::Mono => (fw, fh),
            fathom_core::Projection::SideBySide { .. } => ((fw / 2).max(1), (fh / 2).max(1)),
            fathom_core::Projection::Ods { .. } => (fw, (fh / 2).max(1)),
        };
        let mut request = RenderRequest {
            width: fw,
            height: fh,
            supersample: ss,
            region: None,
            ..base.clone()
        };
        if path {
            if stage == Stage::Interactive {
                // Moving: the preview tracer at the dynamic scale.
                request.backend = Backend::Trace;
                request.path = Default::default();
            } else {
                // Still: samples for a few target frame times per job (at least one pass),
                // so the picture on screen refines several times a second.
                request.path.time_limit =
                    Some((PATH_JOB_FRAMES * self.scale.target_ms()).max(PATH_JOB_MIN_MS) / 1e3);
            }
        }
        if octree && stage == Stage::Full {
            // Nothing moves: a fixed, long subdivision (at least the request's own).
            request.octree.target_fps = 0.0;
            request.octree.subdivide_ms = (self.octree_still_budget * self.scale.target_ms())
                .max(request.octree.subdivide_ms);
        } else if octree {
            // The octree's frames hold the same frame time: its subdivision takes what the
            // render leaves of it (between half and all of its budget).
            request.octree.target_fps = 1e3 / self.scale.target_ms();
        }
        self.next_id += 1;
        let cancel = CancelToken::new();
        let progress = std::sync::Arc::new(std::sync::atomic::AtomicU64::new(0));
        worker.render(FrameJob {
            progress: progress.clone(),
            id: self.next_id,
            stage,
            key,
            camera: camera.clone(),
            request,
            cancel: cancel.clone(),
            octree_step: octree,
            scale,
        });
        self.in_flight = Some(InFlight {
            id: self.next_id,
            key,
            stage,
            cancel,
            sent: Instant::now(),
            progress,
        });
    }

    /// The worker stopped: the frame in flight never comes back. Its view is marked failed
    /// and not asked for again until the view changes.
    pub fn worker_lost(&mut self) {
        if let Some(f) = self.in_flight.take() {
            self.failed_key = Some(f.key);
        }
    }

    /// How far the frame being rendered has got, once it has taken longer than a second and
    /// its renderer reports progress.
    pub fn progress(&self) -> Option<f64> {
        let f = self.in_flight.as_ref()?;
        if f.sent.elapsed().as_secs_f64() < 1.0 {
            return None;
        }
        let v = f.progress.load(std::sync::atomic::Ordering::Relaxed);
        let (total, done) = (v >> 32, v & 0xffff_ffff);
        (total > 0).then(|| done as f64 / total as f64)
    }

    /// Frames asked of the worker so far.
    pub fn frames_asked(&self) -> u64 {
        self.next_id
    }

    /// Whether a frame is being rendered.
    pub fn busy(&self) -> bool {
        self.in_flight.is_some()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::worker::Reply;
    use crate::worker::tests::wait_for;

    /// Schedules the next frame of `key` and waits for it (at most 60 s); the viewport takes
    /// it as the window would. Returns the frame's request, the session's counters and the
    /// octree's outstanding subdivisions.
    fn next_frame(
        v: &mut Viewport,
        w: &mut Worker,
        (key, cam, base): (u64, &Camera, &RenderRequest),
    ) -> (RenderRequest, fathom_render::Counters, Option<u64>) {
        v.schedule(w, key, cam, base, (32, 24));
        let Reply::Frame(done) = wait_for(w, |r| matches!(r, Reply::Frame(_))) else {
            unreachable!()
        };
        assert!(done.result.is_ok(), "{:?}", done.result.err());
        let out = (done.request.clone(), done.counters, done.octree_requests);
        v.accept(*done);
        out
    }

    /// A worker on `preset` and a viewport stepping its view on the octree (one thread,
    /// target 40 ms): the worker, the camera, the request, the view's key and the viewport.
    fn octree_view(preset: &str) -> (Worker, Camera, RenderRequest, u64, Viewport) {
        let scene = fathom_core::presets::load(preset).unwrap();
        let cam = scene.camera.clone();
        let w = Worker::start(scene, 0, || {}).unwrap();
        let base = RenderRequest {
            backend: Backend::Octree,
            threads: Some(1),
            ..RenderRequest::default()
        };
        let key = view_key(&cam, 0, &base);
        (w, cam, base, key, Viewport::new(40.0))
    }

    #[test]
    fn octree_frames_ask_for_the_target_frame_time_and_a_new_target_keeps_the_tree() {
        let (mut w, cam, base, key, mut v) = octree_view("sierpinski");
        // The view holds still through this test: keep the moving view's budget.
        v.octree_still_budget = 0.0;
        let (req, _, requests) = next_frame(&mut v, &mut w, (key, &cam, &base));
        assert_eq!(req.octree.target_fps, 25.0);
        assert!(requests.is_some(), "a stepped octree frame");
        // The slider moves: the next step of the same view asks for 50 fps, on the same tree.
        v.scale.set_target_ms(20.0);
        let (req, counters, _) = next_frame(&mut v, &mut w, (key, &cam, &base));
        assert_eq!(req.octree.target_fps, 50.0);
        assert_eq!(
            counters.octrees_built, 1,
            "a new frame-time target kept the tree"
        );
        // A setting that shapes the tree does rebuild it.
        let finer = RenderRequest {
            octree: fathom_render::OctreeSettings {
                fidelity: 2.0,
                ..base.octree.clone()
            },
            ..base.clone()
        };
        let finer_key = view_key(&cam, 0, &finer);
        let (_, counters, _) = next_frame(&mut v, &mut w, (finer_key, &cam, &finer));
        assert_eq!(counters.octrees_built, 2);
    }

    #[test]
    fn a_still_octree_view_subdivides_longer_and_gives_way_at_once_when_it_moves() {
        let (mut w, cam, base, key, mut v) = octree_view("mandelbulb");
        // Still steps of 10 ms (the view is far from settled after two steps either way).
        v.octree_still_budget = 0.25;
        let (req, _, _) = next_frame(&mut v, &mut w, (key, &cam, &base));
        assert_eq!(
            req.octree.target_fps, 25.0,
            "a view just shown steps as if moving"
        );
        std::thread::sleep(std::time::Duration::from_secs_f64(
            OCTREE_STILL_DELAY_MS * 1.2e-3,
        ));
        let (req, _, requests) = next_frame(&mut v, &mut w, (key, &cam, &base));
        assert_eq!(
            req.octree.target_fps, 0.0,
            "a still view holds no frame rate"
        );
        assert_eq!(req.octree.subdivide_ms, 10.0);
        assert!(
            requests.is_some_and(|r| r > 0),
            "the view is not settled yet"
        );
        assert_eq!(v.shown.as_ref().unwrap().stage, Stage::Full);
        // The next still step is in flight when the camera moves: it is cancelled at once
        // (an interactive step would be let finish), and the moved view is asked for.
        v.schedule(&w, key, &cam, &base, (32, 24));
        let still = v.in_flight.as_ref().unwrap().cancel.clone();
        assert!(!still.is_cancelled());
        let mut moved = cam.clone();
        moved.eye.x += 1e-3;
        let moved_key = view_key(&moved, 0, &base);
        v.schedule(&w, moved_key, &moved, &base, (32, 24));
        assert!(still.is_cancelled());
        let f = v.in_flight.as_ref().unwrap();
        assert_eq!((f.key, f.stage), (moved_key, Stage::Interactive));
    }
}
