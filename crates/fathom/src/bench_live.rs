//! `fathom bench live`: the numbers of live modulation, as JSON.
//!
//! - **latency**: a frame loop (modulator apply, session update, CPU render of the dive scene)
//!   while another thread sends one OSC value at a random moment, waits until a frame shows
//!   it, and sends the next. Per packet: the time until `apply` returns the new value, how
//!   many frames *started after the packet was sent* passed before one showed it (0: the very
//!   next frame, the target), and the time until that frame was finished.
//! - **flood**: the same loop's frame times, quiet and while a thread sends `--flood-rate`
//!   packets per second (a third valid, a third NaN, a third garbage).
//! - **path**: `fathom render --path dive` of docs/examples/mandelbulb-dive.ron, `--frames`
//!   frames at `--path-size`, PNGs written to a temporary directory, no video: frames/s.

use crate::args::parse_size;
use crate::cmd_render::RenderArgs;
use clap::Args;
use fathom_core::binding::{Binding, OscInput, Source};
use fathom_core::scene::Scene;
use fathom_live::{Modulator, Sender};
use fathom_render::{RenderRequest, Session};
use serde_json::json;
use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::{Arc, Mutex, mpsc};
use std::time::{Duration, Instant};

const DIVE: &str = include_str!("../../../docs/examples/mandelbulb-dive.ron");

#[derive(Args)]
pub struct LiveBenchArgs {
    /// Frame size of the latency and flood loops.
    #[arg(long, default_value = "320x240")]
    size: String,
    /// Render threads of the latency and flood loops (the OSC sender and listener use the
    /// other cores).
    #[arg(long, default_value_t = 1)]
    threads: usize,
    /// OSC packets timed for latency.
    #[arg(long, default_value_t = 40)]
    trials: usize,
    /// Frames in each of the quiet and flood runs.
    #[arg(long, default_value_t = 150)]
    frames: usize,
    /// Packets per second during the flood.
    #[arg(long, default_value_t = 100_000)]
    flood_rate: u64,
    /// Frames of the path render (0: skip it).
    #[arg(long, default_value_t = 300)]
    path_frames: usize,
    /// Size of the path render.
    #[arg(long, default_value = "640x480")]
    path_size: String,
    /// Render threads of the path render (default: all cores).
    #[arg(long)]
    path_threads: Option<usize>,
}

/// The dive scene with one OSC binding (no smoothing) on the light.
fn bench_scene() -> Result<Scene, String> {
    let mut scene =
        fathom_core::scene_file::parse(DIVE, "mandelbulb-dive.ron").map_err(|e| e.to_string())?;
    scene.bindings = vec![Binding {
        param: "lights[0].intensity".into(),
        source: Source::Osc(OscInput {
            address: "/bench/level".into(),
            arg: 0,
            from: (0.0, 1.0),
        }),
        to: (0.0, 1.0),
        smoothing: 0.0,
    }];
    scene.validate_animation().map_err(|e| e.to_string())?;
    Ok(scene)
}

fn percentile(v: &[f64], p: f64) -> f64 {
    if v.is_empty() {
        return f64::NAN;
    }
    let mut s = v.to_vec();
    s.sort_by(f64::total_cmp);
    s[((p / 100.0) * (s.len() - 1) as f64).round() as usize]
}

fn summary(v: &[f64]) -> serde_json::Value {
    json!({
        "n": v.len(),
        "p50": percentile(v, 50.0),
        "p99": percentile(v, 99.0),
        "max": percentile(v, 100.0),
    })
}

/// A frame loop: apply, update the session, render. Returns (apply done, frame done) times.
struct Loop {
    scene: Scene,
    session: Session,
    modulator: Modulator,
    request: RenderRequest,
    start: Instant,
}

impl Loop {
    fn new(a: &LiveBenchArgs) -> Result<(Loop, std::net::SocketAddr), String> {
        let scene = bench_scene()?;
        let (width, height) = parse_size(&a.size)?;
        let request = RenderRequest {
            width,
            height,
            threads: Some(a.threads),
            ..RenderRequest::default()
        };
        request.validate().map_err(|e| e.to_string())?;
        let session = Session::new(scene.clone()).map_err(|e| e.to_string())?;
        let mut modulator = Modulator::new(&scene).map_err(|e| e.to_string())?;
        let addr = modulator
            .listen("127.0.0.1:0".parse().expect("a literal address"))
            .map_err(|e| e.to_string())?;
        Ok((
            Loop {
                scene,
                session,
                modulator,
                request,
                start: Instant::now(),
            },
            addr,
        ))
    }

    /// One frame; returns (instant apply returned, instant the frame was done).
    fn frame(&mut self) -> Result<(Instant, Instant), String> {
        let t = self.start.elapsed().as_secs_f64();
        let applied = self.modulator.apply(&mut self.scene, t);
        let seen = Instant::now();
        if applied.changed {
            self.session
                .set_scene(self.scene.clone())
                .map_err(|e| e.to_string())?;
        }
        let cam = self.scene.camera.clone();
        self.session
            .render(&cam, &self.request)
            .map_err(|e| e.to_string())?;
        Ok((seen, Instant::now()))
    }

