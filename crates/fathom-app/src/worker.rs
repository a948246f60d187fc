//! The render worker: a thread that owns the render [`Session`], so the window's thread never
//! waits on a render. The window sends it scene edits and frame jobs; it renders the newest job
//! (older queued jobs are dropped unrendered), applies the newest scene first (an edit reaches
//! the next frame through `Session::set_scene`: a parameter-buffer update, or a recompile for a
//! structure edit), converts the frame to an image the window uploads as is, and wakes the
//! window. Each job carries its own [`CancelToken`]: the window cancels a job that went stale
//! without any risk of cancelling the next one.
//!
//! A worker that panics (a bug in a renderer, say) reports [`Reply::Stopped`] with the panic's
//! message and ends; a worker thread that vanished without a word is reported the same way by
//! [`Worker::poll`]. The window then starts a fresh worker on its own copy of the scene.

use fathom_core::{Camera, Scene};
use fathom_render::{
    Backend, CancelToken, Control, Counters, RenderError, RenderRequest, SceneChange, Session,
    Stats,
};
use std::sync::mpsc::{Receiver, Sender, TryRecvError, channel};
use std::time::Instant;

/// How refined a frame is.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Stage {
    /// Reduced resolution while the view moves.
    Interactive,
    /// Full resolution.
    Full,
    /// Full resolution, supersampled.
    Supersampled,
}

/// One frame to render.
#[derive(Clone)]
pub struct FrameJob {
    /// The job's number, to match its reply.
    pub id: u64,
    /// The refinement stage it renders.
    pub stage: Stage,
    /// The view this frame is of (camera, scene, settings, size), to tell stale frames.
    pub key: u64,
    /// The camera to render from.
    pub camera: Camera,
    /// What to render (size, backend, settings).
    pub request: RenderRequest,
    /// Set to abandon the frame when the view has moved on.
    pub cancel: CancelToken,
    /// Step the octree (render, then subdivide within its time budget) instead of settling it.
    pub octree_step: bool,
    /// The fraction of the viewport's resolution this frame renders at.
    pub scale: f64,
    /// How far the render has got: units done (low 32 bits) and their total (high 32 bits),
    /// written by the renderer as it goes, read by the window for a slow frame's progress.
    pub progress: std::sync::Arc<std::sync::atomic::AtomicU64>,
}

/// What the worker sends back for a job.
pub struct FrameDone {
    /// The job's number.
    pub id: u64,
    /// The job's refinement stage.
    pub stage: Stage,
    /// The job's view key.
    pub key: u64,
    /// The scene generation the frame shows.
    pub generation: u64,
    /// The request it was rendered with.
    pub request: RenderRequest,
    /// The picture, or why there is none.
    pub result: Result<Picture, FrameFailure>,
    /// Wall time of the render, conversion included.
    pub ms: f64,
    /// The job's resolution scale.
    pub scale: f64,
    /// The session's counters after the frame (compiles, parameter updates, ...).
    pub counters: Counters,
    /// Subdivisions the octree still asked for (stepped octree frames), so the window keeps
    /// stepping a still view until it has settled.
    pub octree_requests: Option<u64>,
}

/// A finished frame as the window shows it.
pub struct Picture {
    /// 8-bit sRGB RGBA, ready to upload.
    pub image: egui::ColorImage,
    /// What the frame cost.
    pub stats: Stats,
}

/// Why a job produced no picture.
#[derive(Debug)]
pub enum FrameFailure {
    /// The job was cancelled before it finished.
    Cancelled,
    /// The render failed (the error, as text).
    Error(String),
}

/// Scene edits the worker applied (or refused), reported once each.
pub struct SceneApplied {
    /// The scene generation of the edit.
    pub generation: u64,
    /// What the session had to do for it, or why it was refused.
    pub result: Result<SceneChange, String>,
    /// When the window sent the edit, to measure its latency to the screen.
    pub sent: Instant,
}

/// From the worker.
pub enum Reply {
    /// A job finished.
    Frame(Box<FrameDone>),
    /// A scene edit was applied or refused.
    Scene(SceneApplied),
    /// The worker stopped (it panicked, or its thread is gone) and renders nothing more; the
    /// frame it was rendering never comes back. Carries what is known of why.
    Stopped(String),
}

enum Msg {
    Scene {
        generation: u64,
        scene: Box<Scene>,
        sent: Instant,
    },
    Frame(Box<FrameJob>),
    Gpu(Box<fathom_gpu::Renderer>),
    /// Fault injection for tests: panic in the worker thread.
    Panic,
}

/// The window's side of the worker.
pub struct Worker {
    tx: Sender<Msg>,
    rx: Receiver<Reply>,
    /// Whether [`Reply::Stopped`] was already reported.
    stopped: bool,
}

