//! The farm's bookkeeping with a counting fake renderer (reruns, corrupt and foreign files,
//! refusals), and the real renderer against the single-process renders it must equal.

use crate::assemble::{Assembled, assemble};
use crate::manifest::{FarmDir, Fingerprint, RECEIPTS, UnitState};
use crate::render::{SessionRenderer, encode_frame};
use crate::run::{Event, UnitRenderer, run_shard};
use crate::{FarmError, Shard, Unit, Work};
use fathom_render::{Control, RenderRequest, Session};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

fn scratch(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("fathom-farm-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    d
}

/// Writes each unit's index as text and counts how often each unit was rendered.
#[derive(Default)]
struct Counting {
    renders: BTreeMap<usize, u32>,
}

impl UnitRenderer for Counting {
    fn render(&mut self, unit: &Unit) -> Result<Vec<u8>, FarmError> {
        *self.renders.entry(unit.index).or_default() += 1;
        Ok(format!("unit {} of the fake job\n", unit.index).into_bytes())
    }
}

fn small_request() -> RenderRequest {
    RenderRequest {
        width: 64,
        height: 48,
        threads: Some(1),
        ..RenderRequest::default()
    }
}

/// The fingerprint of `fake_job(_, "scene A", 4)`.
fn fake_fingerprint() -> Fingerprint {
    let req = small_request();
    Fingerprint::new(
        "scene A",
        &req,
        Work::tiles(4, req.width, req.height).unwrap(),
    )
    .unwrap()
}

fn fake_job(dir: &Path, scene: &str, tiles: usize) -> Result<FarmDir, FarmError> {
    let req = small_request();
    let work = Work::tiles(tiles, req.width, req.height)?;
    FarmDir::create(dir, Fingerprint::new(scene, &req, work)?, scene)
}

fn run_all(farm: &FarmDir, n: usize, r: &mut Counting) -> Vec<crate::ShardReport> {
    (0..n)
        .map(|i| run_shard(farm, Shard::new(i, n).unwrap(), r, &mut |_| {}).unwrap())
        .collect()
}

#[test]
fn a_rerun_skips_done_units_and_renders_missing_and_corrupt_ones_once() {
    let dir = scratch("rerun");
    let farm = fake_job(&dir, "scene A", 8).unwrap();
    let mut r = Counting::default();
    let first = run_all(&farm, 3, &mut r);
    assert_eq!(first.iter().map(|s| s.rendered.len()).sum::<usize>(), 8);
    assert!(farm.status().complete());
    assert!(r.renders.values().all(|&c| c == 1));

    // A rerun renders nothing.
    let again = run_all(&farm, 3, &mut r);
    assert_eq!(again.iter().map(|s| s.skipped.len()).sum::<usize>(), 8);
    assert!(r.renders.values().all(|&c| c == 1));

    // Truncate one tile, delete another, and corrupt a third in place (same size).
    let units = &farm.manifest.units;
    let p = |i: usize| farm.path(&units[i]);
    let bytes = std::fs::read(p(2)).unwrap();
    std::fs::write(p(2), &bytes[..bytes.len() / 2]).unwrap();
    std::fs::remove_file(p(5)).unwrap();
    std::fs::remove_file(dir.join(RECEIPTS).join(format!("{}.json", units[5].file))).unwrap();
    let mut b = std::fs::read(p(7)).unwrap();
    b[0] ^= 1;
    std::fs::write(p(7), b).unwrap();
    let s = farm.status();
    assert_eq!(s.missing, vec![5]);
    let corrupt: Vec<usize> = s.corrupt.iter().map(|c| c.0).collect();
    assert_eq!(corrupt, vec![2, 7]);
    assert!(
        s.corrupt[0].1.contains("bytes, the receipt says"),
        "{:?}",
        s.corrupt
    );
    assert!(s.corrupt[1].1.contains("checksum"), "{:?}", s.corrupt);
    // Assembly refuses, naming them.
    let e = farm.verified().unwrap_err().to_string();
    assert!(
        e.contains("3 of 8 units") && e.contains("tile-00005.png missing"),
        "{e}"
    );

    // A rerun of one shard at a time renders exactly those three, each once more.
    let mut events = Vec::new();
    for i in 0..3 {
        run_shard(&farm, Shard::new(i, 3).unwrap(), &mut r, &mut |e| {
            if let Event::Rendered { unit, .. } = e {
                events.push(unit.index)
            }
        })
        .unwrap();
    }
    events.sort();
    assert_eq!(events, vec![2, 5, 7]);
    for (u, c) in &r.renders {
        assert_eq!(*c, if [2, 5, 7].contains(u) { 2 } else { 1 }, "unit {u}");
    }
    assert!(farm.status().complete());
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn a_directory_of_a_different_job_is_refused() {
    let dir = scratch("other-job");
    let farm = fake_job(&dir, "scene A", 4).unwrap();
    let mut r = Counting::default();
    run_all(&farm, 1, &mut r);
    // Same job: opens.
    assert_eq!(
        fake_job(&dir, "scene A", 4).unwrap().manifest.job,
        farm.manifest.job
    );
    // Another scene, another tiling, another request: refused, naming what differs.
    let e = fake_job(&dir, "scene B", 4).unwrap_err();
    assert!(matches!(e, FarmError::DifferentJob { .. }));
    assert!(e.to_string().contains("the scene differs"), "{e}");
    let e = fake_job(&dir, "scene A", 6).unwrap_err().to_string();
    assert!(e.contains("the work"), "{e}");
    let req = RenderRequest {
        ssao: 1.0,
        ..small_request()
    };
    let fp = Fingerprint::new("scene A", &req, Work::tiles(4, 64, 48).unwrap()).unwrap();
    let e = FarmDir::create(&dir, fp, "scene A")
        .unwrap_err()
        .to_string();
    assert!(e.contains("render request"), "{e}");
    // Threads are not part of the job (any count renders the same pixels).
    let req = RenderRequest {
        threads: Some(2),
        ..small_request()
    };
    let fp = Fingerprint::new("scene A", &req, Work::tiles(4, 64, 48).unwrap()).unwrap();
    FarmDir::create(&dir, fp, "scene A").unwrap();
    // A receipt copied from another job does not make a unit done.
    let other = scratch("other-job-b");
    let b = fake_job(&other, "scene B", 4).unwrap();
    run_all(&b, 1, &mut r);
    let u = &farm.manifest.units[1];
    for f in [u.file.clone(), format!("{RECEIPTS}/{}.json", u.file)] {
        std::fs::copy(other.join(&f), dir.join(&f)).unwrap();
    }
    assert!(
        matches!(farm.check(u), UnitState::Corrupt(ref w) if w.contains("another job")),
        "{:?}",
        farm.check(u)
    );
    // The stored scene edited by hand is caught.
    std::fs::write(dir.join(crate::manifest::SCENE), "scene C").unwrap();
    assert!(matches!(
        farm.scene_text(),
        Err(FarmError::SceneChanged { .. })
    ));
    // Not a farm directory.
    assert!(matches!(
        FarmDir::open(&dir.join(RECEIPTS)),
        Err(FarmError::NotAFarm { .. })
    ));
    std::fs::remove_dir_all(&dir).ok();
    std::fs::remove_dir_all(&other).ok();
}

#[test]
fn a_job_written_before_settings_were_added_is_refused_naming_them_not_called_damaged() {
    let dir = scratch("outdated");
    fake_job(&dir, "scene A", 4).unwrap();
    let path = dir.join(crate::manifest::MANIFEST);
    let text = std::fs::read_to_string(&path).unwrap();
    let mut v: serde_json::Value = serde_json::from_str(&text).unwrap();
    // As an earlier build wrote it: its octree settings had no `smooth` and no `fovea`.
    let octree = v["fingerprint"]["request"]["octree"]
        .as_object_mut()
        .unwrap();
    assert!(octree.remove("smooth").is_some() && octree.remove("fovea").is_some());
    // ... and its job id was the hash of its fingerprint without them.
    let compact = serde_json::to_string(&fake_fingerprint()).unwrap();
    let earlier = compact.replace(r#","fovea":4.0,"smooth":true"#, "");
    assert_ne!(earlier, compact);
    v["job"] = crate::manifest::sha256_hex(earlier.as_bytes())[..16].into();
    std::fs::write(&path, serde_json::to_vec_pretty(&v).unwrap()).unwrap();
    let e = FarmDir::open(&dir).unwrap_err();
    let FarmError::Outdated { ref missing, .. } = e else {
        panic!("{e}");
    };
    let mut missing = missing.clone();
    missing.sort();
    assert_eq!(missing, ["octree.fovea", "octree.smooth"]);
    assert!(e.to_string().contains("new directory"), "{e}");
    // Creating the same job there is refused the same way, and the directory is kept.
    assert!(matches!(
        fake_job(&dir, "scene A", 4),
        Err(FarmError::Outdated { .. })
    ));
    assert_eq!(
        std::fs::read_to_string(&path).unwrap(),
        serde_json::to_string_pretty(&v).unwrap()
    );
    // Fields deleted by hand (the job id is not the hash without them): damaged.
    let good = v["job"].clone();
    v["job"] = "0123456789abcdef".into();
    std::fs::write(&path, serde_json::to_vec_pretty(&v).unwrap()).unwrap();
    let e = FarmDir::open(&dir).unwrap_err();
    assert!(matches!(e, FarmError::Damaged { .. }), "{e}");
    v["job"] = good;
    v["fingerprint"]["request"]
        .as_object_mut()
        .unwrap()
        .remove("width");
    std::fs::write(&path, serde_json::to_vec_pretty(&v).unwrap()).unwrap();
    let e = FarmDir::open(&dir).unwrap_err();
    assert!(matches!(e, FarmError::Damaged { .. }), "{e}");
    v["fingerprint"]["request"]["width"] = 64.into();
    // A job id edited by hand, with every field present, is still damaged.
    v["fingerprint"]["request"]["octree"]["smooth"] = true.into();
    v["fingerprint"]["request"]["octree"]["fovea"] = 4.0.into();
    v["job"] = "0123456789abcdef".into();
    std::fs::write(&path, serde_json::to_vec_pretty(&v).unwrap()).unwrap();
    let e = FarmDir::open(&dir).unwrap_err();
    assert!(matches!(e, FarmError::Damaged { .. }), "{e}");
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn a_failing_render_commits_nothing_for_its_unit() {
    struct FailAt(usize);
    impl UnitRenderer for FailAt {
        fn render(&mut self, unit: &Unit) -> Result<Vec<u8>, FarmError> {
            if unit.index == self.0 {
                return Err(FarmError::Render {
                    unit: unit.index,
                    file: unit.file.clone(),
                    message: "out of memory".into(),
                });
            }
            Ok(vec![1, 2, 3])
        }
    }
    let dir = scratch("fail");
    let farm = fake_job(&dir, "scene A", 4).unwrap();
    let e = run_shard(&farm, Shard::ALL, &mut FailAt(2), &mut |_| {}).unwrap_err();
    assert!(e.to_string().contains("unit 2") && e.to_string().contains("out of memory"));
    let s = farm.status();
    assert_eq!(
        (s.done.clone(), s.missing.clone()),
        (vec![0, 1], vec![2, 3])
    );
    std::fs::remove_dir_all(&dir).ok();
}

fn preset_text(name: &str) -> String {
    fathom_core::scene_file::to_string(&fathom_core::presets::load(name).unwrap())
}

#[test]
fn tiles_rendered_in_shards_assemble_to_the_single_render_byte_for_byte() {
    let dir = scratch("tiles");
    let text = preset_text("mandelbulb");
    assert_eq!(
        text,
        preset_text("mandelbulb"),
        "scene text is deterministic"
    );
    let req = RenderRequest {
        ssao: 1.0,
        ..small_request()
    };
    let work = Work::tiles(6, req.width, req.height).unwrap();
    let farm = FarmDir::create(&dir, Fingerprint::new(&text, &req, work).unwrap(), &text).unwrap();
    for i in 0..4 {
        let mut r = SessionRenderer::new(&farm, Some(1)).unwrap();
        run_shard(&farm, Shard::new(i, 4).unwrap(), &mut r, &mut |_| {}).unwrap();
    }
    let out = dir.join("still.png");
    let Assembled::Still { width, height, .. } = assemble(&farm, &out).unwrap() else {
        panic!("a tiled job assembles a still")
    };
    assert_eq!((width, height), (64, 48));
    // The single-process render of the preset itself (not of the stored text), encoded as
    // `fathom render` writes it.
    let scene = fathom_core::presets::load("mandelbulb").unwrap();
    let camera = scene.camera.clone();
    let whole = Session::new(scene).unwrap().render(&camera, &req).unwrap();
    let want = encode_frame(&whole.frame).unwrap();
    let path = dir.join("whole.png");
    fathom_image::output::save_colour(
        &whole.frame,
        fathom_image::output::open_output(&path).unwrap(),
        &path,
    )
    .unwrap();
    assert_eq!(std::fs::read(&path).unwrap(), want, "encoder drift");
    assert!(
        std::fs::read(&out).unwrap() == want,
        "assembled image differs"
    );
    // A truncated tile stops assembly.
    let t = farm.path(&farm.manifest.units[3]);
    let b = std::fs::read(&t).unwrap();
    std::fs::write(&t, &b[..b.len() - 10]).unwrap();
    let e = assemble(&farm, &dir.join("again.png"))
        .unwrap_err()
        .to_string();
    assert!(e.contains("tile-00003.png corrupt"), "{e}");
    assert!(!dir.join("again.png").exists());
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn path_frames_rendered_in_shards_equal_the_sequential_render() {
    let dir = scratch("path");
    let file =
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../../docs/examples/mandelbulb-dive.ron");
    let text = std::fs::read_to_string(&file).unwrap();
    let req = RenderRequest {
        width: 32,
        height: 24,
        threads: Some(1),
        ..RenderRequest::default()
    };
    let frames = 5;
    let work = Work::Path {
        path: "dive".into(),
        frames,
    };
    let farm = FarmDir::create(&dir, Fingerprint::new(&text, &req, work).unwrap(), &text).unwrap();
    // Shard 1/2 first (frames 1, 3), then 0/2: each replays modulation from frame 0.
    for i in [1, 0] {
        let mut r = SessionRenderer::new(&farm, Some(1)).unwrap();
        run_shard(&farm, Shard::new(i, 2).unwrap(), &mut r, &mut |_| {}).unwrap();
    }
    let Assembled::Frames { files, .. } = assemble(&farm, &dir.join("x.mp4")).unwrap() else {
        panic!("a path job gives frames")
    };
    // The sequence `fathom render --path` renders.
    let scene = fathom_core::scene_file::parse(&text, "t").unwrap();
    let mut session = Session::new(scene.clone()).unwrap();
    let flight = scene
        .path("dive")
        .unwrap()
        .prepare(&scene, Some(session.tape()))
        .unwrap();
    let mut modulator = fathom_live::Modulator::new(&scene).unwrap();
    let mut want = Vec::new();
    fathom_render::flight::FlightRender {
        frames,
        request: req.clone(),
    }
    .run(
        &mut session,
        &scene,
        &flight,
        &mut |s, t| {
            modulator.apply(s, t);
        },
        &Control::default(),
        &mut |f| {
            want.push(encode_frame(&f.rendered.frame)?);
            Ok(())
        },
    )
    .unwrap();
    assert_eq!(files.len(), frames);
    for (i, f) in files.iter().enumerate() {
        assert!(std::fs::read(f).unwrap() == want[i], "frame {i} differs");
    }
    assert_ne!(want[0], want[4]);
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn zoom_frames_are_settled_stills_that_do_not_depend_on_the_shard() {
    let preset = fathom_core::camera_path::path_preset("menger").unwrap();
    let text = fathom_core::scene_file::to_string(&preset.scene);
    let req = RenderRequest {
        width: 32,
        height: 24,
        threads: Some(1),
        backend: fathom_render::Backend::Octree,
        octree: fathom_render::OctreeSettings {
            max_memory: 64 << 20,
            ..Default::default()
        },
        ..RenderRequest::default()
    };
    let work = Work::Zoom {
        preset: "menger".into(),
        depth: 100.0,
        frames: 3,
    };
    let fp = Fingerprint::new(&text, &req, work).unwrap();
    // All frames in one task, and the same job in 3 shards run backwards with 2 threads.
    let (a, b) = (scratch("zoom-a"), scratch("zoom-b"));
    let fa = FarmDir::create(&a, fp.clone(), &text).unwrap();
    let mut r = SessionRenderer::new(&fa, Some(1)).unwrap();
    run_shard(&fa, Shard::ALL, &mut r, &mut |_| {}).unwrap();
    let fb = FarmDir::create(&b, fp, &text).unwrap();
    for i in [2, 1, 0] {
        let mut r = SessionRenderer::new(&fb, Some(2)).unwrap();
        run_shard(&fb, Shard::new(i, 3).unwrap(), &mut r, &mut |_| {}).unwrap();
    }
    let frames = |f: &FarmDir| -> Vec<Vec<u8>> {
        f.verified()
            .unwrap()
            .iter()
            .map(|p| std::fs::read(p).unwrap())
            .collect()
    };
    let (x, y) = (frames(&fa), frames(&fb));
    assert!(x == y, "zoom frames depend on the shard or the threads");
    assert_ne!(x[0], x[2], "the camera zooms");
    std::fs::remove_dir_all(&a).ok();
    std::fs::remove_dir_all(&b).ok();
}

#[test]
fn of_two_jobs_racing_into_a_new_directory_exactly_one_wins_and_it_is_whole() {
    for round in 0..20 {
        let dir = scratch(&format!("race-{round}"));
        // Odd rounds: two scenes; even rounds: one scene, two tilings.
        let jobs = [
            ("scene A", 4),
            (if round % 2 == 1 { "scene B" } else { "scene A" }, 6),
        ];
        let results: Vec<_> = std::thread::scope(|s| {
            let handles: Vec<_> = jobs
                .iter()
                .map(|&(scene, tiles)| {
                    let dir = dir.clone();
                    s.spawn(move || fake_job(&dir, scene, tiles))
                })
                .collect();
            handles.into_iter().map(|h| h.join().unwrap()).collect()
        });
        let won: Vec<&FarmDir> = results.iter().filter_map(|r| r.as_ref().ok()).collect();
        assert_eq!(won.len(), 1, "round {round}: {results:?}");
        for r in &results {
            if let Err(e) = r {
                assert!(matches!(e, FarmError::DifferentJob { .. }), "{e}");
            }
        }
        let reopened = FarmDir::open(&dir).unwrap();
        assert_eq!(reopened.manifest.job, won[0].manifest.job);
        reopened.scene_text().unwrap();
        std::fs::remove_dir_all(&dir).ok();
    }
}

#[test]
fn assembly_refuses_an_output_among_the_jobs_own_files() {
    let dir = scratch("assemble-inside");
    let farm = fake_job(&dir, "scene A", 4).unwrap();
    let unit = farm.path(&farm.manifest.units[0]);
    for out in [
        unit.clone(),
        dir.join(crate::manifest::MANIFEST),
        dir.join("receipts/x.png"),
    ] {
        let e = crate::assemble::assemble(&farm, &out)
            .err()
            .unwrap()
            .to_string();
        assert!(e.contains("would overwrite a file of the job"), "{e}");
    }
    assert!(!unit.exists(), "nothing was written");
    // Beside the job is fine as far as this check goes (the units are not done, so it
    // fails for that reason instead).
    let e = crate::assemble::assemble(&farm, &dir.with_extension("png"))
        .err()
        .unwrap()
        .to_string();
    assert!(!e.contains("would overwrite"), "{e}");
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn a_damaged_manifest_entry_names_its_unit() {
    let dir = scratch("damaged-entry");
    fake_job(&dir, "scene A", 4).unwrap();
    let path = dir.join(crate::manifest::MANIFEST);
    let text = std::fs::read_to_string(&path).unwrap();
    let mut v: serde_json::Value = serde_json::from_str(&text).unwrap();
    v["units"][2]["index"] = serde_json::json!("two");
    std::fs::write(&path, serde_json::to_string(&v).unwrap()).unwrap();
    let e = FarmDir::open(&dir).err().unwrap().to_string();
    assert!(e.contains("units[2]") && e.contains("tile-"), "{e}");
    v["units"][2]["index"] = serde_json::json!(3);
    std::fs::write(&path, serde_json::to_string(&v).unwrap()).unwrap();
    let e = FarmDir::open(&dir).err().unwrap().to_string();
    assert!(e.contains("unit 2 ("), "{e}");
    // A manifest that is a device behind a symlink is refused, not read forever.
    #[cfg(unix)]
    {
        std::fs::remove_file(&path).unwrap();
        std::os::unix::fs::symlink("/dev/zero", &path).unwrap();
        let e = FarmDir::open(&dir).err().unwrap().to_string();
        assert!(e.contains("not a regular file"), "{e}");
    }
    std::fs::remove_dir_all(&dir).ok();
}
