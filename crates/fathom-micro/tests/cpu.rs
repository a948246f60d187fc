//! The CPU renderer's promises: a flat triangle renders what the texture, marched directly in
//! world space over the triangle, shows; nothing is drawn outside the shell; shading has no
//! step across a shared edge; frames do not depend on the thread count.

use fathom_core::frame::Frame;
use fathom_core::primitives::Primitive;
use fathom_core::scene::{Call, Node, Scene};
use fathom_core::transforms::Transform;
use fathom_core::{Camera, Evaluator, Tape, V3};
use fathom_micro::march::{self, MarchParams, Scratch};
use fathom_micro::mesh::{self, RawMesh, TriangleMesh};
use fathom_micro::shade::Lighting;
use fathom_micro::{Cell, MicroScene, RenderOptions, Shell, Texture, Tiling};
use glam::{DVec2, DVec3};

fn at(p: [f64; 3]) -> Call<fathom_core::scene::DomainOp> {
    Call::new(Transform::Translate).with("offset", &p).into()
}

fn scene_of(root: Node) -> Scene {
    Scene::new(root)
}

fn options(w: u32, h: u32, eye: DVec3, target: DVec3) -> RenderOptions {
    RenderOptions {
        width: w,
        height: h,
        camera: Camera {
            eye,
            target,
            up: DVec3::Y,
            fov: 40.0,
        },
        ..Default::default()
    }
}

fn micro(mesh: &TriangleMesh, height: f64, tiling: &Tiling, tex: &Scene) -> MicroScene {
    let shell = Shell::build(mesh, height, tiling).unwrap();
    let texture = Texture::from_scene(tex, "test").unwrap();
    MicroScene::new(shell, texture, Lighting::from_scene(tex), None)
}

/// UVs mapping the triangle's x and z into one tile: u = A (x + 1), v = A (z + 1).
const A: f64 = 0.499;
const H: f64 = 0.5;

fn flat_triangle() -> TriangleMesh {
    let p = [
        DVec3::new(-1.0, 0.0, -1.0),
        DVec3::new(-1.0, 0.0, 1.0),
        DVec3::new(1.0, 0.0, -1.0),
    ];
    let raw = RawMesh {
        positions: p.to_vec(),
        triangles: vec![[0, 1, 2]],
        corner_normals: Some(vec![[DVec3::Y; 3]]),
        corner_uvs: Some(vec![
            p.map(|q| DVec2::new(A * (q.x + 1.0), A * (q.z + 1.0))),
        ]),
    };
    TriangleMesh::build(raw, None, "flat").unwrap().0
}