impl Worker {
    /// Starts a worker on a session of `scene` (which must validate), whose frames report
    /// scene generation `generation` until the first edit. `wake` is called after every reply
    /// (the window passes `egui::Context::request_repaint`).
    pub fn start(
        scene: Scene,
        generation: u64,
        wake: impl Fn() + Send + 'static,
    ) -> Result<Worker, RenderError> {
        let session = Session::new(scene)?;
        let (tx, worker_rx) = channel::<Msg>();
        let (worker_tx, rx) = channel::<Reply>();
        std::thread::Builder::new()
            .name("fathom render worker".into())
            .spawn(move || {
                let report = worker_tx.clone();
                let r = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
                    run(session, generation, worker_rx, worker_tx, &wake)
                }));
                if let Err(p) = r {
                    let why = p
                        .downcast_ref::<&str>()
                        .map(|s| s.to_string())
                        .or_else(|| p.downcast_ref::<String>().cloned())
                        .unwrap_or_else(|| "a panic without a message".into());
                    let _ =
                        report.send(Reply::Stopped(format!("the render worker panicked: {why}")));
                    wake();
                }
            })
            .map_err(|e| RenderError::Threads {
                threads: 1,
                message: e.to_string(),
            })?;
        Ok(Worker {
            tx,
            rx,
            stopped: false,
        })
    }

    /// Sends an edited scene (generation `generation`).
    pub fn set_scene(&self, generation: u64, scene: Scene) {
        let _ = self.tx.send(Msg::Scene {
            generation,
            scene: Box::new(scene),
            sent: Instant::now(),
        });
    }

    /// Queues a frame.
    pub fn render(&self, job: FrameJob) {
        let _ = self.tx.send(Msg::Frame(Box::new(job)));
    }

    /// Gives the session a GPU renderer (on the window's device).
    pub fn set_gpu(&self, r: fathom_gpu::Renderer) {
        let _ = self.tx.send(Msg::Gpu(Box::new(r)));
    }

    /// Makes the worker thread panic, as a bug in a renderer would: how the tests check that
    /// the window notices and replaces it. Not for anything else.
    #[doc(hidden)]
    pub fn inject_panic(&self) {
        let _ = self.tx.send(Msg::Panic);
    }

    /// Replies so far, without waiting. Ends with [`Reply::Stopped`] (once) when the worker
    /// has stopped.
    pub fn poll(&mut self) -> Vec<Reply> {
        let mut out = Vec::new();
        loop {
            match self.rx.try_recv() {
                Ok(r) => {
                    if matches!(r, Reply::Stopped(_)) {
                        self.stopped = true;
                    }
                    out.push(r);
                }
                Err(TryRecvError::Empty) => break,
                Err(TryRecvError::Disconnected) => {
                    if !self.stopped {
                        self.stopped = true;
                        out.push(Reply::Stopped("the render worker's thread ended".into()));
                    }
                    break;
                }
            }
        }
        out
    }

    /// Whether the worker has stopped (as reported by [`Worker::poll`]).
    pub fn stopped(&self) -> bool {
        self.stopped
    }
}

fn run(
    mut session: Session,
    mut generation: u64,
    rx: Receiver<Msg>,
    tx: Sender<Reply>,
    wake: &impl Fn(),
) {
    let mut pending: Vec<Msg> = Vec::new();
    loop {
        if pending.is_empty() {
            match rx.recv() {
                Ok(m) => pending.push(m),
                Err(_) => return, // the window is gone
            }
        }
        loop {
            match rx.try_recv() {
                Ok(m) => pending.push(m),
                Err(TryRecvError::Empty) => break,
                Err(TryRecvError::Disconnected) => return,
            }
        }
        // The newest scene and the newest frame; GPU renderers in order.
        let mut scene = None;
        let mut frame = None;
        for m in pending.drain(..) {
            match m {
                Msg::Scene {
                    generation: g,
                    scene: s,
                    sent,
                } => scene = Some((g, s, sent)),
                Msg::Frame(j) => frame = Some(j),
                Msg::Gpu(r) => session.set_gpu(*r),
                Msg::Panic => panic!("fault injected by a test"),
            }
        }
        if let Some((g, s, sent)) = scene {
            let result = session.set_scene(*s).map_err(|e| e.to_string());
            if result.is_ok() {
                generation = g;
            }
            let _ = tx.send(Reply::Scene(SceneApplied {
                generation: g,
                result,
                sent,
            }));
            wake();
        }
        if let Some(job) = frame {
            let done = render(&mut session, &job, generation);
            if tx.send(Reply::Frame(Box::new(done))).is_err() {
                return;
            }
            wake();
        }
    }
}

