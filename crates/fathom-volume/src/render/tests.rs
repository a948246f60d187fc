//! Image-level tests of the path tracer against closed forms (white furnace, single
//! scattering of the sun, emission), the majorant grid against the global majorant, and
//! determinism across thread counts and passes.

use super::*;
use crate::grid::{DensityGrid, Grid, WorldBox};
use crate::light::{Environment, Sun, colour_map};
use crate::medium::{Majorant, Medium, MediumParams};
use glam::DVec3;

fn noise(res: u32, seed: u64) -> DensityGrid {
    let mut r = Stream::new(seed, 0, 0);
    let n = (res * res * res) as usize;
    let data = (0..n)
        .map(|_| if r.f32() < 0.5 { 0.0 } else { r.f32() })
        .collect();
    Grid::from_data([res; 3], data, WorldBox::UNIT).unwrap()
}

fn scene(grid: DensityGrid, p: MediumParams, env: Environment) -> VolumeScene {
    VolumeScene {
        medium: Medium::new(grid, &p).unwrap(),
        environment: env,
        sun: None,
        max_depth: 100_000,
        rr_depth: 5,
    }
}

fn camera(eye: DVec3) -> Camera {
    Camera {
        eye,
        target: DVec3::splat(0.5),
        up: DVec3::Y,
        fov: 40.0,
    }
}

/// A 1-degree camera looking down -z through the centre of the unit cube.
fn narrow_camera() -> Camera {
    Camera {
        eye: DVec3::new(0.5, 0.5, 3.0),
        target: DVec3::new(0.5, 0.5, 0.0),
        up: DVec3::Y,
        fov: 1.0,
    }
}

fn mean(f: &Frame) -> f64 {
    f.colour.iter().map(|c| c[1] as f64).sum::<f64>() / f.len() as f64
}

/// Albedo 1 in a uniform environment: every pixel converges to the environment radiance, for
/// several g and densities, from outside and from inside the volume.
#[test]
fn white_furnace_converges_to_the_environment() {
    let env = 0.7f32;
    for (g, scale, eye) in [
        (0.0f32, 4.0f32, DVec3::new(0.5, 0.6, 2.5)),
        (0.8, 15.0, DVec3::new(0.5, 0.6, 2.5)),
        (-0.6, 30.0, DVec3::new(0.5, 0.6, 2.5)),
        (0.3, 10.0, DVec3::new(0.4, 0.45, 0.55)), // inside
    ] {
        let p = MediumParams {
            density_scale: scale,
            albedo: Vec3::ONE,
            g,
            ..MediumParams::default()
        };
        let s = scene(noise(8, 1), p, Environment::Constant(Vec3::splat(env)));
        let (f, st) = render(&s, &camera(eye), 12, 12, 128, 5).unwrap();
        assert!(
            st.mean_path_length > 0.5,
            "g {g}: the rays should scatter ({})",
            st.mean_path_length
        );
        let m = mean(&f);
        assert!(
            (m - env as f64).abs() < 0.01,
            "g {g} scale {scale}: image mean {m}, want {env}"
        );
        for c in &f.colour {
            assert!(
                (c[0] - env).abs() < 0.3 && c[0] == c[2],
                "g {g} scale {scale}: pixel {c:?}"
            );
        }
    }
}

/// An optically thin cube lit by the sun from above, with one scattering allowed: along the
/// central view ray the radiance is sigma E p (1 - exp(-sigma)) exp(-sigma / 2) / sigma
/// integrated in closed form (isotropic p = 1 / 4 pi).
#[test]
fn single_scattering_of_the_sun_matches_the_closed_form() {
    let sigma = 0.8f32;
    let grid = Grid::from_data([4; 3], vec![1.0; 64], WorldBox::UNIT).unwrap();
    let p = MediumParams {
        density_scale: sigma,
        albedo: Vec3::ONE,
        ..MediumParams::default()
    };
    let mut s = scene(grid, p, Environment::Constant(Vec3::ZERO));
    s.sun = Some(Sun {
        towards: Vec3::Y,
        radiance: Vec3::splat(3.0),
    });
    s.max_depth = 1;
    let cam = narrow_camera();
    let (f, _) = render(&s, &cam, 3, 3, 20_000, 1).unwrap();
    let want = 3.0 / (4.0 * std::f64::consts::PI)
        * (1.0 - (-sigma as f64).exp())
        * (-0.5 * sigma as f64).exp();
    let got = f.colour[4][0] as f64;
    assert!(
        (got - want).abs() < 0.02 * want,
        "sun single scattering {got}, want {want}"
    );
}

/// A purely absorbing, emitting cube: radiance (1 - exp(-sigma L)) L_e along a ray of length L.
#[test]
fn emission_matches_the_closed_form() {
    let sigma = 1.5f32;
    let grid = Grid::from_data([4; 3], vec![2.0; 64], WorldBox::UNIT).unwrap();
    let p = MediumParams {
        density_scale: sigma / 2.0,
        albedo: Vec3::ZERO,
        emission: 2.0,
        ..MediumParams::default()
    };
    let s = scene(grid, p, Environment::Constant(Vec3::ZERO));
    let cam = narrow_camera();
    let (f, _) = render(&s, &cam, 3, 3, 20_000, 1).unwrap();
    let le = colour_map(1.0) * 2.0;
    let k = 1.0 - (-sigma).exp();
    for ch in 0..3 {
        let got = f.colour[4][ch];
        let want = k * le[ch];
        assert!(
            (got - want).abs() < 0.02 * want + 1e-4,
            "channel {ch}: {got}, want {want}"
        );
    }
}

