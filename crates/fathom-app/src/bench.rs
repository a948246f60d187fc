//! The explorer's numbers without a window (`fathom bench explore`): the window's own frame
//! scheduling ([`Viewport`]) and render worker ([`Worker`]) driven by a loop that stands in
//! for the UI thread (it polls every few milliseconds, as a window repainting while the view
//! moves does). UI drawing is not included: these are the render side's figures.
//!
//! Per scene and renderer:
//! - **moving**: the camera turns steadily for `move_secs`; the render time of each
//!   interactive frame, the interval between frames reaching the screen, and the render
//!   scale the controller settles at (median over the second half) against the target;
//! - **stop**: from the camera's last move to the first full-resolution frame of the still
//!   view, and to the final (supersampled) refinement;
//! - **edit**: a parameter nudged `edits` times, one edit every 50 ms as a slow slider drag
//!   does, starting from the still view: the time from each edit to the first frame on screen
//!   showing it, how many frames came back in between without it (frames already in flight
//!   when it was made), and the compilations the edits caused (none expected:
//!   parameter-buffer updates only).

use crate::camera::{self, CameraController, Controls};
use crate::scale::RenderScale;
use crate::viewport::{Viewport, view_key};
use crate::worker::{Reply, Stage, Worker};
use fathom_core::registry::{Family, ParamKind};
use fathom_core::{Camera, Scene, Tape};
use fathom_render::{Backend, RenderRequest};
use glam::DVec2;
use serde::Serialize;
use std::sync::mpsc::{Receiver, channel};
use std::time::{Duration, Instant};

/// What to measure.
#[derive(Clone, Debug)]
pub struct BenchConfig {
    /// Viewport width, pixels.
    pub width: u32,
    /// Viewport height, pixels.
    pub height: u32,
    /// Frame time the dynamic scale holds while moving, ms.
    pub target_ms: f64,
    /// How long the camera moves.
    pub move_secs: f64,
    /// Parameter edits timed on the still view.
    pub edits: usize,
    /// Longest wait for any one frame or refinement before the run gives up.
    pub timeout: Duration,
}

/// Summary of a list of numbers.
#[derive(Clone, Debug, Serialize)]
pub struct Summary {
    /// Finite values summarised.
    pub n: usize,
    /// The median.
    pub p50: f64,
    /// The 90th percentile.
    pub p90: f64,
    /// The largest value.
    pub max: f64,
}

impl Summary {
    fn of(v: &[f64]) -> Summary {
        let mut s: Vec<f64> = v.iter().copied().filter(|x| x.is_finite()).collect();
        s.sort_by(f64::total_cmp);
        let at = |p: f64| {
            if s.is_empty() {
                f64::NAN
            } else {
                s[((p * (s.len() - 1) as f64).round() as usize).min(s.len() - 1)]
            }
        };
        Summary {
            n: s.len(),
            p50: at(0.5),
            p90: at(0.9),
            max: at(1.0),
        }
    }
}

/// The moving camera.
#[derive(Clone, Debug, Serialize)]
pub struct Moving {
    /// Render time of each interactive frame (conversion to an image included), ms.
    pub render_ms: Summary,
    /// Render time over the second half only (after the scale has adapted), ms.
    pub render_ms_settled: Summary,
    /// Time between frames reaching the screen, second half, ms.
    pub interval_ms_settled: Summary,
    /// Render scale over the second half (fraction of the viewport's width).
    pub scale_settled: Summary,
    /// Pixel size of the interactive frames at the median settled scale.
    pub settled_size: (u32, u32),
}

/// The still view after the camera stopped.
#[derive(Clone, Debug, Serialize)]
pub struct Stop {
    /// From the last camera move to the first full-resolution frame, ms.
    pub to_full_ms: f64,
    /// To the final refinement (supersampled), ms.
    pub to_settled_ms: f64,
    /// Render time of the full-resolution frame, ms.
    pub full_render_ms: f64,
}

