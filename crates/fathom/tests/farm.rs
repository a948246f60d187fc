//! `fathom farm` end to end through the binary, without a scheduler: a local array (`farm
//! run`: the same `farm work` processes a Slurm array runs) renders a tiled still that must
//! equal a single-process render byte for byte, then resumes after units are lost or
//! damaged, rendering only those; the refusals explain themselves. The same flow on a real
//! Slurm cluster is scripts/farm-slurm-test.sh.

use fathom_core::testing::scratch_dir;
use std::collections::BTreeSet;
use std::path::Path;
use std::process::{Command, Output};

fn fathom(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_fathom"))
        .args(args)
        .env_remove("SLURM_ARRAY_TASK_ID")
        .env_remove("SLURM_ARRAY_TASK_COUNT")
        .output()
        .unwrap()
}

fn ok(args: &[&str]) -> String {
    let o = fathom(args);
    assert!(
        o.status.success(),
        "fathom {args:?} failed: {}",
        String::from_utf8_lossy(&o.stderr)
    );
    String::from_utf8_lossy(&o.stdout).into_owned()
}

fn err(args: &[&str]) -> String {
    let o = fathom(args);
    assert!(!o.status.success(), "fathom {args:?} should fail");
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// Units rendered according to the local tasks' logs.
fn rendered(dir: &Path) -> Vec<String> {
    let mut v = Vec::new();
    for e in std::fs::read_dir(dir.join("logs")).unwrap() {
        let text = std::fs::read_to_string(e.unwrap().path()).unwrap();
        for line in text.lines() {
            if let Some(rest) = line.split("rendered ").nth(1) {
                v.push(rest.split(' ').next().unwrap().to_string());
            }
        }
    }
    v.sort();
    v
}

#[test]
fn a_local_array_renders_a_still_identical_to_one_process_and_resumes_only_what_failed() {
    let d = scratch_dir("farm-cli-still");
    let s = |p: &str| d.join(p).to_str().unwrap().to_string();
    let common = ["--preset", "menger", "--size", "160x120"];
    ok(&[
        &["render", "-q", "--threads", "1", "-o", &s("ref.png")],
        &common[..],
    ]
    .concat());
    // The job and its array script, not submitted.
    ok(&[
        &[
            "farm",
            "slurm",
            "-q",
            "--tiles",
            "16",
            "--tasks",
            "8",
            "-o",
            &s("job"),
        ],
        &common[..],
    ]
    .concat());
    let script = std::fs::read_to_string(d.join("job/farm.sbatch")).unwrap();
    assert!(script.contains("#SBATCH --array=0-7\n"), "{script}");
    assert!(
        script.contains("--shard \"$SLURM_ARRAY_TASK_ID/8\""),
        "{script}"
    );
    ok(&["farm", "run", &s("job"), "--tasks", "8", "--parallel", "2"]);
    let first = rendered(&d.join("job"));
    assert_eq!(first.len(), 16, "{first:?}");
    assert_eq!(first.iter().collect::<BTreeSet<_>>().len(), 16);
    ok(&["farm", "assemble", &s("job"), "-o", &s("farm.png")]);
    assert!(
        std::fs::read(d.join("farm.png")).unwrap() == std::fs::read(d.join("ref.png")).unwrap(),
        "the assembled still differs from the single-process render"
    );

    // Two tiles were lost and one was truncated.
    for t in ["tile-00003.png", "tile-00011.png"] {
        std::fs::remove_file(d.join("job").join(t)).unwrap();
    }
    let t5 = d.join("job/tile-00005.png");
    let b = std::fs::read(&t5).unwrap();
    std::fs::write(&t5, &b[..b.len() / 2]).unwrap();
    let st = ok(&["farm", "status", &s("job")]);
    assert!(st.contains("13 done, 2 missing, 1 corrupt"), "{st}");
    let e = err(&["farm", "assemble", &s("job"), "-o", &s("bad.png")]);
    assert!(
        e.contains("3 of 16 units are not done") && e.contains("tile-00005.png corrupt"),
        "{e}"
    );
    assert!(!d.join("bad.png").exists());
    // Resume: only those three are rendered.
    std::fs::remove_dir_all(d.join("job/logs")).unwrap();
    ok(&["farm", "run", &s("job"), "--tasks", "8", "--parallel", "2"]);
    assert_eq!(
        rendered(&d.join("job")),
        ["tile-00003.png", "tile-00005.png", "tile-00011.png"]
    );
    ok(&["farm", "assemble", &s("job"), "-o", &s("farm2.png")]);
    assert!(
        std::fs::read(d.join("farm2.png")).unwrap() == std::fs::read(d.join("ref.png")).unwrap()
    );
    std::fs::remove_dir_all(&d).ok();
}

#[test]
fn farm_refusals_explain_themselves() {
    let d = scratch_dir("farm-cli-refuse");
    let s = |p: &str| d.join(p).to_str().unwrap().to_string();
    let job = s("job");
    let still = [
        "render", "-q", "--preset", "menger", "--size", "64x48", "--tiles", "4",
    ];
    let e = err(&[&still[..], &["--shard", "4/4", "-o", &job]].concat());
    assert!(e.contains("shard 4/4 is out of range"), "{e}");
    let e = err(&[&still[..], &["--shard", "x", "-o", &job]].concat());
    assert!(e.contains("should look like I/N"), "{e}");
    let e = err(&[&still[..], &["--shard", "-o", &job]].concat());
    assert!(e.contains("SLURM_ARRAY_TASK_ID"), "{e}");
    let e = err(&[&still[..], &["-o", &s("x.png")]].concat());
    assert!(e.contains("looks like a file"), "{e}");
    ok(&[&still[..], &["--shard", "1/2", "-o", &job]].concat());
    // The same directory for another job (another size) is refused.
    let e = err(&[
        "render", "-q", "--preset", "menger", "--size", "64x40", "--tiles", "4", "-o", &job,
    ]);
    assert!(
        e.contains("different job") && e.contains("render request"),
        "{e}"
    );
    let e = err(&["farm", "status", &s("nothing")]);
    assert!(e.contains("not a farm directory"), "{e}");
    let e = err(&[
        "render",
        "-q",
        "--preset",
        "menger",
        "--tiles",
        "100000",
        "--size",
        "64x48",
        "-o",
        &s("j2"),
    ]);
    assert!(e.contains("--tiles 100000"), "{e}");
    std::fs::remove_dir_all(&d).ok();
}

#[test]
fn zoom_and_path_shards_write_frames_that_assemble() {
    let d = scratch_dir("farm-cli-frames");
    let s = |p: &str| d.join(p).to_str().unwrap().to_string();
    for i in 0..2 {
        ok(&[
            "zoom",
            "--preset",
            "menger",
            "--depth",
            "10",
            "--frames",
            "3",
            "--size",
            "32x24",
            "--threads",
            "1",
            "--max-memory",
            "64M",
            "--shard",
            &format!("{i}/2"),
            "-o",
            &s("zoom"),
        ]);
    }
    let st = ok(&["farm", "status", &s("zoom")]);
    assert!(st.contains("3 done, 0 missing"), "{st}");
    let dive =
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../../docs/examples/mandelbulb-dive.ron");
    ok(&[
        "render",
        dive.to_str().unwrap(),
        "-q",
        "--path",
        "dive",
        "--frames",
        "3",
        "--size",
        "32x24",
        "--threads",
        "1",
        "--shard",
        "0/1",
        "-o",
        &s("path"),
    ]);
    ok(&["farm", "assemble", &s("path"), "-o", &s("path.mp4")]);
    assert!(std::fs::metadata(d.join("path.mp4")).unwrap().len() > 0);
    std::fs::remove_dir_all(&d).ok();
}
