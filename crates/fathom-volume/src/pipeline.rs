//! From a source to a density grid and on to files: what `fathom volume` does between parsing
//! its arguments and writing the image. A grid comes from the physarum simulation, from a
//! scene's tape (the fractal density mode), or from a `.vol` / raw file; it can be exported to
//! either format; the image is written as a linear float EXR (PNG is the command's, through
//! the sphere tracer's tonemapping).

use crate::error::VolumeError;
use crate::file_io::io_err;
use crate::fractal;
use crate::grid::{DensityGrid, TrailGrid, WorldBox};
use crate::physarum::{self, Params, Simulation, StepTimes};
use crate::raw_file::{self, RawGrid};
use crate::vol_file;
use fathom_core::atomic_file::AtomicFile;
use fathom_core::camera::Camera;
use fathom_core::frame::Frame;
use fathom_core::scene::Scene;
use fathom_core::tape::Tape;
use glam::DVec3;
use serde::Serialize;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Most simulation steps.
pub const MAX_STEPS: u32 = 1_000_000;

/// Where a grid read from a file sits in the world.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Placement {
    /// The unit cube (Mitsuba's convention; raw files keep their own box).
    Default,
    /// The bounding box written in the `.vol` header.
    FromFile,
    /// This box.
    Box(WorldBox),
}

/// Where the density comes from.
#[derive(Clone, Debug)]
pub enum Source {
    /// Grow a physarum network for `steps` steps in a `res`^3 grid.
    Physarum {
        params: Params,
        res: u32,
        steps: u32,
        seed: u64,
    },
    /// Sample a scene's tape into a `res`^3 grid over `bbox` (fitted when `None`).
    Fractal {
        scene: Box<Scene>,
        res: u32,
        bbox: Option<WorldBox>,
        smooth: f32,
    },
    /// Read a `.vol` or raw grid.
    File { path: PathBuf, placement: Placement },
}

/// What a long-running phase reports: which phase, units done, units in all.
pub type Progress<'a> = &'a (dyn Fn(&str, u64, u64) + Sync);

/// The simulation's timing, for the stats file.
#[derive(Clone, Copy, Debug, Default, Serialize)]
pub struct SimReport {
    pub agents: u32,
    pub steps: u32,
    pub seconds: f64,
    pub steps_per_second: f64,
    pub agent_steps_per_second: f64,
    /// Mean milliseconds per step in each phase.
    pub mean_step: StepTimes,
}

/// A grid ready to render.
pub struct Built {
    pub density: DensityGrid,
    /// The trail counts, when the grid was simulated (or read as counts).
    pub trail: Option<TrailGrid>,
    /// The camera to use when none is given: the scene's, or one framing the box.
    pub camera: Camera,
    pub sim: Option<SimReport>,
}

/// A camera framing `bbox` from above a front corner, vertical field of view 40 degrees, as
/// close as it can be with every corner of the box inside the view (a 5% margin; for images
/// at least as wide as they are tall). Fitting the corners rather than the box's bounding
/// sphere lets a grid filled to its faces take most of the picture instead of its middle half.
pub fn framing_camera(bbox: &WorldBox) -> Camera {
    let c = bbox.centre().as_dvec3();
    let fov = 40.0f64;
    let back = DVec3::new(0.55, 0.45, 0.7).normalize();
    let right = DVec3::Y.cross(back).normalize();
    let up = back.cross(right);
    let t = (0.5 * fov).to_radians().tan();
    let (lo, hi) = (bbox.min.as_dvec3(), bbox.max.as_dvec3());
    let dist = (0..8)
        .map(|i| {
            let p = DVec3::new(
                if i & 1 == 0 { lo.x } else { hi.x },
                if i & 2 == 0 { lo.y } else { hi.y },
                if i & 4 == 0 { lo.z } else { hi.z },
            ) - c;
            // The corner is in view when its offset across the view is within t times its
            // depth in front of the eye.
            let across = p.dot(right).abs().max(p.dot(up).abs()) * 1.05;
            p.dot(back) + across / t
        })
        .fold(0.0f64, f64::max)
        .max(1e-6);
    Camera {
        eye: c + back * dist,
        target: c,
        up: DVec3::Y,
        fov,
    }
}

fn check_res(name: &'static str, res: u32) -> Result<(), VolumeError> {
    if !(1..=crate::grid::MAX_RES).contains(&res) {
        return Err(VolumeError::param(
            name,
            res,
            format!("1..={} voxels per side", crate::grid::MAX_RES),
        ));
    }
    Ok(())
}