/// Block means of the green channel (4 x 4 pixel blocks).
fn blocks(f: &Frame) -> Vec<f64> {
    let b = 4;
    let mut out = vec![0.0; ((f.width / b) * (f.height / b)) as usize];
    for y in 0..f.height {
        for x in 0..f.width {
            out[((y / b) * (f.width / b) + x / b) as usize] +=
                f.colour[f.index(x, y)][1] as f64 / (b * b) as f64;
        }
    }
    out
}

fn rms(a: &[f64], b: &[f64]) -> f64 {
    (a.iter().zip(b).map(|(x, y)| (x - y).powi(2)).sum::<f64>() / a.len() as f64).sqrt()
}

/// The majorant grid (with and without homogeneous cells) and one global majorant render the
/// same image within noise: their difference is no larger than that between two seeds of the
/// global majorant. A Menger-like grid (blocks of empty and full voxels) with a sun and a sky.
#[test]
fn majorant_grid_and_global_majorant_give_the_same_image() {
    let res = 27u32;
    let menger = |i: u32| {
        let mut i = i;
        (0..3).all(|_| {
            let d = i % 3;
            i /= 3;
            d != 1
        })
    };
    let mut g = Grid::from_data(
        [res; 3],
        vec![0.0; (res * res * res) as usize],
        WorldBox::UNIT,
    )
    .unwrap();
    for z in 0..res {
        for y in 0..res {
            for x in 0..res {
                let holes = [menger(x), menger(y), menger(z)]
                    .iter()
                    .filter(|v| !**v)
                    .count();
                if holes < 2 {
                    let i = g.index(x, y, z);
                    g.data_mut()[i] = 1.0;
                }
            }
        }
    }
    let env = Environment::Sky {
        top: Vec3::new(0.6, 0.7, 1.0),
        bottom: Vec3::splat(0.2),
        up: Vec3::Y,
    };
    let sun = Some(Sun {
        towards: Vec3::new(0.3, 0.9, 0.3).normalize(),
        radiance: Vec3::splat(2.0),
    });
    let cam = camera(DVec3::new(1.6, 1.3, 2.0));
    let mut images = Vec::new();
    for (maj, hom, seed) in [
        (Majorant::Global, false, 1),
        (Majorant::Global, false, 2),
        (Majorant::Grid { block: 3 }, false, 3),
        (Majorant::Grid { block: 3 }, true, 4),
        (Majorant::Grid { block: 9 }, true, 5),
    ] {
        let p = MediumParams {
            density_scale: 20.0,
            albedo: Vec3::splat(0.8),
            g: 0.2,
            majorant: maj,
            homogeneous_cells: hom,
            ..MediumParams::default()
        };
        let mut s = scene(g.clone(), p, env);
        s.sun = sun;
        let (f, st) = render(&s, &cam, 32, 32, 48, seed).unwrap();
        images.push((blocks(&f), mean(&f), st.lookups_per_path));
    }
    let noise = rms(&images[0].0, &images[1].0);
    assert!(noise > 0.0);
    for (i, (b, m, lookups)) in images.iter().enumerate().skip(2) {
        let d = rms(b, &images[0].0);
        assert!(
            d < 2.0 * noise,
            "mode {i}: block rms difference {d} vs seed noise {noise}"
        );
        assert!(
            (m - images[0].1).abs() < 3.0 * noise / 8.0 + 1e-3,
            "mode {i}: mean {m} vs {}",
            images[0].1
        );
        if i < 4 {
            // 3-voxel blocks fit the sponge's holes; 9-voxel ones overlap solid everywhere.
            assert!(
                *lookups < images[0].2,
                "mode {i} should look up less than the global majorant"
            );
        }
    }
}

/// The same seed gives the same bytes on 1 and 2 threads, in one pass or several.
#[test]
fn images_do_not_depend_on_threads_or_passes() {
    let p = MediumParams {
        density_scale: 12.0,
        g: 0.5,
        ..MediumParams::default()
    };
    let s = scene(noise(10, 3), p, Environment::Constant(Vec3::ONE));
    let cam = camera(DVec3::new(0.3, 0.8, 2.2));
    let run = |threads: usize, passes: &[u32]| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        pool.install(|| {
            let mut pr = Progressive::new(&s, &cam, 16, 12, 9).unwrap();
            for &n in passes {
                pr.add_samples(n, &|| {}).unwrap();
            }
            pr.frame().colour
        })
    };
    let a = run(1, &[6]);
    assert_eq!(a, run(2, &[6]));
    assert_eq!(a, run(2, &[1, 2, 3]));
    assert_ne!(a, run(2, &[5]));
}

#[test]
fn bad_render_settings_are_refused() {
    let s = scene(
        noise(4, 1),
        MediumParams::default(),
        Environment::Constant(Vec3::ONE),
    );
    let cam = camera(DVec3::new(0.5, 0.5, 3.0));
    let e = render(&s, &cam, 8, 8, 0, 1).unwrap_err().to_string();
    assert!(e.contains("spp = 0") && e.contains("1..="), "{e}");
    let e = render(&s, &cam, 0, 8, 1, 1).unwrap_err().to_string();
    assert!(e.contains("size = 0x8"), "{e}");
    let mut bad = s.clone();
    bad.environment = Environment::Constant(Vec3::splat(f32::NAN));
    assert!(
        render(&bad, &cam, 4, 4, 1, 1)
            .unwrap_err()
            .to_string()
            .contains("environment")
    );
    let cam = Camera { fov: 0.0, ..cam };
    assert!(
        render(&s, &cam, 4, 4, 1, 1)
            .unwrap_err()
            .to_string()
            .contains("fov")
    );
}