/// Parameter edits on the still view.
#[derive(Clone, Debug, Serialize)]
pub struct Edits {
    /// The parameter nudged (node path and name).
    pub param: String,
    /// Milliseconds between edits.
    pub interval_ms: f64,
    /// From the edit to the first frame on screen that shows it, ms.
    pub latency_ms: Summary,
    /// Edits shown by the first frame that came back after them.
    pub shown_by_first_frame: usize,
    /// Edits shown by the first or second frame that came back after them (the first having
    /// been in flight when the edit was made).
    pub shown_by_second_frame: usize,
    /// Most frames that came back after an edit without showing it.
    pub stale_frames_max: usize,
    /// Tape compilations the edits caused (0: each edit was a parameter-buffer update).
    pub compiles_added: u64,
    /// Parameter-buffer updates the edits caused.
    pub param_updates_added: u64,
}

/// One scene on one renderer.
#[derive(Clone, Debug, Serialize)]
pub struct BenchRow {
    /// The scene's name.
    pub scene: String,
    /// The renderer's name.
    pub renderer: &'static str,
    /// The GPU adapter (for the GPU renderer); a software one (lavapipe) gives CPU times.
    pub adapter: Option<String>,
    /// Whether that adapter is a software one.
    pub adapter_is_software: Option<bool>,
    /// Viewport width, pixels.
    pub width: u32,
    /// Viewport height, pixels.
    pub height: u32,
    /// Frame time the dynamic scale held, ms.
    pub target_ms: f64,
    /// The moving camera's figures.
    pub moving: Moving,
    /// The still view's figures after the camera stopped.
    pub stop: Stop,
    /// The parameter edits' figures, when edits were timed.
    pub edits: Option<Edits>,
    /// The renderers' notes on the frames (a fallback to the CPU, say), each once.
    pub notes: Vec<String>,
}

/// An octree view held still in the window from its first frame: how long its steps take to
/// settle it (no leaf asking for subdivision), with a given still-view budget.
#[derive(Clone, Debug, Serialize)]
pub struct OctreeSettle {
    /// The scene's name.
    pub scene: String,
    /// Viewport width, pixels.
    pub width: u32,
    /// Viewport height, pixels.
    pub height: u32,
    /// Target frame time, ms.
    pub target_ms: f64,
    /// The still view's subdivision per step, in target frame times (0: the moving view's
    /// budget, which holds the target frame time).
    pub still_budget: f64,
    /// From asking for the first frame to the first frame that asked for no subdivision, ms
    /// (`None`: not settled within the time limit).
    pub to_settled_ms: Option<f64>,
    /// Frames shown until then (or until the time limit).
    pub frames: usize,
    /// Interval between frames reaching the screen, ms.
    pub interval_ms: Summary,
    /// Octree nodes at the last frame shown.
    pub nodes: u64,
    /// Subdivisions the last frame shown asked for (0: settled).
    pub requests_left: u64,
}

/// Holds `scene`'s view still on the octree in the window's scheduling, for at most
/// `limit`, with `still_budget` ([`Viewport::octree_still_budget`]).
pub fn measure_octree_settle(
    name: &str,
    scene: &Scene,
    cfg: &BenchConfig,
    still_budget: f64,
    limit: Duration,
) -> Result<OctreeSettle, String> {
    let base = RenderRequest {
        backend: Backend::Octree,
        ..RenderRequest::default()
    };
    let mut rig = Rig::new(scene, base, cfg, None)?;
    rig.viewport.octree_still_budget = still_budget;
    let start = Instant::now();
    while !rig.settled() && start.elapsed() < limit {
        rig.tick()?;
    }
    let settled = rig.settled();
    let arrivals: Vec<Instant> = rig.shown.iter().map(|s| s.3).collect();
    let intervals: Vec<f64> = arrivals
        .windows(2)
        .map(|w| w[1].duration_since(w[0]).as_secs_f64() * 1e3)
        .collect();
    let shown = rig.viewport.shown.as_ref();
    Ok(OctreeSettle {
        scene: name.to_string(),
        width: cfg.width,
        height: cfg.height,
        target_ms: cfg.target_ms,
        still_budget,
        to_settled_ms: settled.then(|| {
            arrivals
                .last()
                .map_or(0.0, |t| t.duration_since(start).as_secs_f64() * 1e3)
        }),
        frames: arrivals.len(),
        interval_ms: Summary::of(&intervals),
        nodes: shown
            .and_then(|s| s.stats.octree.as_ref())
            .map_or(0, |o| o.nodes),
        requests_left: shown.and_then(|s| s.octree_requests).unwrap_or(0),
    })
}

