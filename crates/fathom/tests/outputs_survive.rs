//! Nothing lost: a command that is refused, fails or is interrupted (Ctrl-C, SIGTERM) leaves
//! an existing output byte for byte as it was, and no temporary or spool (`.part`) file
//! behind (fathom_core::atomic_file and fathom_core::cleanup, with the binary's Ctrl-C
//! handler). Each case runs the real `fathom` binary.

use fathom_core::testing::{file_names, scratch_dir};
use std::path::Path;
use std::process::{Command, ExitStatus, Stdio};
use std::time::{Duration, Instant};

fn fathom() -> Command {
    Command::new(env!("CARGO_BIN_EXE_fathom"))
}

/// Whether a name is a temporary output or a spool file.
fn is_temporary(name: &str) -> bool {
    fathom_core::atomic_file::is_temp_name(name) || name.ends_with(".part")
}

/// Starts `cmd`, waits until a temporary file shows up in `dir` (the work is under way), then
/// sends `signal` and waits for the exit.
fn interrupt(mut cmd: Command, dir: &Path, signal: &str) -> ExitStatus {
    let mut child = cmd
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let start = Instant::now();
    while !file_names(dir).iter().any(|n| is_temporary(n)) {
        if let Some(s) = child.try_wait().unwrap() {
            let mut err = String::new();
            use std::io::Read;
            child.stderr.take().unwrap().read_to_string(&mut err).ok();
            panic!("the command ended ({s}) before it was interrupted: {err}");
        }
        assert!(
            start.elapsed() < Duration::from_secs(120),
            "no temporary file"
        );
        std::thread::sleep(Duration::from_millis(20));
    }
    // Let it write a little more.
    std::thread::sleep(Duration::from_millis(300));
    let ok = Command::new("kill")
        .args([signal, &child.id().to_string()])
        .status()
        .unwrap();
    assert!(ok.success());
    child.wait().unwrap()
}

/// Writes distinct old contents to each of `files` in `dir`.
fn old_files(dir: &Path, files: &[&str]) -> Vec<Vec<u8>> {
    files
        .iter()
        .map(|f| {
            let b = format!("the old {f}, which must survive").into_bytes();
            std::fs::write(dir.join(f), &b).unwrap();
            b
        })
        .collect()
}

fn assert_intact(dir: &Path, files: &[&str], old: &[Vec<u8>], what: &str) {
    for (f, b) in files.iter().zip(old) {
        assert_eq!(
            &std::fs::read(dir.join(f)).unwrap(),
            b,
            "{what}: {f} changed"
        );
    }
    let left: Vec<String> = file_names(dir)
        .into_iter()
        .filter(|n| is_temporary(n))
        .collect();
    assert!(left.is_empty(), "{what}: left behind {left:?}");
}

#[test]
fn an_interrupted_render_keeps_its_image_and_stats() {
    let dir = scratch_dir("survive-render");
    let files = ["out.png", "stats.json"];
    let old = old_files(&dir, &files);
    let mut cmd = fathom();
    cmd.args([
        "render",
        "--preset",
        "mandelbulb",
        "--size",
        "4096x4096",
        "--threads",
        "1",
        "-q",
        "-o",
    ])
    .arg(dir.join("out.png"))
    .arg("--stats")
    .arg(dir.join("stats.json"));
    let status = interrupt(cmd, &dir, "-INT");
    assert_eq!(status.code(), Some(130), "{status}");
    assert_intact(&dir, &files, &old, "render after SIGINT");
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn an_interrupted_mesh_keeps_its_output_and_removes_its_spools() {
    for (signal, ext) in [("-INT", "ply"), ("-TERM", "glb")] {
        let dir = scratch_dir(&format!("survive-mesh-{ext}"));
        let out = format!("m.{ext}");
        let files = [out.as_str()];
        let old = old_files(&dir, &files);
        let mut cmd = fathom();
        cmd.args([
            "mesh",
            "--preset",
            "mandelbulb",
            "--resolution",
            "2048",
            "--threads",
            "1",
            "-q",
            "-o",
        ])
        .arg(dir.join(&out));
        let status = interrupt(cmd, &dir, signal);
        assert_eq!(status.code(), Some(130), "{signal}: {status}");
        assert_intact(&dir, &files, &old, &format!("mesh after {signal}"));
        std::fs::remove_dir_all(&dir).ok();
    }
}

#[test]
fn an_interrupted_volume_keeps_its_image() {
    let dir = scratch_dir("survive-volume");
    let files = ["v.png"];
    let old = old_files(&dir, &files);
    let mut cmd = fathom();
    cmd.args([
        "volume",
        "--preset",
        "menger",
        "--grid",
        "32",
        "--spp",
        "1000000",
        "--size",
        "256x256",
        "--threads",
        "1",
        "-q",
        "-o",
    ])
    .arg(dir.join("v.png"));
    // The image's temporary file is only created at the end: wait for the probe instead.
    let mut child = cmd
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    std::thread::sleep(Duration::from_millis(1500));
    assert!(child.try_wait().unwrap().is_none(), "volume ended early");
    Command::new("kill")
        .args(["-INT", &child.id().to_string()])
        .status()
        .unwrap();
    assert_eq!(child.wait().unwrap().code(), Some(130));
    assert_intact(&dir, &files, &old, "volume after SIGINT");
    std::fs::remove_dir_all(&dir).ok();
}

/// Runs `fathom ARGS` (with `{dir}` replaced), which must fail, and checks the outputs named
/// `files` are untouched and nothing temporary is left.
fn refused(dir: &Path, files: &[&str], args: &[&str], says: &str) {
    let old = old_files(dir, files);
    let args: Vec<String> = args
        .iter()
        .map(|a| a.replace("{dir}", &dir.display().to_string()))
        .collect();
    let out = fathom().args(&args).output().unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success(), "{args:?} succeeded");
    assert!(err.contains(says), "{args:?}: {err}");
    assert_intact(dir, files, &old, &format!("{args:?}"));
}

