//! Meshes of shapes with known surfaces: Hausdorff distance within a voxel, closed manifolds,
//! outward orientation, culled streaming equal to the in-memory dense mesh, and limits refused
//! before allocation.

use crate::check::{self, EdgeReport};
use crate::{IsoMesh, IsoMeshError, MeshOptions, Method, mesh, plan};
use fathom_core::primitives::Primitive;
use fathom_core::scene::Scene;
use fathom_core::transforms::Transform;
use fathom_core::{Call, Node, Tape};
use glam::DVec3;

/// A shape with its exact signed distance.
struct Known {
    name: &'static str,
    scene: Scene,
    sdf: fn(DVec3) -> f64,
}

fn known() -> Vec<Known> {
    // Off-grid placements so no surface sits exactly on grid planes.
    let t = [0.031, -0.017, 0.023];
    let place = |n: Node| n.op(Call::new(Transform::Translate).with("offset", &t));
    vec![
        Known {
            name: "sphere",
            scene: Scene::new(place(Node::new(
                Call::new(Primitive::Sphere).with("radius", &[0.9]),
            ))),
            sdf: |p| (p - DVec3::new(0.031, -0.017, 0.023)).length() - 0.9,
        },
        Known {
            name: "box",
            scene: Scene::new(place(Node::new(
                Call::new(Primitive::Box).with("size", &[0.8, 0.6, 0.7]),
            ))),
            sdf: |p| {
                let q = (p - DVec3::new(0.031, -0.017, 0.023)).abs() - DVec3::new(0.8, 0.6, 0.7);
                q.max(DVec3::ZERO).length() + q.max_element().min(0.0)
            },
        },
        Known {
            name: "torus",
            scene: Scene::new(place(Node::new(
                Call::new(Primitive::Torus)
                    .with("major", &[0.8])
                    .with("minor", &[0.3]),
            ))),
            sdf: |p| {
                let q = p - DVec3::new(0.031, -0.017, 0.023);
                (glam::DVec2::new(q.x, q.z).length() - 0.8).hypot(q.y) - 0.3
            },
        },
    ]
}

fn opts(method: Method, resolution: u32) -> MeshOptions {
    MeshOptions {
        bounds: Some((DVec3::splat(-1.25), DVec3::splat(1.25))),
        resolution,
        method,
        ..MeshOptions::default()
    }
}

fn run(scene: &Scene, o: &MeshOptions) -> (IsoMesh, crate::MeshStats) {
    let tape = Tape::compile(scene).unwrap();
    let p = plan(scene, &tape, o).unwrap();
    let mut m = IsoMesh::default();
    let s = mesh(scene, &tape, &p, o, &mut m, &|_, _| {}).unwrap();
    (m, s)
}