    fn level(&self) -> Option<f64> {
        self.modulator.live()[0].level
    }
}

fn latency(a: &LiveBenchArgs) -> Result<serde_json::Value, String> {
    let (mut lp, addr) = Loop::new(a)?;
    // Warm up (thread pool, caches) and measure a frame.
    let mut frame_ms = Vec::new();
    for _ in 0..5 {
        let t0 = Instant::now();
        lp.frame()?;
        frame_ms.push(t0.elapsed().as_secs_f64() * 1e3);
    }
    let typical = Duration::from_secs_f64(percentile(&frame_ms, 50.0) / 1e3);
    // The sender publishes (value, instant sent) and waits for the loop's acknowledgement.
    let sent: Arc<Mutex<Option<(f64, Instant)>>> = Arc::new(Mutex::new(None));
    let (ack_tx, ack_rx) = mpsc::channel::<()>();
    let trials = a.trials;
    let s = sent.clone();
    let sender = std::thread::spawn(move || -> Result<(), String> {
        let tx = Sender::new(addr).map_err(|e| e.to_string())?;
        let mut x = 0x2545_f491_4f6c_dd1du64;
        for k in 0..trials {
            // A pseudo-random moment within about two frames.
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            let wait = typical.mul_f64((x % 2000) as f64 / 1000.0);
            std::thread::sleep(wait);
            let v = (k + 1) as f64 / (trials + 2) as f64;
            let v = v as f32 as f64; // what arrives is an f32
            *s.lock().map_err(|e| e.to_string())? = Some((v, Instant::now()));
            tx.send("/bench/level", &[v]).map_err(|e| e.to_string())?;
            if ack_rx.recv_timeout(Duration::from_secs(30)).is_err() {
                return Err("the frame loop never showed a packet".into());
            }
        }
        Ok(())
    });
    let mut apply_us = Vec::new();
    let mut to_frame_ms = Vec::new();
    let mut frames_late = [0usize; 4];
    let mut pending: Option<(f64, Instant, Option<usize>)> = None;
    let mut frame = 0usize;
    let deadline = Instant::now() + Duration::from_secs(600);
    while apply_us.len() < trials {
        if Instant::now() > deadline {
            return Err("latency run did not finish in 10 minutes".into());
        }
        let frame_start = Instant::now();
        if pending.is_none() {
            pending = sent
                .lock()
                .map_err(|e| e.to_string())?
                .map(|(v, at)| (v, at, None));
        }
        // The first frame started after the packet was sent.
        if let Some((_, at, first @ None)) = &mut pending
            && frame_start >= *at
        {
            *first = Some(frame);
        }
        let (seen, done) = lp.frame()?;
        if pending.is_none() {
            // Published after this frame started: this frame may already show it.
            pending = sent
                .lock()
                .map_err(|e| e.to_string())?
                .map(|(v, at)| (v, at, None));
        }
        if let Some((v, at, first)) = pending
            && lp.level() == Some(v)
        {
            apply_us.push(seen.duration_since(at).as_secs_f64() * 1e6);
            to_frame_ms.push(done.duration_since(at).as_secs_f64() * 1e3);
            // A packet that arrived while this frame was already running shows in it
            // (first is None or later than this frame): 0 frames late.
            let late = first.map_or(0, |f| frame.saturating_sub(f));
            frames_late[late.min(3)] += 1;
            pending = None;
            *sent.lock().map_err(|e| e.to_string())? = None;
            ack_tx.send(()).map_err(|e| e.to_string())?;
        }
        frame += 1;
    }
    sender
        .join()
        .map_err(|_| "the sender thread panicked".to_string())??;
    Ok(json!({
        "trials": trials,
        "frame_ms": summary(&frame_ms),
        "packet_to_apply_us": summary(&apply_us),
        "packet_to_frame_done_ms": summary(&to_frame_ms),
        "frames_late": {
            "0 (the next frame)": frames_late[0],
            "1": frames_late[1],
            "2": frames_late[2],
            "3 or more": frames_late[3],
        },
        "counters": lp.modulator.counters(),
    }))
}

