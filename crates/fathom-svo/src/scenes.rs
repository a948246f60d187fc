//! Code-built scenes for the zoom presets and the tests: the Menger sponge as an IFS of folds
//! on a box, and a sphere. (The Mandelbulb comes from fathom-core's presets.)

use fathom_core::primitives::Primitive;
use fathom_core::scene::{Call, Ifs, Material, Node, Scene};
use fathom_core::transforms::Transform;
use glam::DVec3;

/// The Menger sponge spanning `[-1, 1]^3` as an IFS: per iteration abs + sort (x >= y >= z),
/// scale by 3 about (1, 1, 1), then fold z about -1 (`z -> |z + 1| - 1`), which is the
/// classic conditional `if z < -1 { z += 2 }` up to the sign the next abs removes. The result
/// is a distance bound (folds are 1-Lipschitz).
pub fn menger(iterations: u32) -> Scene {
    let ops = vec![
        Call::new(Transform::FoldMenger),
        Call::new(Transform::ScaleAbout)
            .with("factor", &[3.0])
            .with("centre", &[1.0, 1.0, 1.0]),
        Call::new(Transform::Translate).with("offset", &[0.0, 0.0, -1.0]),
        Call::new(Transform::FoldAbs),
        Call::new(Transform::Translate).with("offset", &[0.0, 0.0, 1.0]),
    ];
    let root =
        Node::new(Call::new(Primitive::Box).with("size", &[1.0, 1.0, 1.0])).material(Material {
            albedo: [0.8, 0.75, 0.65],
            trap_colour: 0.35,
            ..Material::default()
        });
    let mut s = Scene::new(root);
    s.ifs = Some(Ifs { iterations, ops });
    s.camera.eye = DVec3::new(2.6, 2.0, 3.2);
    s.camera.target = DVec3::ZERO;
    s
}

/// A sphere of radius `r` at the origin.
pub fn sphere(r: f64) -> Scene {
    Scene::new(Node::new(Call::new(Primitive::Sphere).with("radius", &[r])))
}

#[cfg(test)]
mod tests {
    use super::*;
    use fathom_core::Tape;

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
        assert!((d([3.0, 0.5, 0.5]) - 2.0).abs() < 1e-9);
    }
}
