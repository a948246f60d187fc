//! fathom-xdrive: the explorer as a user meets it, for tests and benchmarks. egui's test
//! harness calls the app directly and never goes through eframe, winit and the X server, so a
//! bug in how the window reads its input (a lock taken twice, a widget stealing a click)
//! passes it. This crate drives the *shipped binary* in a real window instead:
//!
//! - [`Display`]: a virtual X server (`Xvfb`) of its own, started with `-displayfd` so it picks
//!   a free display number, and stopped by the PID it was started with;
//! - [`Window`]: `fathom explore ... --log FILE` on that display, real X input through
//!   `xdotool` (clicks, drags, keys), the window's own per-frame log read back as JSON, and
//!   captures of what the screen shows (`import` from ImageMagick), never an offline render.
//!
//! The tools are Debian's `xvfb`, `xdotool` and `imagemagick`; `scripts/setup.sh` installs
//! them. A missing tool is an error, never a skipped test.
//!
//! ```no_run
//! use fathom_xdrive::{Display, Window};
//! let display = Display::start(1280, 800)?;
//! let mut w = Window::launch(&display, "target/release/fathom".as_ref(),
//!     &["explore", "--preset", "menger"], "/tmp/frames.jsonl".as_ref())?;
//! w.wait_for("a first picture", 60.0, |log| log.iter().any(|l| !l["shown"].is_null()))?;
//! w.drag((640.0, 400.0), &[(10.0, 0.0); 6], 30)?;
//! # Ok::<(), fathom_xdrive::XError>(())
//! ```

#![warn(missing_docs)]

use serde_json::Value;
use std::io::{BufRead, BufReader, Read};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant, SystemTime, UNIX_EPOCH};

/// What went wrong while driving the window.
#[derive(Debug, thiserror::Error)]
pub enum XError {
    /// A tool could not be started (not installed?).
    #[error(
        "cannot run `{program}`: {source} (bash scripts/setup.sh installs xvfb, xdotool and imagemagick)"
    )]
    Spawn {
        /// The program.
        program: String,
        /// Why.
        source: std::io::Error,
    },
    /// A tool ran and failed.
    #[error("`{command}` failed ({status}): {stderr}")]
    Failed {
        /// The command line.
        command: String,
        /// Its exit status.
        status: String,
        /// What it printed on standard error.
        stderr: String,
    },
    /// Something awaited did not happen in time.
    #[error("timed out after {seconds} s waiting for {what}{}", last.as_ref().map(|l| format!("; last frame log line: {l}")).unwrap_or_default())]
    Timeout {
        /// What was awaited.
        what: String,
        /// How long.
        seconds: f64,
        /// The window's last log line, if any.
        last: Option<String>,
    },
    /// The window's process ended while it was being driven.
    #[error("the window exited ({status}) while waiting for {what}; its stderr: {stderr}")]
    Exited {
        /// What was awaited.
        what: String,
        /// Its exit status.
        status: String,
        /// What it printed on standard error.
        stderr: String,
    },
    /// A file could not be read or written.
    #[error("{path}: {source}")]
    Io {
        /// The file.
        path: PathBuf,
        /// Why.
        source: std::io::Error,
    },
}

/// Wall-clock time in milliseconds since the Unix epoch: the clock the window's frame log
/// stamps its lines with (`t_ms`), so an X event sent here and the frame that shows it can be
/// put on one time line.
pub fn now_ms() -> f64 {
    SystemTime::now()
        .duration_since(UNIX_EPOCH)
        .map(|d| d.as_secs_f64() * 1e3)
        .unwrap_or(0.0)
}

fn spawn_err(program: &str) -> impl FnOnce(std::io::Error) -> XError + '_ {
    move |source| XError::Spawn {
        program: program.into(),
        source,
    }
}

/// A virtual X server of our own, stopped (by its PID) when dropped.
pub struct Display {
    xvfb: Child,
    /// The display's name, `:N`.
    pub name: String,
    /// Its size in pixels.
    pub size: (u32, u32),
}

