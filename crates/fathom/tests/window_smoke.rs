//! The real window under a virtual X server: `xvfb-run` (installed by scripts/setup.sh) starts
//! Xvfb for the one command and stops it afterwards. The explorer runs 30 frames on the menger
//! preset, logs each and renders its final view to a PNG; the test checks that the window drew
//! frames and that the image is the scene: equal to an offline render of the preset's view
//! within a stated tolerance. A second test runs `fathom` with no arguments on the display and
//! checks that it opened the window (still running after a while, no fathom.png) instead of
//! rendering to a file. A missing xvfb-run fails the tests (scripts/setup.sh installs it).

use fathom_core::presets;
use fathom_core::testing::scratch_dir;
use fathom_render::{RenderRequest, Session};
use std::process::Command;

/// Tolerance: the window's camera is the preset's camera rebuilt from a rotation (its up and
/// target vectors differ in the last bits), so a few edge pixels may flip; the rest agree to
/// rounding. At most this fraction of pixels may differ by more than `LEVELS` in any channel.
const FRACTION: f64 = 0.005;
const LEVELS: u8 = 8;

/// One Xvfb at a time (`xvfb-run -a` picks a free display number, racily).
static SERIAL: std::sync::Mutex<()> = std::sync::Mutex::new(());

/// Fails the test when xvfb-run is missing: a window test that passes without its window
/// tests nothing.
fn require_xvfb_run() {
    let found = Command::new("sh")
        .args(["-c", "command -v xvfb-run"])
        .output()
        .is_ok_and(|o| o.status.success());
    assert!(
        found,
        "xvfb-run is not installed: bash scripts/setup.sh installs xvfb and xauth"
    );
}

