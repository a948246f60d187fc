//! `fathom bench window`: the explorer as a user meets it, measured on the real window under a
//! virtual X server with real X input (fathom-xdrive: Xvfb started and stopped by PID,
//! xdotool). For each renderer: the time from launch to the first picture, the window's frame
//! rate during a continuous drag, and the latency of a drag (from the first X motion event to
//! the first window frame whose picture is of the moved view: `shown_view` in the frame log),
//! median and worst over a number of separate drags. Prints JSON.

use clap::Args;
use fathom_xdrive::{Display, Window, now_ms};
use serde_json::{Value, json};
use std::path::PathBuf;

/// Measures the explorer's real window: launch time, fps while dragging, drag latency.
#[derive(Args, Debug)]
pub struct WindowBenchArgs {
    /// Preset to explore.
    #[arg(long, default_value = "menger")]
    preset: String,
    /// Renderers to measure (`trace`, `svo`, `gpu`).
    #[arg(long, value_delimiter = ',', default_value = "trace,svo")]
    renderers: Vec<String>,
    /// Separate drags timed for the latency.
    #[arg(long, default_value_t = 12)]
    drags: usize,
    /// The screen (and window) size.
    #[arg(long, default_value = "1280x800")]
    size: String,
}

pub fn run(a: WindowBenchArgs) -> Result<(), String> {
    let (w, h) = crate::args::parse_size(&a.size)?;
    let exe = std::env::current_exe().map_err(|e| e.to_string())?;
    let dir = std::env::temp_dir().join(format!("fathom-bench-window-{}", std::process::id()));
    std::fs::create_dir_all(&dir).map_err(|e| format!("{}: {e}", dir.display()))?;
    let mut out = Vec::new();
    for r in &a.renderers {
        let display = Display::start(w, h).map_err(|e| e.to_string())?;
        eprintln!("bench window: {} on {}", r, a.preset);
        out.push(measure(&display, &exe, &dir, &a, r).map_err(|e| format!("{r}: {e}"))?);
    }
    let _ = std::fs::remove_dir_all(&dir);
    let report = json!({
        "preset": a.preset,
        "screen": [w, h],
        "cores": std::thread::available_parallelism().map_or(1, |n| n.get()),
        "renderers": out,
    });
    println!(
        "{}",
        serde_json::to_string_pretty(&report).map_err(|e| e.to_string())?
    );
    Ok(())
}

fn rect(log: &[Value], kind: &str) -> Option<[f64; 4]> {
    let places = log.iter().rev().find_map(|l| l["places"].as_array())?;
    let p = places.iter().find(|p| p["kind"] == kind)?;
    let v: Vec<f64> = p["rect"]
        .as_array()?
        .iter()
        .filter_map(|x| x.as_f64())
        .collect();
    Some([v[0], v[1], v[2], v[3]])
}

fn t_ms(l: &Value) -> f64 {
    l["t_ms"].as_f64().unwrap_or(0.0)
}

fn measure(
    display: &Display,
    exe: &std::path::Path,
    dir: &std::path::Path,
    a: &WindowBenchArgs,
    renderer: &str,
) -> Result<Value, String> {
    let log_path: PathBuf = dir.join(format!("{renderer}.jsonl"));
    let args = ["explore", "--preset", &a.preset, "--renderer", renderer];
    let mut win = Window::launch(display, exe, &args, &log_path).map_err(|e| e.to_string())?;
    let log = win
        .wait_for("a first picture", 300.0, |log| {
            log.iter().any(|l| !l["shown"].is_null()) && rect(log, "viewport").is_some()
        })
        .map_err(|e| e.to_string())?;
    let first = log
        .iter()
        .find(|l| !l["shown"].is_null())
        .expect("waited for");
    let first_picture_ms = t_ms(first) - win.launched_ms;
    let vp = rect(&log, "viewport").expect("waited for");
    let centre = (vp[0] + 0.5 * vp[2], vp[1] + 0.5 * vp[3]);

    // Frames per second while dragging: a 3 s drag, a move every 20 ms.
    let steps: Vec<(f64, f64)> = (0..150)
        .map(|i| {
            if (i / 25) % 2 == 0 {
                (3.0, 1.0)
            } else {
                (-3.0, -1.0)
            }
        })
        .collect();
    let t0 = win.drag(centre, &steps, 20).map_err(|e| e.to_string())?;
    let t1 = now_ms();
    let log = win.frames();
    let during: Vec<&Value> = log.iter().filter(|l| (t0..t1).contains(&t_ms(l))).collect();
    let drag_fps = during.len() as f64 / ((t1 - t0) / 1e3);
    let shown_during = during
        .windows(2)
        .filter(|p| p[0]["shown_view"] != p[1]["shown_view"])
        .count() as f64
        / ((t1 - t0) / 1e3);

    // Latency: separate short drags, each after the view has settled.
    let mut lat = Vec::new();
    for i in 0..a.drags {
        let settled = win
            .wait_for("the view to settle", 120.0, |log| {
                log.last().is_some_and(|l| l["settled"] == true)
            })
            .map_err(|e| e.to_string())?;
        let view = settled.last().expect("settled")["view"].clone();
        std::thread::sleep(std::time::Duration::from_millis(300));
        // Press, let a frame pass, then one motion event of 12 px held until the window shows
        // the moved view (egui sees a drag only across frames, as a hand makes it).
        let dx = if i % 2 == 0 { 12.0 } else { -12.0 };
        win.press(centre).map_err(|e| e.to_string())?;
        std::thread::sleep(std::time::Duration::from_millis(250));
        let t = win
            .move_to((centre.0 + dx, centre.1 + 3.0))
            .map_err(|e| e.to_string())?;
        let log = win
            .wait_for("a frame of the dragged view", 120.0, |log| {
                log.iter()
                    .any(|l| t_ms(l) > t && !l["shown_view"].is_null() && l["shown_view"] != view)
            })
            .map_err(|e| e.to_string());
        win.release().map_err(|e| e.to_string())?;
        let log = log?;
        let shown = log
            .iter()
            .find(|l| t_ms(l) > t && !l["shown_view"].is_null() && l["shown_view"] != view)
            .expect("waited for");
        lat.push(t_ms(shown) - t);
    }
    lat.sort_by(f64::total_cmp);
    let median = lat.get(lat.len() / 2).copied();
    let _ = win.key("ctrl+q");
    let _ = win.wait_exit(10.0);
    Ok(json!({
        "renderer": renderer,
        "launch_to_first_picture_ms": first_picture_ms,
        "window_fps_while_dragging": drag_fps,
        "new_pictures_per_s_while_dragging": shown_during,
        "drag_latency_ms_median": median,
        "drag_latency_ms_max": lat.last(),
        "drag_latency_ms": lat,
    }))
}