impl Display {
    /// Starts `Xvfb` on a free display of `width` x `height` pixels (24-bit) and waits until
    /// it accepts clients.
    pub fn start(width: u32, height: u32) -> Result<Display, XError> {
        let mut xvfb = Command::new("Xvfb")
            // -noreset: by default an X server resets when its last client leaves, and a
            // client connecting during the reset (the window, just after a probe) is refused.
            .args([
                "-displayfd",
                "1",
                "-noreset",
                "-nolisten",
                "tcp",
                "-screen",
                "0",
            ])
            .arg(format!("{width}x{height}x24"))
            .stdin(Stdio::null())
            .stdout(Stdio::piped())
            .stderr(Stdio::null())
            .spawn()
            .map_err(spawn_err("Xvfb"))?;
        // Xvfb writes the display number it chose once it is ready for clients.
        let out = xvfb.stdout.take().expect("piped");
        let (tx, rx) = std::sync::mpsc::channel();
        std::thread::spawn(move || {
            let mut line = String::new();
            let _ = BufReader::new(out).read_line(&mut line);
            let _ = tx.send(line);
        });
        let line = match rx.recv_timeout(Duration::from_secs(20)) {
            Ok(l) if !l.trim().is_empty() => l,
            _ => {
                let _ = xvfb.kill();
                let _ = xvfb.wait();
                return Err(XError::Timeout {
                    what: "Xvfb to start".into(),
                    seconds: 20.0,
                    last: None,
                });
            }
        };
        let d = Display {
            xvfb,
            name: format!(":{}", line.trim()),
            size: (width, height),
        };
        // Ready for clients once a client gets through.
        let t0 = Instant::now();
        while d.xdotool(&["getdisplaygeometry"]).is_err() {
            if t0.elapsed() > Duration::from_secs(20) {
                return Err(XError::Timeout {
                    what: format!("Xvfb on {} to accept clients", d.name),
                    seconds: 20.0,
                    last: None,
                });
            }
            std::thread::sleep(Duration::from_millis(50));
        }
        Ok(d)
    }

    /// The PID of the X server this display was started as.
    pub fn pid(&self) -> u32 {
        self.xvfb.id()
    }

    /// Runs `xdotool ARGS` on this display; returns its standard output.
    pub fn xdotool(&self, args: &[&str]) -> Result<String, XError> {
        run(Command::new("xdotool")
            .args(args)
            .env("DISPLAY", &self.name))
    }

    /// Writes what the whole screen shows now to `path` (PNG), through ImageMagick's
    /// `import`: the pixels the X server has, as a user would see them.
    pub fn capture(&self, path: &Path) -> Result<(), XError> {
        run(Command::new("import")
            .args(["-window", "root"])
            .arg(format!("png:{}", path.display()))
            .env("DISPLAY", &self.name))
        .map(|_| ())
    }
}

/// Stops `child`: SIGTERM (so an X server removes its lock and socket), then SIGKILL if it
/// has not exited within two seconds.
fn stop(child: &mut Child) {
    if matches!(child.try_wait(), Ok(Some(_))) {
        return;
    }
    let _ = Command::new("kill")
        .args(["-TERM", &child.id().to_string()])
        .status();
    let t0 = Instant::now();
    while t0.elapsed() < Duration::from_secs(2) {
        if matches!(child.try_wait(), Ok(Some(_))) {
            return;
        }
        std::thread::sleep(Duration::from_millis(20));
    }
    let _ = child.kill();
    let _ = child.wait();
}

impl Drop for Display {
    fn drop(&mut self) {
        stop(&mut self.xvfb);
    }
}

fn run(cmd: &mut Command) -> Result<String, XError> {
    let program = cmd.get_program().to_string_lossy().into_owned();
    let out = cmd
        .stdin(Stdio::null())
        .output()
        .map_err(spawn_err(&program))?;
    if !out.status.success() {
        return Err(XError::Failed {
            command: format!(
                "{program} {}",
                cmd.get_args()
                    .map(|a| a.to_string_lossy().into_owned())
                    .collect::<Vec<_>>()
                    .join(" ")
            ),
            status: out.status.to_string(),
            stderr: String::from_utf8_lossy(&out.stderr).into_owned(),
        });
    }
    Ok(String::from_utf8_lossy(&out.stdout).into_owned())
}

/// The explorer running in a real window on a [`Display`], killed (by PID) when dropped.
pub struct Window<'d> {
    display: &'d Display,
    child: Child,
    /// The X window id.
    pub wid: String,
    /// The frame log the window writes (`--log`).
    pub log: PathBuf,
    /// When the process was started ([`now_ms`]).
    pub launched_ms: f64,
    /// The window's position on the screen, pixels.
    pub origin: (f64, f64),
    stderr: PathBuf,
}