/// The window's stand-in: a worker, a viewport and a camera.
struct Rig {
    worker: Worker,
    wake: Receiver<()>,
    viewport: Viewport,
    camera: CameraController,
    tape: Tape,
    scene: Scene,
    generation: u64,
    base: RenderRequest,
    size: (u32, u32),
    compiles: u64,
    param_updates: u64,
    /// The generation of the frame on screen, and when it arrived.
    last_frame: Option<(u64, Instant)>,
    /// Frames shown since the rig started, with (stage, render ms, scale used, arrival).
    shown: Vec<(Stage, f64, f64, Instant, u64)>,
    notes: Vec<String>,
    timeout: Duration,
}

impl Rig {
    fn new(
        scene: &Scene,
        base: RenderRequest,
        cfg: &BenchConfig,
        gpu: Option<fathom_gpu::Renderer>,
    ) -> Result<Rig, String> {
        let (tx, wake) = channel();
        let worker = Worker::start(scene.clone(), 0, move || {
            let _ = tx.send(());
        })
        .map_err(|e| e.to_string())?;
        if let Some(g) = gpu {
            worker.set_gpu(g);
        }
        Ok(Rig {
            worker,
            wake,
            viewport: Viewport::new(cfg.target_ms),
            camera: CameraController::new(&scene.camera),
            tape: Tape::compile(scene).map_err(|e| e.to_string())?,
            scene: scene.clone(),
            generation: 0,
            base,
            size: (cfg.width, cfg.height),
            compiles: 1,
            param_updates: 0,
            last_frame: None,
            shown: Vec::new(),
            notes: Vec::new(),
            timeout: cfg.timeout,
        })
    }

    fn camera(&self) -> Camera {
        self.camera.camera()
    }

    fn key(&self) -> u64 {
        view_key(&self.camera(), self.generation, &self.base)
    }

    /// One UI frame: wait (at most 4 ms) for the worker, take its replies, schedule.
    fn tick(&mut self) -> Result<(), String> {
        let _ = self.wake.recv_timeout(Duration::from_millis(4));
        for r in self.worker.poll() {
            match r {
                Reply::Frame(done) => {
                    self.compiles = done.counters.compiles;
                    self.param_updates = done.counters.param_updates;
                    let (stage, ms, scale, generation) =
                        (done.stage, done.ms, done.scale, done.generation);
                    if let Some(e) = done.result.as_ref().err()
                        && let crate::worker::FrameFailure::Error(e) = e
                    {
                        return Err(format!("a frame failed: {e}"));
                    }
                    if let Ok(p) = &done.result
                        && let Some(n) = &p.stats.note
                        && !self.notes.contains(n)
                    {
                        self.notes.push(n.clone());
                    }
                    if self.viewport.accept(*done).is_some() {
                        let now = Instant::now();
                        self.last_frame = Some((generation, now));
                        self.shown.push((stage, ms, scale, now, generation));
                    }
                }
                Reply::Scene(s) => {
                    s.result.map_err(|e| format!("an edit was refused: {e}"))?;
                }
                Reply::Stopped(why) => return Err(why),
            }
        }
        let (cam, key) = (self.camera(), self.key());
        self.viewport
            .schedule(&self.worker, key, &cam, &self.base, self.size);
        Ok(())
    }

    /// Ticks until `done` holds (or the timeout passes).
    fn until(&mut self, what: &str, done: impl Fn(&Rig) -> bool) -> Result<(), String> {
        let start = Instant::now();
        while !done(self) {
            if start.elapsed() > self.timeout {
                return Err(format!("timed out waiting for {what}"));
            }
            self.tick()?;
        }
        Ok(())
    }

    fn settled(&self) -> bool {
        self.viewport.settled(self.key())
    }
}

/// The first scalar parameter with a finite range, depth first: (node path, offset, name,
/// min, max).
fn editable_param(scene: &Scene) -> Option<(Vec<usize>, usize, String, f64, f64)> {
    fn walk(
        n: &fathom_core::scene::Node,
        path: &mut Vec<usize>,
    ) -> Option<(Vec<usize>, usize, String, f64, f64)> {
        let mut off = 0;
        for p in n.shape.kind.def().params {
            if p.kind == ParamKind::Scalar && p.min.is_finite() && p.max.is_finite() {
                return Some((path.clone(), off, p.name.to_string(), p.min, p.max));
            }
            off += p.kind.width();
        }
        for (i, c) in n.children.iter().enumerate() {
            path.push(i);
            if let Some(r) = walk(c, path) {
                return Some(r);
            }
            path.pop();
        }
        None
    }
    walk(&scene.root, &mut Vec::new())
}