fn render(session: &mut Session, job: &FrameJob, generation: u64) -> FrameDone {
    let start = Instant::now();
    let report = |p: fathom_render::Progress| {
        job.progress.store(
            ((p.total as u64) << 32) | p.done as u64,
            std::sync::atomic::Ordering::Relaxed,
        );
    };
    let control = Control {
        cancel: Some(&job.cancel),
        progress: Some(&report),
    };
    let mut octree_requests = None;
    let result = if job.cancel.is_cancelled() {
        Err(FrameFailure::Cancelled)
    } else if job.octree_step && job.request.backend == Backend::Octree {
        // Only a still view's step (its long subdivision) gives way to a cancel; a moving
        // view's step is short, and shown even when overdue.
        let still = job.stage == Stage::Full;
        let stop = if still { control } else { Control::default() };
        match session.step_octree(&job.camera, &job.request, true, still, &stop) {
            // The view moved on during a still view's subdivision, which stopped early: its
            // frame is of a view no longer asked for.
            Ok(_) if still && job.cancel.is_cancelled() => Err(FrameFailure::Cancelled),
            Ok((Some(frame), st)) => {
                octree_requests = Some(st.requests);
                let mut stats = Stats {
                    renderer: "svo",
                    width: frame.width,
                    height: frame.height,
                    primary_rays: st.rays,
                    hits: st.hits,
                    ..Stats::default()
                };
                stats.ms.trace_and_shade = st.render_ms;
                stats.ms.subdivide = Some(st.subdivide_ms);
                stats.octree = Some(fathom_render::stats::OctreeStats {
                    settle_frames: 0,
                    nodes: st.node_count,
                    bricks: st.brick_count,
                    nodes_per_ray: st.nodes_per_ray,
                    arena_bytes: st.arena_bytes,
                });
                Ok(picture(&frame, stats))
            }
            Ok((None, _)) => Err(FrameFailure::Error("the octree returned no frame".into())),
            Err(e) => Err(FrameFailure::Error(e.to_string())),
        }
    } else {
        match session.render_with(&job.camera, &job.request, &control) {
            Ok(r) => Ok(picture(&r.frame, r.stats)),
            Err(RenderError::Cancelled) => Err(FrameFailure::Cancelled),
            Err(e) => Err(FrameFailure::Error(e.to_string())),
        }
    };
    FrameDone {
        id: job.id,
        stage: job.stage,
        key: job.key,
        generation,
        request: job.request.clone(),
        result,
        ms: start.elapsed().as_secs_f64() * 1e3,
        scale: job.scale,
        counters: session.counters(),
        octree_requests,
    }
}

/// The frame as an sRGB image (tonemapped as the PNG output is).
fn picture(frame: &fathom_core::frame::Frame, stats: Stats) -> Picture {
    let rgb = fathom_image::post::to_rgb8(frame);
    let image = egui::ColorImage::from_rgb([frame.width as usize, frame.height as usize], &rgb);
    Picture { image, stats }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use std::time::Duration;

    fn job(id: u64, scene: &Scene) -> FrameJob {
        FrameJob {
            id,
            stage: Stage::Full,
            key: id,
            camera: scene.camera.clone(),
            request: RenderRequest {
                width: 32,
                height: 24,
                threads: Some(1),
                ..RenderRequest::default()
            },
            cancel: CancelToken::new(),
            octree_step: false,
            scale: 1.0,
            progress: Default::default(),
        }
    }

    /// Polls until a reply `want` accepts arrives (at most 60 s).
    pub(crate) fn wait_for(w: &mut Worker, want: impl Fn(&Reply) -> bool) -> Reply {
        let start = Instant::now();
        loop {
            if let Some(r) = w.poll().into_iter().find(|r| want(r)) {
                return r;
            }
            assert!(start.elapsed() < Duration::from_secs(60), "no reply");
            std::thread::sleep(Duration::from_millis(2));
        }
    }

    #[test]
    fn a_panicking_worker_says_so_once_and_a_new_one_renders() {
        let scene = fathom_core::presets::load("sierpinski").unwrap();
        let mut w = Worker::start(scene.clone(), 7, || {}).unwrap();
        w.render(job(1, &scene));
        match wait_for(&mut w, |r| matches!(r, Reply::Frame(_))) {
            Reply::Frame(f) => {
                assert!(f.result.is_ok());
                assert_eq!(f.generation, 7, "the starting generation is reported");
            }
            _ => unreachable!(),
        }
        w.inject_panic();
        match wait_for(&mut w, |r| matches!(r, Reply::Stopped(_))) {
            Reply::Stopped(why) => assert!(why.contains("fault injected"), "{why}"),
            _ => unreachable!(),
        }
        assert!(w.stopped());
        // Jobs sent now go nowhere, and the stop is not reported twice.
        w.render(job(2, &scene));
        std::thread::sleep(Duration::from_millis(50));
        assert!(w.poll().is_empty());
        // A replacement renders.
        let mut w = Worker::start(scene.clone(), 7, || {}).unwrap();
        w.render(job(3, &scene));
        assert!(matches!(
            wait_for(&mut w, |r| matches!(r, Reply::Frame(_))),
            Reply::Frame(f) if f.result.is_ok() && f.id == 3
        ));
    }
}