impl<'d> Window<'d> {
    /// Starts `fathom ARGS --log LOG` on `display`, in the log's directory (files the window
    /// writes by relative name, such as F12's screenshots, land there), and waits (up to 60 s)
    /// for its window to be mapped; gives it the keyboard focus.
    pub fn launch(
        display: &'d Display,
        fathom: &Path,
        args: &[&str],
        log: &Path,
    ) -> Result<Window<'d>, XError> {
        let _ = std::fs::remove_file(log);
        let stderr = log.with_extension("stderr.txt");
        let err_file = std::fs::File::create(&stderr).map_err(|source| XError::Io {
            path: stderr.clone(),
            source,
        })?;
        let runtime = log.with_extension("xdg");
        std::fs::create_dir_all(&runtime).map_err(|source| XError::Io {
            path: runtime.clone(),
            source,
        })?;
        #[cfg(unix)]
        {
            use std::os::unix::fs::PermissionsExt;
            let _ = std::fs::set_permissions(&runtime, std::fs::Permissions::from_mode(0o700));
        }
        let launched_ms = now_ms();
        let child = Command::new(fathom)
            .args(args)
            .arg("--log")
            .arg(log)
            .env("DISPLAY", &display.name)
            .env_remove("WAYLAND_DISPLAY")
            .env("XDG_RUNTIME_DIR", &runtime)
            .current_dir(log.parent().unwrap_or(Path::new(".")))
            .stdin(Stdio::null())
            .stdout(Stdio::null())
            .stderr(err_file)
            .spawn()
            .map_err(spawn_err("fathom"))?;
        let mut w = Window {
            display,
            child,
            wid: String::new(),
            log: log.to_path_buf(),
            launched_ms,
            origin: (0.0, 0.0),
            stderr,
        };
        let t0 = Instant::now();
        loop {
            if let Ok(out) = display.xdotool(&["search", "--onlyvisible", "--name", "^fathom"])
                && let Some(id) = out.lines().next()
            {
                w.wid = id.trim().to_string();
                break;
            }
            w.check_alive("its window to appear")?;
            if t0.elapsed() > Duration::from_secs(60) {
                return Err(XError::Timeout {
                    what: "the window to appear".into(),
                    seconds: 60.0,
                    last: None,
                });
            }
            std::thread::sleep(Duration::from_millis(100));
        }
        let geo = display.xdotool(&["getwindowgeometry", "--shell", &w.wid])?;
        let field = |k: &str| {
            geo.lines()
                .find_map(|l| l.strip_prefix(k))
                .and_then(|v| v.trim().parse::<f64>().ok())
                .unwrap_or(0.0)
        };
        w.origin = (field("X="), field("Y="));
        display.xdotool(&["windowfocus", "--sync", &w.wid])?;
        Ok(w)
    }

    /// The PID of the window's process.
    pub fn pid(&self) -> u32 {
        self.child.id()
    }

    /// Whether the process still runs.
    pub fn running(&mut self) -> bool {
        matches!(self.child.try_wait(), Ok(None))
    }

    /// Waits up to `seconds` for the process to exit; its exit status, if it did.
    pub fn wait_exit(&mut self, seconds: f64) -> Option<std::process::ExitStatus> {
        let t0 = Instant::now();
        loop {
            if let Ok(Some(s)) = self.child.try_wait() {
                return Some(s);
            }
            if t0.elapsed().as_secs_f64() > seconds {
                return None;
            }
            std::thread::sleep(Duration::from_millis(50));
        }
    }

    /// What the window printed on standard error so far.
    pub fn stderr(&self) -> String {
        std::fs::read_to_string(&self.stderr).unwrap_or_default()
    }

    fn check_alive(&mut self, what: &str) -> Result<(), XError> {
        if let Ok(Some(status)) = self.child.try_wait() {
            return Err(XError::Exited {
                what: what.into(),
                status: status.to_string(),
                stderr: self.stderr(),
            });
        }
        Ok(())
    }

    /// Every complete line of the frame log so far, parsed.
    pub fn frames(&self) -> Vec<Value> {
        let mut text = String::new();
        if let Ok(mut f) = std::fs::File::open(&self.log) {
            let _ = f.read_to_string(&mut text);
        }
        // The last line may still be being written: only lines ended by a newline count.
        let complete = text.rfind('\n').map_or("", |i| &text[..i]);
        complete
            .lines()
            .filter_map(|l| serde_json::from_str(l).ok())
            .collect()
    }

    /// Waits up to `seconds` until `done` holds for the frame log; returns the log then.
    pub fn wait_for(
        &mut self,
        what: &str,
        seconds: f64,
        done: impl Fn(&[Value]) -> bool,
    ) -> Result<Vec<Value>, XError> {
        let t0 = Instant::now();
        loop {
            let log = self.frames();
            if done(&log) {
                return Ok(log);
            }
            self.check_alive(what)?;
            if t0.elapsed().as_secs_f64() > seconds {
                return Err(XError::Timeout {
                    what: what.into(),
                    seconds,
                    last: log.last().map(|l| l.to_string()),
                });
            }
            std::thread::sleep(Duration::from_millis(20));
        }
    }

    /// Screen coordinates of a point given in window pixels.
    pub fn screen(&self, (x, y): (f64, f64)) -> (i64, i64) {
        (
            (self.origin.0 + x).round() as i64,
            (self.origin.1 + y).round() as i64,
        )
    }

    /// Runs `xdotool ARGS` on the window's display.
    pub fn xdotool(&self, args: &[&str]) -> Result<String, XError> {
        self.display.xdotool(args)
    }

    /// Moves the pointer to `at` (window pixels) without pressing anything.
    pub fn hover(&self, at: (f64, f64)) -> Result<(), XError> {
        let (x, y) = self.screen(at);
        self.xdotool(&["mousemove", &x.to_string(), &y.to_string()])
            .map(|_| ())
    }

    /// A left click at `at` (window pixels): move there, press, release, as separate X
    /// events a few milliseconds apart, the way a hand clicks.
    pub fn click(&self, at: (f64, f64)) -> Result<(), XError> {
        self.hover(at)?;
        std::thread::sleep(Duration::from_millis(60));
        self.xdotool(&["mousedown", "1"])?;
        std::thread::sleep(Duration::from_millis(40));
        self.xdotool(&["mouseup", "1"]).map(|_| ())
    }

    /// Presses the left button at `at` (window pixels), for gestures that wait on the window
    /// between their events ([`Window::move_to`], [`Window::release`]).
    pub fn press(&self, at: (f64, f64)) -> Result<(), XError> {
        self.hover(at)?;
        std::thread::sleep(Duration::from_millis(40));
        self.xdotool(&["mousedown", "1"]).map(|_| ())
    }

    /// Moves the pointer to `at` (window pixels); returns the time of the X event
    /// ([`now_ms`]).
    pub fn move_to(&self, at: (f64, f64)) -> Result<f64, XError> {
        let (x, y) = self.screen(at);
        let t = now_ms();
        self.xdotool(&["mousemove", &x.to_string(), &y.to_string()])?;
        Ok(t)
    }

    /// Releases the left button.
    pub fn release(&self) -> Result<(), XError> {
        self.xdotool(&["mouseup", "1"]).map(|_| ())
    }

    /// A left-button drag: press at `from` (window pixels), move by each of `steps` (pixels)
    /// with `step_ms` between moves, release. Returns the time of the first move
    /// ([`now_ms`]).
    pub fn drag(
        &self,
        from: (f64, f64),
        steps: &[(f64, f64)],
        step_ms: u64,
    ) -> Result<f64, XError> {
        self.hover(from)?;
        std::thread::sleep(Duration::from_millis(40));
        self.xdotool(&["mousedown", "1"])?;
        std::thread::sleep(Duration::from_millis(step_ms));
        let mut first = None;
        let mut at = from;
        for &(dx, dy) in steps {
            at = (at.0 + dx, at.1 + dy);
            let (x, y) = self.screen(at);
            first.get_or_insert_with(now_ms);
            self.xdotool(&["mousemove", &x.to_string(), &y.to_string()])?;
            std::thread::sleep(Duration::from_millis(step_ms));
        }
        self.xdotool(&["mouseup", "1"])?;
        Ok(first.unwrap_or_else(now_ms))
    }

    /// Gives the window the keyboard focus. There is no window manager on the display to do
    /// it on a click, as a desktop would, so every key press asks for it first.
    pub fn focus(&self) -> Result<(), XError> {
        self.xdotool(&["windowfocus", "--sync", &self.wid])
            .map(|_| ())
    }

    /// Presses and releases a key or chord (`ctrl+z`, `F12`, `w`), xdotool's names.
    pub fn key(&self, keys: &str) -> Result<(), XError> {
        self.focus()?;
        self.xdotool(&["key", "--clearmodifiers", keys]).map(|_| ())
    }

    /// Holds `key` down for `ms` milliseconds.
    pub fn hold(&self, key: &str, ms: u64) -> Result<(), XError> {
        self.focus()?;
        self.xdotool(&["keydown", key])?;
        std::thread::sleep(Duration::from_millis(ms));
        self.xdotool(&["keyup", key]).map(|_| ())
    }

    /// Captures the screen (the window and anything over it) to `path`.
    pub fn capture(&self, path: &Path) -> Result<(), XError> {
        self.display.capture(path)
    }
}

impl Drop for Window<'_> {
    fn drop(&mut self) {
        stop(&mut self.child);
    }
}
