//! Tests of the integrator as a whole: white furnace, NEE + MIS against BSDF sampling alone,
//! self-intersection, determinism, convergence rate, the denoiser's gain, bad input.

use super::*;
use crate::colour::Look;
use crate::lights::SphereLight;
use crate::output::relative_rmse;
use crate::progressive::{Control, Frame, Progressive};
use fathom_core::primitives::Primitive;
use fathom_core::scene::Light;
use fathom_core::transforms::Transform;
use fathom_core::{Camera, Node};

fn look(m: PbrMaterial) -> Look {
    Look {
        material: m,
        layers: Vec::new(),
    }
}

/// A unit sphere seen from z = 4, no lights.
fn sphere_scene() -> Scene {
    let mut s = Scene::new(Node::new(Primitive::Sphere));
    s.lights.clear();
    s.camera = Camera {
        eye: DVec3::new(0.0, 0.0, 4.0),
        target: DVec3::ZERO,
        up: DVec3::Y,
        fov: 36.0,
    };
    s
}

/// A unit sphere resting on a floor at y = -1.
fn sphere_on_plane() -> Scene {
    let floor = Node::new(Primitive::Plane)
        .op(fathom_core::scene::Call::new(Transform::Translate).with("offset", &[0.0, -1.0, 0.0]));
    let mut s = Scene::new(Node::new(Primitive::Sphere).child(floor));
    s.lights.clear();
    s.camera = Camera {
        eye: DVec3::new(0.0, 1.5, 5.0),
        target: DVec3::new(0.0, -0.3, 0.0),
        up: DVec3::Y,
        fov: 45.0,
    };
    s.render.max_distance = 30.0;
    s
}

fn render(scene: &Scene, settings: PathSettings, spp: u32) -> Frame {
    let tape = Tape::compile(scene).unwrap();
    let mut p = Progressive::new(PathTracer::new(scene, &tape, settings).unwrap());
    p.add_samples(spp, &Control::default()).unwrap();
    assert_eq!(p.stats().dropped_non_finite, 0);
    p.frame()
}

/// Three spheres inside a uniform environment of radiance 1, no lights: every path that
/// leaves sees 1 and no energy is made or lost, so every pixel converges to 1.
#[test]
fn white_furnace() {
    let scene = sphere_scene();
    let cases = crate::furnace::furnace_cases();
    for (name, m, tol) in cases {
        let mut s = PathSettings::new(20, 20);
        s.environment = Some(Environment::Uniform(DVec3::ONE));
        s.looks = Some(vec![look(m)]);
        s.max_bounces = 64;
        let f = render(&scene, s, 32);
        let hits: Vec<&[f32; 3]> = f
            .colour
            .iter()
            .zip(&f.depth)
            .filter(|(_, d)| d.is_finite())
            .map(|(c, _)| c)
            .collect();
        assert!(hits.len() > 150, "{name}: the sphere should fill the view");
        let mean = hits.iter().map(|c| c[0] + c[1] + c[2]).sum::<f32>() / (3 * hits.len()) as f32;
        let worst = hits
            .iter()
            .flat_map(|c| c.iter())
            .map(|v| (v - 1.0).abs())
            .fold(0.0f32, f32::max);
        assert!((mean - 1.0).abs() < tol as f32, "{name}: mean {mean}");
        assert!(worst < 0.15, "{name}: a pixel is {worst} away from 1");
    }
}