#[test]
fn the_window_runs_under_xvfb_and_its_screenshot_is_the_scene() {
    let _serial = SERIAL.lock().unwrap_or_else(|e| e.into_inner());
    require_xvfb_run();
    let dir = scratch_dir("window-smoke");
    let shot = dir.join("shot.png");
    let log = dir.join("frames.jsonl");
    let runtime = dir.join("xdg");
    std::fs::create_dir_all(&runtime).unwrap();
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        std::fs::set_permissions(&runtime, std::fs::Permissions::from_mode(0o700)).unwrap();
    }
    let out = Command::new("xvfb-run")
        .args(["-a", "-s", "-screen 0 1280x800x24"])
        .arg(env!("CARGO_BIN_EXE_fathom"))
        .args([
            "explore",
            "--preset",
            "menger",
            "--frames",
            "30",
            "--screenshot",
        ])
        .arg(&shot)
        .arg("--log")
        .arg(&log)
        .env_remove("WAYLAND_DISPLAY")
        .env("XDG_RUNTIME_DIR", &runtime)
        .output()
        .expect("xvfb-run runs");
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "fathom explore failed: {stderr}");

    // The window ran its 30 frames and showed rendered frames of the scene.
    let lines: Vec<serde_json::Value> = std::fs::read_to_string(&log)
        .unwrap()
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect();
    assert_eq!(lines.len(), 30, "one log line per frame");
    let last = lines.last().unwrap();
    assert!(
        last["shown"].is_array(),
        "no frame reached the viewport in 30 frames: {last}"
    );
    assert!(!last["renderer"].as_str().unwrap().is_empty());

    // The screenshot is the preset's view.
    let img = image::open(&shot).unwrap().to_rgb8();
    let (w, h) = img.dimensions();
    assert!(w >= 64 && h >= 64, "{w}x{h}");
    let scene = presets::load("menger").unwrap();
    let cam = scene.camera.clone();
    let req = RenderRequest {
        width: w,
        height: h,
        ..RenderRequest::default()
    };
    let frame = Session::new(scene)
        .unwrap()
        .render(&cam, &req)
        .unwrap()
        .frame;
    let want = fathom_trace::post::to_rgb8(&frame);
    let got = img.as_raw();
    let bad = got
        .chunks(3)
        .zip(want.chunks(3))
        .filter(|(a, b)| a.iter().zip(b.iter()).any(|(x, y)| x.abs_diff(*y) > LEVELS))
        .count();
    let frac = bad as f64 / (w * h) as f64;
    eprintln!(
        "screenshot {w}x{h}: {bad} pixels ({:.3} %) differ by more than {LEVELS}",
        frac * 100.0
    );
    assert!(frac <= FRACTION, "{bad} of {} pixels differ", w * h);
    // And the view is of the sponge, not of empty sky: it covers a good part of the image.
    let hits = (0..frame.len()).filter(|&i| frame.is_hit(i)).count();
    let coverage = hits as f64 / frame.len() as f64;
    assert!((0.1..0.95).contains(&coverage), "coverage {coverage}");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn fathom_without_arguments_opens_the_window_when_a_display_is_present() {
    let _serial = SERIAL.lock().unwrap_or_else(|e| e.into_inner());
    require_xvfb_run();
    let dir = scratch_dir("no-args-window");
    // `timeout` (coreutils) stops fathom after 10 s, inside xvfb-run, which then stops Xvfb.
    // A window still open then exits 124; had no window opened, fathom would have rendered
    // fathom.png and exited 0 within a second or two.
    let out = Command::new("xvfb-run")
        .args(["-a", "-s", "-screen 0 1280x800x24", "timeout", "10"])
        .arg(env!("CARGO_BIN_EXE_fathom"))
        .current_dir(&dir)
        .env_remove("WAYLAND_DISPLAY")
        .env("XDG_RUNTIME_DIR", &dir)
        .output()
        .expect("xvfb-run runs");
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert_eq!(
        out.status.code(),
        Some(124),
        "fathom ended by itself instead of keeping its window open: {stdout}"
    );
    assert!(!dir.join("fathom.png").exists(), "{stdout}");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn the_real_window_listens_on_its_osc_port_and_logs_what_arrives() {
    let _serial = SERIAL.lock().unwrap_or_else(|e| e.into_inner());
    require_xvfb_run();
    let dir = scratch_dir("window-osc");
    let mut scene = presets::load("sierpinski").unwrap();
    use fathom_core::binding::{Binding, OscInput, Source};
    scene.bindings.push(Binding {
        param: "lights[0].intensity".into(),
        source: Source::Osc(OscInput {
            address: "/smoke/light".into(),
            arg: 0,
            from: (0.0, 1.0),
        }),
        to: (0.2, 1.6),
        smoothing: 0.0,
    });
    let file = dir.join("osc.ron");
    fathom_core::scene_file::save(&file, &scene).unwrap();
    let log = dir.join("frames.jsonl");
    // A free port (released just before fathom binds it).
    let port = std::net::UdpSocket::bind("127.0.0.1:0")
        .unwrap()
        .local_addr()
        .unwrap()
        .port();
    let stop = std::sync::Arc::new(std::sync::atomic::AtomicBool::new(false));
    let stop_in = stop.clone();
    // Sends the value every 20 ms until the window has exited.
    let sender = std::thread::spawn(move || {
        let tx = fathom_live::Sender::new(([127, 0, 0, 1], port).into()).unwrap();
        let mut sent = 0u64;
        while !stop_in.load(std::sync::atomic::Ordering::SeqCst) {
            tx.send("/smoke/light", &[1.0]).unwrap();
            sent += 1;
            std::thread::sleep(std::time::Duration::from_millis(20));
        }
        sent
    });
    let out = Command::new("xvfb-run")
        .args(["-a", "-s", "-screen 0 1280x800x24"])
        .arg(env!("CARGO_BIN_EXE_fathom"))
        .arg("explore")
        .arg(&file)
        .args(["--osc-port", &port.to_string(), "--frames", "40", "--log"])
        .arg(&log)
        .env_remove("WAYLAND_DISPLAY")
        .env("XDG_RUNTIME_DIR", &dir)
        .output()
        .expect("xvfb-run runs");
    stop.store(true, std::sync::atomic::Ordering::SeqCst);
    let sent = sender.join().unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "fathom explore failed: {stderr}");
    let lines: Vec<serde_json::Value> = std::fs::read_to_string(&log)
        .unwrap()
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect();
    assert_eq!(lines.len(), 40, "one log line per frame");
    let last = lines.last().unwrap();
    eprintln!(
        "sent {sent}; last log line: osc {} bound {}",
        last["osc"], last["bound"]
    );
    assert!(last["osc"]["packets"].as_u64().unwrap() > 0, "{last}");
    assert_eq!(last["osc"]["rejected"].as_u64(), Some(0), "{last}");
    assert_eq!(last["bound"][0]["param"], "lights[0].intensity");
    assert_eq!(last["bound"][0]["value"].as_f64(), Some(1.6), "{last}");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn an_osc_port_in_use_stops_fathom_explore_before_its_window_with_the_port_named() {
    let taken = std::net::UdpSocket::bind("127.0.0.1:0").unwrap();
    let port = taken.local_addr().unwrap().port();
    let out = Command::new(env!("CARGO_BIN_EXE_fathom"))
        .args([
            "explore",
            "--preset",
            "sierpinski",
            "--osc-port",
            &port.to_string(),
        ])
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success());
    assert!(stderr.contains(&format!("127.0.0.1:{port}")), "{stderr}");
    assert!(!stderr.contains("panicked"), "{stderr}");
}