/// Measures one scene on one renderer (`gpu`: the GPU renderer to use, for the GPU row).
pub fn measure(
    name: &str,
    scene: &Scene,
    cfg: &BenchConfig,
    gpu: Option<fathom_gpu::Renderer>,
) -> Result<BenchRow, String> {
    let (adapter, software) = match &gpu {
        Some(g) => (Some(g.gpu().adapter_name()), Some(g.gpu().is_software())),
        None => (None, None),
    };
    let backend = if gpu.is_some() {
        Backend::Gpu
    } else {
        Backend::Trace
    };
    let base = RenderRequest {
        backend,
        ..RenderRequest::default()
    };
    let mut rig = Rig::new(scene, base, cfg, gpu)?;

    // Warm up: the first view to its final refinement (thread pool, GPU buffers).
    rig.until("the first view to settle", Rig::settled)?;

    // Moving: turn at 0.25 rad/s and drift forward slowly.
    rig.shown.clear();
    let start = Instant::now();
    let mut last = start;
    while start.elapsed().as_secs_f64() < cfg.move_secs {
        let now = Instant::now();
        let dt = now.duration_since(last).as_secs_f64();
        last = now;
        let c = Controls {
            look: DVec2::new(0.25 * dt / camera::LOOK_RATE, 0.0),
            forward: 0.05,
            ..Controls::default()
        };
        let d = camera::distance_at(&rig.tape, rig.camera.eye);
        rig.camera.step(&c, dt.max(1e-4), d);
        rig.tick()?;
    }
    let stopped = Instant::now();
    let half = start + Duration::from_secs_f64(cfg.move_secs / 2.0);
    let interactive: Vec<_> = rig
        .shown
        .iter()
        .filter(|s| s.0 == Stage::Interactive)
        .cloned()
        .collect();
    let later: Vec<_> = interactive.iter().filter(|s| s.3 >= half).collect();
    let intervals: Vec<f64> = later
        .windows(2)
        .map(|w| w[1].3.duration_since(w[0].3).as_secs_f64() * 1e3)
        .collect();
    let scales: Vec<f64> = later.iter().map(|s| s.2).collect();
    let scale_settled = Summary::of(&scales);
    let moving = Moving {
        render_ms: Summary::of(&interactive.iter().map(|s| s.1).collect::<Vec<_>>()),
        render_ms_settled: Summary::of(&later.iter().map(|s| s.1).collect::<Vec<_>>()),
        interval_ms_settled: Summary::of(&intervals),
        settled_size: RenderScale::size(cfg.width, cfg.height, scale_settled.p50),
        scale_settled,
    };

    // Stop: to full resolution, then to the final refinement.
    let n0 = rig.shown.len();
    let key = rig.key();
    rig.until("full resolution", |r| {
        r.viewport
            .shown
            .as_ref()
            .is_some_and(|s| s.key == key && s.stage >= Stage::Full)
    })?;
    let to_full_ms = stopped.elapsed().as_secs_f64() * 1e3;
    let full_render_ms = rig.shown[n0..]
        .iter()
        .find(|s| s.0 >= Stage::Full)
        .map_or(f64::NAN, |s| s.1);
    rig.until("the final refinement", Rig::settled)?;
    let stop = Stop {
        to_full_ms,
        to_settled_ms: stopped.elapsed().as_secs_f64() * 1e3,
        full_render_ms,
    };

    // Edits: nudge a parameter up and down by 1 % of its range every 50 ms, as a slow drag.
    let interval = Duration::from_millis(50);
    let edits = match editable_param(scene) {
        Some((path, off, pname, min, max)) if cfg.edits > 0 => {
            let (c0, u0) = (rig.compiles, rig.param_updates);
            let n0 = rig.shown.len();
            let mut sent = Vec::new();
            let mut next_at = Instant::now();
            let start = Instant::now();
            while sent.len() < cfg.edits || rig.last_frame.is_none_or(|(g, _)| g < rig.generation) {
                if start.elapsed() > rig.timeout {
                    return Err("timed out waiting for the edits to reach the screen".into());
                }
                if sent.len() < cfg.edits && Instant::now() >= next_at {
                    let k = sent.len();
                    let node = crate::tree::node_at_mut(&mut rig.scene.root, &path)
                        .ok_or("the edited node vanished")?;
                    let v = &mut node.shape.params[off];
                    let step = 0.01 * (max - min).min(10.0 * v.abs().max(0.1));
                    *v = (*v + if k % 2 == 0 { step } else { -step }).clamp(min, max);
                    rig.generation += 1;
                    rig.worker.set_scene(rig.generation, rig.scene.clone());
                    sent.push((rig.generation, Instant::now()));
                    next_at += interval;
                }
                rig.tick()?;
            }
            rig.until("the last edit to settle", Rig::settled)?;
            let frames = &rig.shown[n0..];
            let mut lat = Vec::new();
            let (mut first, mut second, mut stale_max) = (0, 0, 0);
            for &(g, t) in &sent {
                let after: Vec<_> = frames.iter().filter(|f| f.3 >= t).collect();
                let Some(i) = after.iter().position(|f| f.4 >= g) else {
                    continue;
                };
                lat.push(after[i].3.duration_since(t).as_secs_f64() * 1e3);
                first += (i == 0) as usize;
                second += (i <= 1) as usize;
                stale_max = stale_max.max(i);
            }
            Some(Edits {
                param: format!(
                    "root{}.{pname}",
                    path.iter()
                        .map(|i| format!(".children[{i}]"))
                        .collect::<String>()
                ),
                interval_ms: interval.as_secs_f64() * 1e3,
                latency_ms: Summary::of(&lat),
                shown_by_first_frame: first,
                shown_by_second_frame: second,
                stale_frames_max: stale_max,
                compiles_added: rig.compiles - c0,
                param_updates_added: rig.param_updates - u0,
            })
        }
        _ => None,
    };
    Ok(BenchRow {
        scene: name.to_string(),
        renderer: backend.name(),
        adapter,
        adapter_is_software: software,
        width: cfg.width,
        height: cfg.height,
        target_ms: cfg.target_ms,
        moving,
        stop,
        edits,
        notes: rig.notes,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_short_run_measures_every_figure_and_edits_compile_nothing() {
        let scene = fathom_core::presets::load("sierpinski").unwrap();
        let cfg = BenchConfig {
            width: 96,
            height: 64,
            target_ms: 33.0,
            move_secs: 0.5,
            edits: 3,
            timeout: Duration::from_secs(60),
        };
        let r = measure("sierpinski", &scene, &cfg, None).unwrap();
        assert!(r.moving.render_ms.n > 0, "{r:?}");
        assert!(r.stop.to_full_ms > 0.0 && r.stop.to_settled_ms >= r.stop.to_full_ms);
        let e = r.edits.unwrap();
        assert_eq!(e.compiles_added, 0, "{e:?}");
        // Every edit that reached the screen was a parameter-buffer update (edits the worker
        // received together are applied as one).
        assert!(e.latency_ms.n >= 1 && e.param_updates_added >= 1, "{e:?}");
        assert!(e.param_updates_added <= 3, "{e:?}");
    }

    #[test]
    fn a_still_octree_view_settles_and_the_run_says_when() {
        let scene = fathom_core::presets::load("sierpinski").unwrap();
        let cfg = BenchConfig {
            width: 48,
            height: 32,
            target_ms: 33.0,
            move_secs: 0.5,
            edits: 0,
            timeout: Duration::from_secs(60),
        };
        let r = measure_octree_settle("sierpinski", &scene, &cfg, 4.0, cfg.timeout).unwrap();
        let ms = r
            .to_settled_ms
            .expect("a tiny view settles within a minute");
        assert!(ms > 0.0 && r.frames >= 2 && r.nodes > 1, "{r:?}");
        assert_eq!(r.requests_left, 0, "{r:?}");
        // Cut short, the run reports what is left instead of a time.
        let r = measure_octree_settle("sierpinski", &scene, &cfg, 0.0, Duration::ZERO).unwrap();
        assert!(r.to_settled_ms.is_none() && r.frames == 0, "{r:?}");
    }
}