/// Next-event estimation with MIS and BSDF sampling alone estimate the same image of a
/// diffuse and a glossy sphere on a floor lit by a spherical area light.
#[test]
fn nee_with_mis_matches_bsdf_sampling() {
    let scene = sphere_on_plane();
    let settings = |light_sampling| {
        let mut s = PathSettings::new(14, 10);
        s.environment = Some(Environment::Uniform(DVec3::ZERO));
        s.sphere_lights = vec![SphereLight {
            centre: DVec3::new(1.5, 2.0, 1.0),
            radius: 0.6,
            colour: [1.0, 0.9, 0.8],
            strength: 6.0,
        }];
        s.looks = Some(vec![
            look(PbrMaterial {
                roughness: 0.6,
                specular: 0.5,
                ..PbrMaterial::diffuse([0.6, 0.3, 0.2])
            }),
            look(PbrMaterial::diffuse([0.7; 3])),
        ]);
        s.max_bounces = 3;
        s.light_sampling = light_sampling;
        s
    };
    let mis = render(&scene, settings(true), 256);
    let bsdf = render(&scene, settings(false), 1024);
    // Per pixel: the difference in units of its standard error.
    let mut z2 = 0.0;
    let mut n = 0;
    for i in 0..mis.colour.len() {
        let l = |c: [f32; 3]| {
            crate::sampling::luminance(DVec3::new(c[0] as f64, c[1] as f64, c[2] as f64))
        };
        // Far floor pixels see the light so small that BSDF sampling never finds it in 1024
        // samples (its estimate is 0 with variance 0): a z-score means nothing there.
        let v = mis.variance[i] as f64 + bsdf.variance[i] as f64;
        if mis.variance[i] > 0.0 && bsdf.variance[i] > 0.0 {
            let d = l(mis.colour[i]) - l(bsdf.colour[i]);
            z2 += d * d / v;

            n += 1;
        }
    }
    let mean_z2 = z2 / n as f64;
    assert!(
        n > 80 && mean_z2 < 2.0,
        "mean squared z-score {mean_z2} over {n} pixels"
    );
    let total = |f: &Frame| f.colour.iter().map(|c| c[0] + c[1] + c[2]).sum::<f32>();
    let (a, b) = (total(&mis), total(&bsdf));
    assert!((a / b - 1.0).abs() < 0.03, "image means {a} vs {b}");
    // MIS is the better estimator: less noise per sample (the noise of the mean times
    // sqrt(spp)), though BSDF sampling's is underestimated where it never found the light.
    let (nm, nb) = (mis.relative_noise() * 16.0, bsdf.relative_noise() * 32.0);
    assert!(nm < nb, "noise per sample: MIS {nm}, BSDF only {nb}");
}

/// A lit plane seen at grazing angles and a lit sphere: with a delta light, one bounce and a
/// black sky every hit's radiance is exactly albedo x irradiance x cos, so any shadow ray
/// blocked by the surface it leaves shows as a darker pixel.
#[test]
fn no_self_shadowing_at_grazing_angles() {
    let light = Light {
        direction: DVec3::new(0.3, 1.0, -0.2),
        colour: [1.0; 3],
        intensity: 1.0,
        shadows: true,
    };
    let l = light.direction.normalize();
    // The floor alone, camera nearly in its plane.
    let mut plane = Scene::new(Node::new(Primitive::Plane));
    plane.lights = vec![light.clone()];
    plane.camera = Camera {
        eye: DVec3::new(0.0, 0.05, 0.0),
        target: DVec3::new(0.0, 0.0, -10.0),
        up: DVec3::Y,
        fov: 30.0,
    };
    let mut sphere = sphere_scene();
    sphere.lights = vec![light];
    for (name, scene) in [("plane", plane), ("sphere", sphere)] {
        let mut s = PathSettings::new(40, 30);
        s.environment = Some(Environment::Uniform(DVec3::ZERO));
        s.sun_radius = Some(0.0);
        s.looks = Some(vec![look(PbrMaterial::diffuse([1.0; 3]))]);
        s.max_bounces = 1;
        let f = render(&scene, s, 1);
        let mut checked = 0;
        for i in 0..f.colour.len() {
            let n = DVec3::new(
                f.normal[i][0] as f64,
                f.normal[i][1] as f64,
                f.normal[i][2] as f64,
            );
            let cos = n.dot(l);
            if !f.depth[i].is_finite() || cos < 0.05 {
                continue;
            }
            checked += 1;
            let got = f.colour[i][0] as f64;
            assert!(
                (got - cos).abs() < 2e-3,
                "{name}: pixel {i} at depth {} has {got}, want {cos}",
                f.depth[i]
            );
        }
        assert!(checked > 100, "{name}: only {checked} lit pixels");
    }
}