#[test]
fn flat_triangle_matches_the_texture_marched_in_world_space() {
    // With one tile spanning the triangle and a cell as tall as the scale needs, the shell map
    // is the similarity q = s p + c: the world-space field is d(q(p)) / s, clipped to the prism.
    let s = 2.0 * A;
    let tiling = Tiling {
        tiles: 1.0,
        cell: Cell {
            min: DVec3::splat(-1.0),
            max: DVec3::new(1.0, -1.0 + s * H, 1.0),
        },
    };
    let tex = scene_of(
        Node::new(Primitive::Empty)
            .child(
                Node::new(Call::new(Primitive::Sphere).with("radius", &[0.35]))
                    .op(at([-0.3, -0.95, -0.35])),
            )
            .child(
                Node::new(
                    Call::new(Primitive::Torus)
                        .with("major", &[0.25])
                        .with("minor", &[0.07]),
                )
                .op(at([-0.55, -0.75, 0.3])),
            )
            .child(
                Node::new(Call::new(Primitive::Box).with("size", &[0.15, 0.4, 0.15]))
                    .op(at([-0.05, -0.8, -0.05])),
            ),
    );
    let m = micro(&flat_triangle(), H, &tiling, &tex);
    // A tight hit threshold on both sides, so the two marchers stop at the same surface.
    let o = RenderOptions {
        pixel_epsilon: 0.02,
        ..options(
            96,
            72,
            DVec3::new(1.0, 1.7, 1.9),
            DVec3::new(-0.35, 0.1, -0.35),
        )
    };
    let (shell_frame, stats) = fathom_micro::render(&m, &o, &|_, _| {}).unwrap();
    assert!(stats.texture_hits > 300, "{stats:?}");

    // The reference: sphere tracing max(texture / s, prism) in world space.
    let tape = Tape::compile(&tex).unwrap();
    let c = DVec3::new(-1.0 + s, -1.0, -1.0 + s);
    let field = |ev: &mut Evaluator<f64>, p: DVec3| {
        let q = c + p * s;
        let d = ev.distance(&tape, V3::new(q.x, q.y, q.z)) / s;
        let prism = (-p.y)
            .max(p.y - H)
            .max(-1.0 - p.x)
            .max(-1.0 - p.z)
            .max((p.x + p.z) / 2f64.sqrt());
        d.max(prism)
    };
    let cam = o.camera.frame();
    let p = o.march_params();
    let mut ev = Evaluator::<f64>::new();
    let (mut agree, mut depth_ok, mut both) = (0, 0, 0);
    for y in 0..o.height {
        for x in 0..o.width {
            let d = cam.ray_dir(x as f64 + 0.5, y as f64 + 0.5, o.width, o.height);
            let mut t = 0.0;
            let mut hit = None;
            for _ in 0..2000 {
                let dist = field(&mut ev, cam.eye + d * t);
                if dist < p.eps_slope * t {
                    hit = Some(t);
                    break;
                }
                t += dist;
                if t > 20.0 {
                    break;
                }
            }
            let i = shell_frame.index(x, y);
            let got = shell_frame.depth[i];
            agree += (hit.is_some() == got.is_finite()) as u32;
            if let Some(t) = hit
                && got.is_finite()
            {
                both += 1;
                depth_ok += ((got as f64 - t).abs() < 2e-3 * t) as u32;
            }
        }
    }
    let n = (o.width * o.height) as f64;
    assert!(
        agree as f64 >= 0.99 * n,
        "hit masks agree on {agree} of {n} pixels"
    );
    assert!(
        depth_ok as f64 >= 0.99 * both as f64,
        "depths agree on {depth_ok} of {both} common hits"
    );
}

fn plane_through(offset_y: f64, normal: [f64; 3]) -> Scene {
    scene_of(
        Node::new(Call::new(Primitive::Plane).with("normal", &normal)).op(at([0.0, offset_y, 0.0])),
    )
}

#[test]
fn no_detail_appears_outside_the_shell() {
    let (mesh, _) = TriangleMesh::build(mesh::bush::raw(6), None, "bush").unwrap();
    let tiling = Tiling::default();
    let o = options(80, 60, DVec3::new(2.2, 1.6, 3.2), DVec3::ZERO);
    // The shell's own coverage: a texture solid everywhere below y = 10 is hit where a ray
    // first enters the shell.
    let cover = micro(&mesh, 0.15, &tiling, &plane_through(10.0, [0.0, 1.0, 0.0]));
    let (cov, _) = fathom_micro::render(&cover, &o, &|_, _| {}).unwrap();
    // A big sphere poking into one corner of every tile and reaching far beyond the shell: a
    // ray that missed it inside the shell and went on marching would find it outside.
    let ball = scene_of(
        Node::new(Call::new(Primitive::Sphere).with("radius", &[1.1])).op(at([0.9, 1.0, 0.9])),
    );
    let tex = micro(&mesh, 0.15, &tiling, &ball);
    let (f, _) = fathom_micro::render(&tex, &o, &|_, _| {}).unwrap();
    let (mut outside, mut hits, mut covered) = (0, 0, 0);
    for i in 0..f.len() {
        covered += cov.is_hit(i) as u32;
        if f.is_hit(i) {
            hits += 1;
            if !cov.is_hit(i) || f.depth[i] < cov.depth[i] * (1.0 - 1e-6) {
                outside += 1;
            }
        }
    }
    assert_eq!(
        outside, 0,
        "{outside} pixels show texture outside the shell"
    );
    // Not trivial: the ball is hit in many tiles and missed in many.
    assert!(
        hits > covered / 5 && hits < covered * 9 / 10,
        "{hits} hits of {covered} covered"
    );
}