/// Makes the density grid of `source`; memory beyond `limit` bytes is refused before
/// allocating.
pub fn build(source: &Source, limit: u64, progress: Progress) -> Result<Built, VolumeError> {
    match source {
        Source::Physarum {
            params,
            res,
            steps,
            seed,
        } => {
            check_res("grid", *res)?;
            if *steps > MAX_STEPS {
                return Err(VolumeError::param(
                    "steps",
                    steps,
                    format!("0..={MAX_STEPS}"),
                ));
            }
            let mut sim = Simulation::new(params.clone(), [*res; 3], *seed, limit)?;
            let start = Instant::now();
            let mut sum = StepTimes::default();
            for i in 0..*steps {
                let t = sim.step();
                sum.sort_ms += t.sort_ms;
                sum.move_ms += t.move_ms;
                sum.deposit_ms += t.deposit_ms;
                sum.diffuse_ms += t.diffuse_ms;
                progress("simulate", i as u64 + 1, *steps as u64);
            }
            let seconds = start.elapsed().as_secs_f64();
            let n = (*steps).max(1) as f64;
            let report = SimReport {
                agents: params.agents,
                steps: *steps,
                seconds,
                steps_per_second: *steps as f64 / seconds.max(1e-9),
                agent_steps_per_second: *steps as f64 * params.agents as f64 / seconds.max(1e-9),
                mean_step: StepTimes {
                    sort_ms: sum.sort_ms / n,
                    move_ms: sum.move_ms / n,
                    deposit_ms: sum.deposit_ms / n,
                    diffuse_ms: sum.diffuse_ms / n,
                },
            };
            let density = sim.density();
            Ok(Built {
                camera: framing_camera(&density.bbox),
                trail: Some(sim.trail()),
                density,
                sim: Some(report),
            })
        }
        Source::Fractal {
            scene,
            res,
            bbox,
            smooth,
        } => {
            let (tape, bbox) = scene_grid(scene, *res, *bbox)?;
            let done = std::sync::atomic::AtomicU64::new(0);
            let density = fractal::sample(&tape, [*res; 3], bbox, *smooth, limit, &|| {
                let d = done.fetch_add(1, std::sync::atomic::Ordering::Relaxed) + 1;
                progress("sample", d, *res as u64);
            })?;
            Ok(Built {
                density,
                trail: None,
                camera: scene.camera.clone(),
                sim: None,
            })
        }
        Source::File { path, placement } => {
            let (mut density, trail, file_box) = if is_raw(path) {
                match raw_file::read(path, limit)? {
                    RawGrid::Density(d) => {
                        let b = d.bbox;
                        (d, None, Some(b))
                    }
                    RawGrid::Trail(t) => (
                        physarum::density_of(&t, 0.999),
                        Some(t.clone()),
                        Some(t.bbox),
                    ),
                }
            } else {
                let v = vol_file::read(path, limit)?;
                let b = v.file_box().ok();
                (v.grid, None, b)
            };
            density.bbox = match placement {
                Placement::Default => {
                    if is_raw(path) {
                        density.bbox
                    } else {
                        WorldBox::UNIT
                    }
                }
                Placement::FromFile => file_box.ok_or_else(|| {
                    VolumeError::Invalid(format!(
                        "{}: the file's bounding box is not a valid box",
                        path.display()
                    ))
                })?,
                Placement::Box(b) => *b,
            };
            Ok(Built {
                camera: framing_camera(&density.bbox),
                density,
                trail,
                sim: None,
            })
        }
    }
}

/// The compiled scene and the box its grid spans (given, or fitted to the scene).
fn scene_grid(
    scene: &Scene,
    res: u32,
    bbox: Option<WorldBox>,
) -> Result<(Tape, WorldBox), VolumeError> {
    check_res("grid", res)?;
    let tape = Tape::compile(scene).map_err(|e| VolumeError::Invalid(e.to_string()))?;
    let bbox = match bbox {
        Some(b) => b,
        None => fractal::fit_box(&tape)?,
    };
    Ok((tape, bbox))
}

/// The signed distance of a scene source ([`Source::Fractal`]) at the voxel centres of its
/// grid (world units, negative inside; see [`fractal::sample_distance`]), for export: not a
/// density to render.
pub fn distance_grid(
    source: &Source,
    limit: u64,
    progress: Progress,
) -> Result<DensityGrid, VolumeError> {
    let Source::Fractal {
        scene, res, bbox, ..
    } = source
    else {
        return Err(VolumeError::Invalid(
            "a distance grid samples a scene (--scene or --preset), not a simulation or a file"
                .into(),
        ));
    };
    let (tape, bbox) = scene_grid(scene, *res, *bbox)?;
    let done = std::sync::atomic::AtomicU64::new(0);
    fractal::sample_distance(&tape, [*res; 3], bbox, limit, &|| {
        let d = done.fetch_add(1, std::sync::atomic::Ordering::Relaxed) + 1;
        progress("distance", d, *res as u64);
    })
}