fn small_preset(name: &str, w: u32, h: u32, spp: u32) -> Frame {
    let scene = fathom_core::presets::load(name).unwrap();
    render(&scene, PathSettings::new(w, h), spp)
}

#[test]
fn one_and_two_threads_give_identical_images() {
    let run = |threads| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| small_preset("menger", 40, 30, 3))
    };
    let a = run(1);
    let b = run(2);
    assert!(a == b, "images differ between 1 and 2 threads");
    // Batches do not matter either: 1 + 2 samples equal 3 at once.
    let scene = fathom_core::presets::load("menger").unwrap();
    let tape = Tape::compile(&scene).unwrap();
    let mut p =
        Progressive::new(PathTracer::new(&scene, &tape, PathSettings::new(40, 30)).unwrap());
    p.add_samples(1, &Control::default()).unwrap();
    p.add_samples(2, &Control::default()).unwrap();
    assert!(p.frame() == a);
}

/// Shared by the convergence and denoiser tests: a lit sphere on a floor under the sky.
/// Both are rough (a glossy sphere would throw the sun's highlight onto the floor, a caustic
/// that only BSDF sampling from the floor finds: rare, bright samples that dominate the error
/// at low spp and hide the rate this test is about).
fn lit_scene() -> (Scene, PathSettings) {
    let mut scene = sphere_on_plane();
    scene.lights = vec![Light {
        direction: DVec3::new(0.5, 0.8, 0.4),
        ..Light::default()
    }];
    let mut s = PathSettings::new(16, 12);
    s.looks = Some(vec![
        look(PbrMaterial {
            roughness: 0.9,
            specular: 0.5,
            ..PbrMaterial::diffuse([0.8, 0.4, 0.2])
        }),
        look(PbrMaterial::diffuse([0.6; 3])),
    ]);
    s.max_bounces = 4;
    (scene, s)
}

/// RMSE against a high-spp reference falls like spp^-1/2: the slope of log RMSE against log
/// spp, fitted over 4 to 256 spp, lies in [-0.65, -0.40] (Monte Carlo gives -0.5; the
/// reference's own noise flattens the curve slightly, stratification steepens it).
#[test]
fn rmse_falls_like_one_over_sqrt_spp() {
    let (scene, s) = lit_scene();
    let tape = Tape::compile(&scene).unwrap();
    let tracer = PathTracer::new(&scene, &tape, s).unwrap();
    let mut reference = Progressive::new(tracer.clone().with_seed(77));
    reference.add_samples(4096, &Control::default()).unwrap();
    let reference = reference.frame();
    let mut p = Progressive::new(tracer);
    let mut pts = Vec::new();
    let mut spp = 0;
    for target in [4u32, 16, 64, 256] {
        p.add_samples(target - spp, &Control::default()).unwrap();
        spp = target;
        let e = relative_rmse(&p.frame().colour, &reference.colour);
        pts.push(((spp as f64).ln(), e.ln()));
    }
    let n = pts.len() as f64;
    let (mx, my) = (
        pts.iter().map(|p| p.0).sum::<f64>() / n,
        pts.iter().map(|p| p.1).sum::<f64>() / n,
    );
    let slope = pts.iter().map(|p| (p.0 - mx) * (p.1 - my)).sum::<f64>()
        / pts.iter().map(|p| (p.0 - mx).powi(2)).sum::<f64>();
    println!("slope {slope}, points {pts:?}");
    assert!(
        (-0.65..=-0.40).contains(&slope),
        "slope {slope}, points {pts:?}"
    );
}