/// Points on the true surface: random directions pushed onto the zero set.
fn surface_samples(sdf: &dyn Fn(DVec3) -> f64, n: usize) -> Vec<DVec3> {
    let mut s = 0x9e37_79b9_7f4a_7c15u64;
    let mut next = move || {
        s ^= s << 13;
        s ^= s >> 7;
        s ^= s << 17;
        (s >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
    };
    (0..n)
        .map(|_| check::project(sdf, DVec3::new(next(), next(), next())))
        .filter(|p| sdf(*p).abs() < 1e-9)
        .collect()
}

#[test]
fn known_shapes_are_within_a_voxel_and_closed_manifolds() {
    for k in known() {
        let samples = surface_samples(&k.sdf, 600);
        assert!(samples.len() > 500, "{}", k.name);
        for method in Method::ALL {
            let o = opts(method, 40);
            let (m, stats) = run(&k.scene, &o);
            let h = stats.voxel;
            let (to_surface, to_mesh) = check::hausdorff(&m, &k.sdf, &samples, h);
            assert!(
                to_surface < h && to_mesh < h,
                "{} {}: Hausdorff {to_surface:.4} / {to_mesh:.4} vs voxel {h:.4}",
                k.name,
                method.name()
            );
            let e = check::edges(&m.tris);
            assert!(
                e.is_closed_manifold(),
                "{} {}: {e:?}",
                k.name,
                method.name()
            );
            assert_eq!(stats.missing_faces, 0);
            let v = check::volume(&m);
            assert!(
                v > 0.0,
                "{} {}: faces point inward ({v})",
                k.name,
                method.name()
            );
        }
    }
}

#[test]
fn dual_contouring_keeps_the_box_corners() {
    let k = &known()[1];
    let c = DVec3::new(0.031, -0.017, 0.023) + DVec3::new(0.8, 0.6, 0.7);
    let nearest = |method| {
        let (m, s) = run(&k.scene, &opts(method, 24));
        let d = m
            .verts
            .iter()
            .map(|v| (glam::Vec3::from(v.p).as_dvec3() - c).length())
            .fold(f64::INFINITY, f64::min);
        d / s.voxel
    };
    let (dc, sn) = (
        nearest(Method::DualContouring),
        nearest(Method::SurfaceNets),
    );
    // Surface nets round the corner off by a good fraction of a voxel.
    assert!(
        dc < 0.1 && sn > 0.2,
        "nearest vertex: dc {dc} sn {sn} voxels"
    );
}

/// Triangles as sorted position triples, independent of vertex numbering.
fn triangle_set(m: &IsoMesh) -> Vec<[[u32; 3]; 3]> {
    let mut v: Vec<[[u32; 3]; 3]> = m
        .tris
        .iter()
        .map(|t| {
            let mut p = t.map(|i| m.verts[i as usize].p.map(f32::to_bits));
            // Rotate so the smallest comes first, keeping the winding.
            let k = (0..3).min_by_key(|&i| p[i]).unwrap();
            p.rotate_left(k);
            p
        })
        .collect();
    v.sort_unstable();
    v
}

fn menger() -> Scene {
    fathom_core::presets::load("menger").unwrap()
}

#[test]
fn streaming_export_equals_the_in_memory_export() {
    for (scene, name) in [(menger(), "menger"), (known().remove(2).scene, "torus")] {
        for method in Method::ALL {
            let mut o = opts(method, 45);
            o.bounds = Some((DVec3::new(-1.6, -1.5, -1.55), DVec3::new(1.7, 1.6, 1.5)));
            let (streamed, s) = run(&scene, &o);
            o.in_memory = true;
            let (dense, _) = run(&scene, &o);
            assert!(
                s.bricks_meshed < s.bricks_total,
                "{name}: nothing was culled"
            );
            assert_eq!(
                triangle_set(&streamed),
                triangle_set(&dense),
                "{name} {}",
                method.name()
            );
            assert_eq!(streamed.verts.len(), dense.verts.len());
        }
    }
}

#[test]
fn cut_objects_are_closed_off_at_the_bounds() {
    let scene = menger();
    let mut o = opts(Method::MarchingCubes, 30);
    o.bounds = Some((DVec3::splat(-0.7), DVec3::splat(0.7)));
    let (m, _) = run(&scene, &o);
    assert!(check::edges(&m.tris).is_closed_manifold());
    assert!(
        m.verts
            .iter()
            .all(|v| v.p.iter().all(|c| c.abs() <= 0.7 + 1e-6))
    );
}

#[test]
fn oversized_runs_are_refused_before_allocation_with_an_estimate() {
    let scene = menger();
    let tape = Tape::compile(&scene).unwrap();
    let t = std::time::Instant::now();
    let mut o = opts(Method::MarchingCubes, 1 << 16);
    o.max_memory = 64 << 20;
    let e = plan(&scene, &tape, &o).unwrap_err();
    assert!(matches!(e, IsoMeshError::Memory { .. }), "{e}");
    let msg = e.to_string();
    assert!(
        msg.contains("bricks per layer") && msg.contains("--max-memory"),
        "{msg}"
    );
    o.resolution = (1 << 16) + 1;
    assert!(matches!(
        plan(&scene, &tape, &o),
        Err(IsoMeshError::Resolution(_))
    ));
    assert!(t.elapsed().as_secs_f64() < 20.0);
}

#[test]
fn fitted_bounds_hold_the_object_and_planes_are_refused() {
    let k = &known()[0];
    let tape = Tape::compile(&k.scene).unwrap();
    let (lo, hi) = crate::fit::fit_bounds(&k.scene, &tape).unwrap();
    assert!(
        lo.max_element() < -0.85 && hi.min_element() > 0.9,
        "{lo} {hi}"
    );
    assert!(
        lo.min_element() > -1.2 && hi.max_element() < 1.2,
        "{lo} {hi}"
    );
    let plane = Scene::new(Node::new(Primitive::Plane));
    let tape = Tape::compile(&plane).unwrap();
    assert!(crate::fit::fit_bounds(&plane, &tape).is_err());
}

#[test]
fn vertex_colours_follow_materials() {
    let mut scene = known().remove(0).scene;
    scene.root.material.albedo = [1.0, 0.0, 0.0];
    let (m, _) = run(&scene, &opts(Method::SurfaceNets, 16));
    assert!(
        m.verts.iter().all(|v| v.colour == [255, 0, 0]),
        "{:?}",
        m.verts[0]
    );
}

/// The spheres proptest found in CI: marching cubes fanned a loop that crosses an
/// ambiguous face twice through a diagonal joining that face's two segments; the neighbour
/// across the face drew triangles on it too, and the edge was in more than two triangles.
#[test]
fn two_spheres_touching_an_ambiguous_face_stay_manifold() {
    let spheres = [
        (
            -0.07220454430229124,
            -0.14304910718947808,
            -0.2902556954041778,
            0.4283117649658253,
        ),
        (
            0.543088125427086,
            -0.49881917524634906,
            0.03301199618396629,
            0.34501039901639785,
        ),
    ];
    let mut root = Node::new(Call::new(Primitive::Sphere).with("radius", &[0.01]));
    for (x, y, z, r) in spheres {
        root = root.child(
            Node::new(Call::new(Primitive::Sphere).with("radius", &[r]))
                .op(Call::new(Transform::Translate).with("offset", &[x, y, z])),
        );
    }
    let (m, _) = run(&Scene::new(root), &opts(Method::MarchingCubes, 20));
    let e = check::edges(&m.tris);
    assert!(e.is_closed_manifold(), "{e:?}");
}

proptest::proptest! {
    #![proptest_config(proptest::prelude::ProptestConfig::with_cases(12))]
    /// Random unions of spheres (touching, nested, thin gaps): marching cubes is always a
    /// closed manifold; the dual methods always closed and oriented.
    #[test]
    fn random_sphere_unions_are_closed(
        spheres in proptest::collection::vec(
            (-0.8f64..0.8, -0.8f64..0.8, -0.8f64..0.8, 0.05f64..0.5), 1..6)
    ) {
        let mut root = Node::new(Call::new(Primitive::Sphere).with("radius", &[0.01]));
        for (x, y, z, r) in spheres {
            root = root.child(
                Node::new(Call::new(Primitive::Sphere).with("radius", &[r]))
                    .op(Call::new(Transform::Translate).with("offset", &[x, y, z])),
            );
        }
        let scene = Scene::new(root);
        for method in Method::ALL {
            let (m, s) = run(&scene, &opts(method, 20));
            let e: EdgeReport = check::edges(&m.tris);
            proptest::prop_assert_eq!(s.missing_faces, 0);
            proptest::prop_assert_eq!(e.boundary, 0, "{} {:?}", method.name(), e);
            proptest::prop_assert_eq!(e.misoriented, 0, "{} {:?}", method.name(), e);
            if method == Method::MarchingCubes {
                proptest::prop_assert!(e.is_closed_manifold(), "{:?}", e);
            }
        }
    }
}
