//! Code-built scenes for the zoom presets, benchmarks and tests of every crate: the Menger
//! sponge spanning exactly `[-1, 1]^3`, the Mandelbox, a sphere and a panorama (a ring over a
//! floor around the camera). (The scene-file presets are
//! in [`crate::presets`].)

use crate::combine::Combine;
use crate::fractals::Fractal;
use crate::primitives::Primitive;
use crate::registry::Family;
use crate::scene::{Call, Material, Node, Scene};
use crate::transforms::Transform;
use glam::DVec3;

/// The Menger sponge spanning `[-1, 1]^3` (fathom-core's `Menger` estimator, a distance
/// bound) with `iterations` levels of holes.
pub fn menger(iterations: u32) -> Scene {
    let shape = Call::new(Fractal::Menger).with("iterations", &[iterations as f64]);
    let root = Node::new(shape).material(Material {
        albedo: [0.8, 0.75, 0.65],
        trap_colour: 0.35,
        ..Material::default()
    });
    let mut s = Scene::new(root);
    s.camera.eye = DVec3::new(2.6, 2.0, 3.2);
    s.camera.target = DVec3::ZERO;
    s
}

/// A ring (a torus of radii 3 and 0.6 around the camera at the origin) over a floor one unit
/// below: every direction of a panorama sees geometry (the omni-directional stereo tests).
pub fn ring_over_floor() -> Scene {
    let floor = Node::new(Call::new(Primitive::Plane).with("normal", &[0.0, 1.0, 0.0]))
        .op(Call::new(Transform::Translate).with("offset", &[0.0, -1.0, 0.0]));
    let ring = Call::new(Primitive::Torus)
        .with("major", &[3.0])
        .with("minor", &[0.6]);
    let mut s = Scene::new(Node::new(ring).child(floor));
    s.camera.eye = DVec3::ZERO;
    s.camera.target = DVec3::new(0.3, 0.0, -1.0);
    s.render.max_distance = 50.0;
    s
}

/// The Mandelbox with fathom-core's default parameters (scale -1.5).
pub fn mandelbox() -> Scene {
    let mut s = Scene::new(Node::new(Call::new(Fractal::Mandelbox)));
    s.camera.eye = DVec3::new(3.0, 2.4, 4.2);
    s.camera.target = DVec3::ZERO;
    s
}

/// A sphere of radius `r` at the origin.
pub fn sphere(r: f64) -> Scene {
    Scene::new(Node::new(Call::new(Primitive::Sphere).with("radius", &[r])))
}

/// A 100-node tree mixing every primitive, several operators and every combine.
pub fn hundred_node_scene() -> Scene {
    let prims = Primitive::all();
    let combines = Combine::all();
    let mut root = Node::new(Primitive::Sphere);
    for i in 0..9 {
        let mut branch = Node::new(prims[(i * 7 + 1) % prims.len()])
            .combine(combines[i % combines.len()])
            .op(Call::new(Transform::Translate).with("offset", &[i as f64 * 0.3, 0.0, 0.0]));
        for j in 0..10 {
            let k = i * 10 + j;
            branch = branch.child(
                Node::new(prims[k % prims.len()])
                    .combine(combines[k % combines.len()])
                    .op(Call::new(Transform::Rotate).with("angle", &[k as f64]))
                    .op(Call::new(Transform::Scale).with("factor", &[0.5])),
            );
        }
        root = root.child(branch);
    }
    Scene::new(root)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Tape;

    #[test]
    fn menger_has_its_holes_and_corners() {
        let t = Tape::compile(&menger(8)).unwrap();
        let d = |p: [f64; 3]| t.eval_f64(p).d;
        // Corners and edge points are on the surface (distance ~0), the centre tunnel and the
        // face-centre holes are empty, points far out are far.
        assert!(d([1.0, 1.0, 1.0]).abs() < 1e-9);
        assert!(d([1.0, 1.0, 0.0]).abs() < 1e-9, "{}", d([1.0, 1.0, 0.0]));
        assert!(d([0.0, 0.0, 0.0]) > 0.3, "centre {}", d([0.0, 0.0, 0.0]));
        assert!(d([0.0, 0.0, 0.9]) > 0.3, "tunnel {}", d([0.0, 0.0, 0.9]));
        // The 1/3-scale hole in the face x = 1 centred at (1, 2/3, 2/3).
        assert!(d([1.0, 2.0 / 3.0, 2.0 / 3.0]) > 0.1);
        // A solid point: in the corner subcube at its own corner region.
        assert!(d([0.95, 0.95, 0.95]) <= 0.0 + 1e-12);
        assert!((d([3.0, 0.5, 0.5]) - 2.0).abs() < 1e-6);
        let b = Tape::compile(&mandelbox()).unwrap();
        for p in [[3.0, 0.0, 0.0], [0.0, 3.0, 0.0], [2.2, 2.2, 2.2]] {
            assert!(b.eval_f64(p).d > 0.0, "the Mandelbox reaches {p:?}");
        }
    }

    #[test]
    fn hundred_node_scene_has_a_hundred_nodes_and_compiles() {
        let s = hundred_node_scene();
        assert_eq!(s.root.count(), 100);
        Tape::compile(&s).unwrap();
    }
}