/// At 16 spp the denoised image is closer to the reference than the raw one. The brief's
/// target was 4x; on this scene it is not reached: Sobol sampling leaves the raw image at
/// about 1.8 % RMSE at 16 spp, and the filter's own bias at the sphere's silhouette, the
/// penumbra and the contact shadow (pixels whose guides are blends) is about 1 %, so the
/// measured gain is 1.2x here at 64x48 (1.5x at 96x72 in an experiment). The test asserts
/// 1.1x: the denoiser must help, and it does not reach the target on this scene.
#[test]
fn denoiser_lowers_the_error_at_16_spp() {
    let (scene, mut s) = lit_scene();
    s.width = 64;
    s.height = 48;
    let tape = Tape::compile(&scene).unwrap();
    let tracer = PathTracer::new(&scene, &tape, s).unwrap();
    let mut reference = Progressive::new(tracer.clone().with_seed(77));
    reference.add_samples(256, &Control::default()).unwrap();
    let reference = reference.frame();
    let mut p = Progressive::new(tracer);
    p.add_samples(16, &Control::default()).unwrap();
    let f = p.frame();
    let raw = relative_rmse(&f.colour, &reference.colour);
    let den = relative_rmse(
        &crate::denoise(&f, &crate::DenoiseSettings::default()),
        &reference.colour,
    );
    println!("raw {raw}, denoised {den}: gain {}", raw / den);
    assert!(
        raw / den >= 1.1,
        "raw {raw}, denoised {den}: gain {}",
        raw / den
    );
}

#[test]
fn bad_settings_and_looks_are_refused_with_their_names() {
    let scene = sphere_scene();
    let tape = Tape::compile(&scene).unwrap();
    let err = |s: PathSettings| PathTracer::new(&scene, &tape, s).unwrap_err().to_string();
    assert!(err(PathSettings::new(0, 10)).contains("image size 0x10"));
    let mut s = PathSettings::new(8, 8);
    s.max_bounces = 0;
    assert_eq!(err(s), "max_bounces = 0 is out of range [1, 256]");
    let mut s = PathSettings::new(8, 8);
    s.aperture = f64::NAN;
    assert_eq!(err(s), "aperture = NaN is out of range [0, 1e6]");
    let mut s = PathSettings::new(8, 8);
    s.looks = Some(vec![look(PbrMaterial {
        ior: f64::INFINITY,
        ..PbrMaterial::default()
    })]);
    assert_eq!(err(s), "node 0: material.ior = inf is out of range [1, 4]");
    let mut s = PathSettings::new(8, 8);
    s.looks = Some(vec![]);
    assert_eq!(err(s), "0 looks given for a tape with 1 materials");
    let mut s = PathSettings::new(8, 8);
    s.sphere_lights = vec![SphereLight {
        centre: DVec3::ZERO,
        radius: 1.0,
        colour: [1.0; 3],
        strength: -2.0,
    }];
    assert_eq!(
        err(s),
        "sphere light 0: strength = -2 is out of range [0, 1e9]"
    );
    let mut bad_camera = scene.clone();
    bad_camera.camera.fov = 0.0;
    assert!(
        PathTracer::new(&bad_camera, &tape, PathSettings::new(8, 8))
            .unwrap_err()
            .to_string()
            .contains("fov")
    );
}

#[test]
fn cancelling_adds_nothing() {
    let scene = sphere_scene();
    let tape = Tape::compile(&scene).unwrap();
    let mut p =
        Progressive::new(PathTracer::new(&scene, &tape, PathSettings::new(40, 40)).unwrap());
    p.add_samples(1, &Control::default()).unwrap();
    let before = p.frame();
    let flag = std::sync::atomic::AtomicBool::new(true);
    let r = p.add_samples(
        4,
        &Control {
            cancel: Some(&flag),
            progress: None,
        },
    );
    assert!(matches!(r, Err(PathTraceError::Cancelled)));
    assert!(p.frame() == before && p.stats().samples_per_pixel == 1);
}