/// Whether `path` names a raw grid (extension `.raw`) rather than a `.vol`.
pub fn is_raw(path: &Path) -> bool {
    path.extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("raw"))
}

/// Writes the grid: `.vol` (Mitsuba; densities, the world box in the header) or `.raw`
/// (trail counts when there are any, else densities).
pub fn export(path: &Path, built: &Built) -> Result<(), VolumeError> {
    if is_raw(path) {
        let g = match &built.trail {
            Some(t) => RawGrid::Trail(t.clone()),
            None => RawGrid::Density(built.density.clone()),
        };
        raw_file::write(path, &g)
    } else if path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("vol"))
    {
        vol_file::write(path, &built.density)
    } else {
        Err(VolumeError::Invalid(format!(
            "{}: unknown grid format (valid extensions: .vol for Mitsuba 3, .raw for fathom's raw grids)",
            path.display()
        )))
    }
}

/// Writes the frame's colour as a linear float RGB OpenEXR file (atomically).
pub fn save_exr(frame: &Frame, path: &Path) -> Result<(), VolumeError> {
    let data: Vec<f32> = frame.colour.iter().flatten().copied().collect();
    let img = image::Rgb32FImage::from_raw(frame.width, frame.height, data)
        .ok_or_else(|| VolumeError::Invalid("frame buffer has the wrong size".into()))?;
    let mut w = std::io::BufWriter::new(AtomicFile::create(path)?);
    image::DynamicImage::ImageRgb32F(img)
        .write_to(&mut w, image::ImageFormat::OpenExr)
        .map_err(|e| VolumeError::Invalid(format!("{}: {e}", path.display())))?;
    let f = w.into_inner().map_err(|e| io_err(path)(e.into_error()))?;
    Ok(f.commit()?)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::grid::Grid;

    fn tmp(name: &str) -> PathBuf {
        let d = std::env::temp_dir().join(format!("fathom-volume-pipe-{}", std::process::id()));
        std::fs::create_dir_all(&d).unwrap();
        d.join(name)
    }

    #[test]
    fn exported_grids_read_back_with_each_placement() {
        let bbox = WorldBox::new(glam::Vec3::splat(-1.0), glam::Vec3::splat(1.0)).unwrap();
        let built = Built {
            density: Grid::from_data([2, 1, 1], vec![0.5, 2.0], bbox).unwrap(),
            trail: None,
            camera: Camera::default(),
            sim: None,
        };
        let vol = tmp("g.vol");
        export(&vol, &built).unwrap();
        for (placement, want) in [
            (Placement::Default, WorldBox::UNIT),
            (Placement::FromFile, bbox),
            (
                Placement::Box(WorldBox::new(glam::Vec3::ZERO, glam::Vec3::splat(3.0)).unwrap()),
                WorldBox::new(glam::Vec3::ZERO, glam::Vec3::splat(3.0)).unwrap(),
            ),
        ] {
            let b = build(
                &Source::File {
                    path: vol.clone(),
                    placement,
                },
                1 << 20,
                &|_, _, _| {},
            )
            .unwrap();
            assert_eq!(b.density.data(), built.density.data());
            assert_eq!(b.density.bbox, want);
        }
        let raw = tmp("g.raw");
        export(&raw, &built).unwrap();
        let b = build(
            &Source::File {
                path: raw,
                placement: Placement::Default,
            },
            1 << 20,
            &|_, _, _| {},
        )
        .unwrap();
        assert_eq!(b.density, built.density);
        let e = export(&tmp("g.png"), &built).err().unwrap().to_string();
        assert!(e.contains("valid extensions: .vol"), "{e}");
    }

    #[test]
    fn exr_output_is_linear_float_rgb() {
        let mut f = Frame::new(2, 1);
        f.colour = vec![[0.25, 1.5, 3.0], [0.0, 0.0, 7.0]];
        let p = tmp("f.exr");
        save_exr(&f, &p).unwrap();
        let img = image::open(&p).unwrap().to_rgb32f();
        assert_eq!(img.get_pixel(0, 0).0, [0.25, 1.5, 3.0]);
        assert_eq!(img.get_pixel(1, 0).0, [0.0, 0.0, 7.0]);
    }
}