#[test]
fn refused_and_failed_commands_keep_existing_outputs() {
    let dir = scratch_dir("survive-refused");
    std::fs::write(dir.join("empty.obj"), "# nothing\n").unwrap();
    let mut nan = b"VOL\x03\x01\0\0\0\x01\0\0\0\x01\0\0\0\x01\0\0\0\x01\0\0\0".to_vec();
    for v in [0.0f32, 0.0, 0.0, 1.0, 1.0, 1.0, f32::NAN] {
        nan.extend_from_slice(&v.to_le_bytes());
    }
    std::fs::write(dir.join("nan.vol"), nan).unwrap();
    let cases: &[(&[&str], &[&str], &str)] = &[
        (
            &["v.png"],
            &[
                "volume",
                "--grid",
                "{dir}/missing.vol",
                "-q",
                "-o",
                "{dir}/v.png",
            ],
            "missing.vol",
        ),
        (
            &["v.png"],
            &[
                "volume",
                "--grid",
                "{dir}/nan.vol",
                "-q",
                "-o",
                "{dir}/v.png",
            ],
            "NaN",
        ),
        (
            &["v.png", "g.png"],
            &[
                "volume",
                "--preset",
                "menger",
                "--grid",
                "8",
                "-q",
                "-o",
                "{dir}/v.png",
                "--export",
                "{dir}/g.png",
            ],
            "unknown grid format",
        ),
        (
            &["v.bmp"],
            &["volume", "--preset", "menger", "-q", "-o", "{dir}/v.bmp"],
            ".png",
        ),
        (
            &["t.png"],
            &["micro", "{dir}/empty.obj", "-q", "-o", "{dir}/t.png"],
            "empty.obj",
        ),
        (
            &["m.stl"],
            &[
                "mesh",
                "--preset",
                "menger",
                "--max-memory",
                "1K",
                "-q",
                "-o",
                "{dir}/m.stl",
            ],
            "--max-memory",
        ),
        (
            &["m.stl"],
            &[
                "mesh",
                "--preset",
                "menger",
                "--bounds",
                "1,1,1,0,0,0",
                "-q",
                "-o",
                "{dir}/m.stl",
            ],
            "bounds",
        ),
        (
            &["m.stl"],
            &[
                "mesh",
                "--preset",
                "menger",
                "--resolution",
                "1000000",
                "-q",
                "-o",
                "{dir}/m.stl",
            ],
            "--resolution",
        ),
    ];
    for (files, args, says) in cases {
        refused(&dir, files, args, says);
    }
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn outputs_are_checked_before_the_work() {
    let dir = scratch_dir("survive-checked");
    let t = Instant::now();
    // A zoom's stats into a missing directory fails before any frame.
    let out = fathom()
        .args([
            "zoom", "--preset", "menger", "--frames", "100000", "--stats",
        ])
        .arg(dir.join("missing/z.json"))
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        !out.status.success() && err.contains("does not exist"),
        "{err}"
    );
    // A zoom's frame directory is made, but not its missing parents.
    let out = fathom()
        .args(["zoom", "--preset", "menger", "--frames", "100000", "-o"])
        .arg(dir.join("typo/frames"))
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        !out.status.success() && err.contains("does not exist"),
        "{err}"
    );
    assert!(!dir.join("typo").exists());
    assert!(t.elapsed() < Duration::from_secs(30), "{:?}", t.elapsed());
    std::fs::remove_dir_all(&dir).ok();
}