fn flood(a: &LiveBenchArgs) -> Result<serde_json::Value, String> {
    let (mut lp, addr) = Loop::new(a)?;
    for _ in 0..3 {
        lp.frame()?;
    }
    let mut quiet = Vec::with_capacity(a.frames);
    for _ in 0..a.frames {
        let t0 = Instant::now();
        lp.frame()?;
        quiet.push(t0.elapsed().as_secs_f64() * 1e3);
    }
    let before = lp.modulator.counters();
    let stop = Arc::new(AtomicBool::new(false));
    let sent = Arc::new(AtomicU64::new(0));
    let rate = a.flood_rate;
    let (s_stop, s_sent) = (stop.clone(), sent.clone());
    let flooder = std::thread::spawn(move || -> Result<(), String> {
        let tx = Sender::new(addr).map_err(|e| e.to_string())?;
        let good = fathom_live::send::encode("/bench/level", &[0.5]).map_err(|e| e.to_string())?;
        let nan =
            fathom_live::send::encode("/bench/level", &[f64::NAN]).map_err(|e| e.to_string())?;
        let start = Instant::now();
        let mut n = 0u64;
        while !s_stop.load(Ordering::Relaxed) {
            // Keep to the rate: send what is due, then yield briefly.
            let due = (start.elapsed().as_secs_f64() * rate as f64) as u64;
            while n < due {
                let _ = match n % 3 {
                    0 => tx.send_raw(&good),
                    1 => tx.send_raw(&nan),
                    _ => tx.send_raw(&n.to_le_bytes()),
                };
                n += 1;
            }
            s_sent.store(n, Ordering::Relaxed);
            std::thread::sleep(Duration::from_micros(200));
        }
        Ok(())
    });
    let t_flood = Instant::now();
    let mut flooded = Vec::with_capacity(a.frames);
    for _ in 0..a.frames {
        let t0 = Instant::now();
        lp.frame()?;
        flooded.push(t0.elapsed().as_secs_f64() * 1e3);
    }
    let secs = t_flood.elapsed().as_secs_f64();
    stop.store(true, Ordering::Relaxed);
    flooder
        .join()
        .map_err(|_| "the flood thread panicked".to_string())??;
    std::thread::sleep(Duration::from_millis(50));
    let after = lp.modulator.counters();
    let received = after.packets - before.packets;
    let p99q = percentile(&quiet, 99.0);
    let p99f = percentile(&flooded, 99.0);
    Ok(json!({
        "frames": a.frames,
        "quiet_frame_ms": summary(&quiet),
        "flood_frame_ms": summary(&flooded),
        "p99_flood_over_quiet": p99f / p99q,
        "p50_flood_over_quiet": percentile(&flooded, 50.0) / percentile(&quiet, 50.0),
        "flood_seconds": secs,
        "packets_sent": sent.load(Ordering::Relaxed),
        "packets_sent_per_s": sent.load(Ordering::Relaxed) as f64 / secs,
        "packets_received": received,
        "packets_received_per_s": received as f64 / secs,
        "rejected": after.rejected - before.rejected,
        "counters_after": after,
    }))
}

fn path_render(a: &LiveBenchArgs) -> Result<serde_json::Value, String> {
    let dir = std::env::temp_dir().join(format!("fathom-bench-live-{}", std::process::id()));
    std::fs::create_dir_all(&dir).map_err(|e| format!("cannot create {}: {e}", dir.display()))?;
    let scene_file = dir.join("mandelbulb-dive.ron");
    std::fs::write(&scene_file, DIVE).map_err(|e| e.to_string())?;
    let args = RenderArgs {
        scene: Some(scene_file),
        output: PathBuf::from(format!("{}/", dir.join("frames").display())),
        size: Some(parse_size(&a.path_size)?),
        threads: a.path_threads,
        quiet: true,
        path: Some("dive".into()),
        frames: Some(a.path_frames),
        no_video: true,
        ..RenderArgs::defaults()
    };
    let start = Instant::now();
    let r = crate::render(args);
    let secs = start.elapsed().as_secs_f64();
    let written = std::fs::read_dir(dir.join("frames")).map_or(0, |d| d.count());
    std::fs::remove_dir_all(&dir).ok();
    r?;
    Ok(json!({
        "frames": a.path_frames,
        "size": a.path_size,
        "threads": a.path_threads.unwrap_or_else(|| std::thread::available_parallelism().map_or(1, |n| n.get())),
        "files_written": written,
        "seconds": secs,
        "fps": a.path_frames as f64 / secs,
    }))
}

pub fn run(a: LiveBenchArgs) -> Result<(), String> {
    eprintln!("bench live: latency ({} packets) ...", a.trials);
    let latency = latency(&a)?;
    eprintln!(
        "bench live: flood ({} frames quiet, {} with {} packets/s) ...",
        a.frames, a.frames, a.flood_rate
    );
    let flood = flood(&a)?;
    let path = if a.path_frames > 0 {
        eprintln!(
            "bench live: fathom render --path dive, {} frames at {} ...",
            a.path_frames, a.path_size
        );
        path_render(&a)?
    } else {
        serde_json::Value::Null
    };
    let out = json!({
        "build": if cfg!(debug_assertions) { "debug" } else { "release" },
        "cores": std::thread::available_parallelism().map_or(1, |n| n.get()),
        "loop_size": a.size,
        "loop_threads": a.threads,
        "latency": latency,
        "flood": flood,
        "path_render": path,
    });
    println!(
        "{}",
        serde_json::to_string_pretty(&out).map_err(|e| e.to_string())?
    );
    Ok(())
}