fn roof() -> TriangleMesh {
    let p = [
        DVec3::new(0.0, 0.0, 0.0),
        DVec3::new(0.0, 0.0, 1.0),
        DVec3::new(1.0, -0.5, 0.5),
        DVec3::new(-1.0, -0.5, 0.5),
    ];
    let uv = |q: DVec3| DVec2::new(0.45 * q.x + 0.5, 0.45 * q.z + 0.5);
    let tris = [[0usize, 1, 2], [1, 0, 3]];
    let raw = RawMesh {
        positions: p.to_vec(),
        triangles: tris.iter().map(|t| t.map(|i| i as u32)).collect(),
        corner_normals: None,
        corner_uvs: Some(tris.iter().map(|t| t.map(|i| uv(p[i]))).collect()),
    };
    TriangleMesh::build(raw, None, "roof").unwrap().0
}

#[test]
fn shading_is_continuous_across_a_shared_edge() {
    // A flat layer half way up the shell of a ridge of two triangles.
    let tex = plane_through(0.0, [0.0, 1.0, 0.0]);
    let m = micro(&roof(), 0.1, &Tiling::default(), &tex);
    let params = MarchParams {
        max_steps: 1000,
        eps_slope: 1e-5,
        eps_min: 1e-7,
    };
    let mut s = Scratch::default();
    let normal_at = |s: &mut Scratch, x: f64, rotate: bool| {
        let (o, d) = (DVec3::new(x, 1.0, 0.7), DVec3::NEG_Y);
        let r = march::trace(&m.shell, &m.bvh, &m.texture, false, s, o, d, 10.0, &params);
        let hit = r.hit.expect("the layer is hit");
        march::surface(&m.shell, &m.texture, &mut s.ev, &hit, o, d, 1e-4, rotate).0
    };
    let deg = |a: DVec3, b: DVec3| a.angle_between(b).to_degrees();
    let (l, r) = (
        normal_at(&mut s, -1e-4, true),
        normal_at(&mut s, 1e-4, true),
    );
    assert!(
        deg(l, r) < 0.1,
        "step of {} degrees across the edge",
        deg(l, r)
    );
    // Away from the edge the normal turns with the surface, smoothly.
    let (l2, r2) = (normal_at(&mut s, -0.3, true), normal_at(&mut s, 0.3, true));
    assert!(deg(l2, r2) > 5.0);
    // Without the rotation the texture's own normals show the facets.
    let (lf, rf) = (
        normal_at(&mut s, -1e-4, false),
        normal_at(&mut s, 1e-4, false),
    );
    assert!(
        deg(lf, rf) > 10.0,
        "the unrotated normals step by {} degrees",
        deg(lf, rf)
    );
}

#[test]
fn frames_do_not_depend_on_the_thread_count() {
    let demo = fathom_micro::demo::load("bush").unwrap();
    let shell = Shell::build(&demo.mesh, demo.shell_height, &demo.tiling).unwrap();
    let tex = Texture::from_scene(&demo.texture, "bush").unwrap();
    let m = MicroScene::new(
        shell,
        tex,
        Lighting::from_scene(&demo.texture),
        Some(demo.base.clone()),
    );
    let o = options(64, 48, DVec3::new(1.6, 1.2, 2.6), DVec3::ZERO);
    let run = |threads| -> Frame {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        pool.install(|| fathom_micro::render(&m, &o, &|_, _| {}).unwrap().0)
    };
    let (a, b) = (run(1), run(2));
    assert_eq!(a, b);
    // The base mesh shows between the leaves, and only when asked for.
    let base = (0..a.len())
        .filter(|&i| a.id[i] == fathom_micro::render::BASE_ID)
        .count();
    assert!(base > 20, "{base} base pixels");
}
