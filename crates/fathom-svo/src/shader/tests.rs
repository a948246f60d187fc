//! Tests of the shader: four lanes against one, surface points and planes, lines of sight.

use super::shading::onto_surface;
use super::sight::{Sight, SightLine};
use super::*;
use crate::generate::DEFAULT_MARGIN;
use crate::plane::SurfacePlane;
use fathom_core::camera_path::path_preset;

#[test]
fn a_plane_point_is_moved_onto_the_zero_of_a_linear_distance() {
    // A distance that is linear with any slope (estimates are scaled distances): one
    // Newton step lands on its zero, from either side; a step longer than the half side
    // is cut to it, and a vanishing or broken gradient leaves the point where it is.
    let n = DVec3::new(0.3, -0.5, 0.8);
    let field = |x: DVec3| 2.5 * (n.dot(x) - 0.1);
    let g = 2.5 * n;
    for p in [DVec3::new(0.2, 0.1, 0.3), DVec3::new(-0.1, 0.4, -0.2)] {
        let on = onto_surface(p, field(p), g, 1.0);
        assert!(field(on).abs() < 1e-12, "{p}: {} at {on}", field(on));
        let short = onto_surface(p, field(p), g, 0.01);
        assert!(((short - p).length() - 0.01).abs() < 1e-12, "{p}: {short}");
        assert!(
            field(short).abs() < field(p).abs(),
            "{p}: not toward the zero"
        );
        assert_eq!(onto_surface(p, field(p), DVec3::ZERO, 1.0), p);
        assert_eq!(onto_surface(p, f64::NAN, g, 1.0), p);
    }
}

#[test]
fn a_leaf_plane_passes_nearer_the_surface_than_its_shading_point() {
    // Voxels of several sizes around each zoom target: where the line of sight stopped
    // (the shading point) the distance may be up to a quarter side; the plane's point
    // nearest it, after the Newton step, must be much nearer the surface.
    for name in ["mandelbulb", "menger"] {
        let p = path_preset(name).unwrap();
        let mut sh = Shader::new(&p.scene, DEFAULT_MARGIN).unwrap();
        let t = p.path.target().unwrap();
        let eye = p.path.camera(0, 300, 1e15, 40.0).eye;
        sh.view = View {
            eye,
            scale: (t - eye).length(),
        };
        let mut pr = Probe::new();
        let (mut at_point, mut at_plane) = (Vec::new(), Vec::new());
        for h in [1e-2, 1e-3, 1e-4] {
            for k in 0..64 {
                let f = |i: u32| ((k * 7 + i * 13) % 17) as f64 / 8.0 - 1.0;
                let c = t + DVec3::new(f(1), f(2), f(3)) * (2.0 * h);
                let d = sh.distance(&mut pr, c);
                let s = sh.surface(&mut pr, c, h, d);
                if !s.plane.is_some() || s.plane.is_behind() {
                    continue;
                }
                let (m, off) = s.plane.decode();
                let q = s.p - m * (m.dot(s.p - c) - off * h);
                at_point.push(s.v.d.abs() / h);
                at_plane.push(sh.distance(&mut pr, q).abs() / h);
            }
        }
        let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len().max(1) as f64;
        let (a, b) = (mean(&at_point), mean(&at_plane));
        eprintln!(
            "{name}: {} planes; mean |distance| / half side: point {a:.4}, plane {b:.4}",
            at_plane.len()
        );
        assert!(at_plane.len() >= 40, "{name}: {} planes", at_plane.len());
        assert!(b < 0.5 * a, "{name}: plane {b} vs point {a}");
    }
}

/// A zoom preset's shader, its zoom target and a deep origin at the target (double-double
/// evaluation relative to it).
fn at_target(name: &str) -> (Shader, DVec3, Origin) {
    let p = path_preset(name).unwrap();
    let sh = Shader::new(&p.scene, DEFAULT_MARGIN).unwrap();
    let t = p.path.target().unwrap();
    let deep = Origin {
        hi: t,
        lo: DVec3::splat(1e-20),
        deep: true,
    };
    (sh, t, deep)
}

#[test]
fn four_surfaces_at_once_match_one_at_a_time() {
    // Voxels of several sizes around each zoom target, on shallow and deep frames: the
    // packet's surface points, values and colours are the scalar path's up to the
    // packet's rounding; a lane past `live` is left empty.
    for name in ["mandelbulb", "menger"] {
        let (mut sh, t, deep) = at_target(name);
        let mut pr = Probe::new();
        let mut traced = 0;
        let shallow = sh.origin;
        for h in [3e-2, 1e-3, 4e-5, 1e-6] {
            let c: [DVec3; 4] =
                std::array::from_fn(|k| t + DVec3::new(0.7, -0.4, 0.3) * (h * (k as f64 - 1.5)));
            for (origin, c) in [(shallow, c), (deep, c.map(|c| c - t))] {
                sh.origin = origin;
                let d = c.map(|c| sh.distance(&mut pr, c));
                for live in [4, 3] {
                    let four = sh.surfaces4(&mut pr, c, d, live, h);
                    // Shaded together, each surface takes the colour it takes alone.
                    let together = sh.shade4(&mut pr, std::array::from_fn(|k| &four[k]), live);
                    for k in 0..4 {
                        let what = format!("{name} h {h:e} deep {} lane {k}", origin.deep);
                        if k >= live {
                            assert_eq!(four[k].plane, SurfacePlane::NONE, "{what}");
                            continue;
                        }
                        let one = sh.surface(&mut pr, c[k], h, d[k]);
                        traced += sh.sight_point(&mut pr, c[k], h).is_some() as usize;
                        let moved = (four[k].p - one.p).length();
                        assert!(moved <= 1e-9 * h, "{what}: moved {moved:e}");
                        let dd = (four[k].v.d - one.v.d).abs();
                        assert!(dd <= 1e-9 * h, "{what}: distance off by {dd:e}");
                        let dt = (four[k].v.trap - one.v.trap).abs();
                        assert!(
                            dt <= 1e-9 * one.v.trap.abs().max(1.0),
                            "{what}: trap {dt:e}"
                        );
                        let a = sh.shade(&mut pr, &four[k]);
                        assert_eq!(together[k], a, "{what}: shaded together");
                        let b = sh.shade(&mut pr, &one);
                        for ch in 0..4 {
                            let (x, y) = ((a >> (8 * ch)) & 255, (b >> (8 * ch)) & 255);
                            assert!(x.abs_diff(y) <= 1, "{what}: colour {a:08x} against {b:08x}");
                        }
                    }
                }
            }
        }
        // Most of these voxels straddle the surface: their lines of sight find it.
        assert!(
            traced >= 40,
            "{name}: only {traced} of 56 lines of sight found it"
        );
    }
}

#[test]
fn a_voxel_its_line_of_sight_passes_shows_the_surface_behind_it() {
    // Voxels in front of the Mandelbulb zoom's target, on the line from the first
    // camera's eye to it, 4 to 10 half-diagonals short of it: the line of sight passes
    // each voxel and meets the surface near the target, past the voxel's bounding sphere.
    // The surface point is there (a Newton step from the centre would stay within one
    // half-diagonal of it), the plane is clear of the cube, and the packet path finds the
    // same points. On shallow and deep frames.
    let p = path_preset("mandelbulb").unwrap();
    let (mut sh, t, deep) = at_target("mandelbulb");
    let shallow = sh.origin;
    let eye = p.path.camera(0, 300, 1e15, 40.0).eye;
    let dist = (t - eye).length();
    let dir = (t - eye) / dist;
    let mut pr = Probe::new();
    for h in [1e-3 * dist, 1e-6 * dist] {
        let hd = h * 3f64.sqrt();
        let c: [DVec3; 4] = std::array::from_fn(|k| t - dir * (hd * (4.0 + 2.0 * k as f64)));
        for (origin, at) in [(shallow, DVec3::ZERO), (deep, t)] {
            sh.origin = origin;
            sh.view = View {
                eye: eye - at,
                scale: dist,
            };
            let c = c.map(|c| c - at);
            let d = c.map(|c| sh.distance(&mut pr, c));
            let four = sh.surfaces4(&mut pr, c, d, 4, h);
            for k in 0..4 {
                let what = format!("h {h:e} deep {} voxel {k}", origin.deep);
                let s = sh.surface(&mut pr, c[k], h, d[k]);
                let along = (s.p - c[k]).dot(dir);
                assert!(
                    along > hd,
                    "{what}: stopped {:.2} half-diagonals on",
                    along / hd
                );
                // Not past the target (the first surface on the line) by more than the
                // trace's stopping distance.
                let past = (s.p - (t - at)).dot(dir);
                assert!(
                    past <= 0.5 * h,
                    "{what}: {:.2} sides past the target",
                    past / h
                );
                assert!(s.v.d < 0.5 * h, "{what}: distance {:e} at the point", s.v.d);
                assert!(s.plane.is_clear(), "{what}: plane {:?}", s.plane);
                let moved = (four[k].p - s.p).length();
                assert!(moved <= 1e-9 * h, "{what}: packet point moved {moved:e}");
            }
        }
    }
}

#[test]
fn lines_of_sight_traced_in_two_stretches_reach_the_points_of_one() {
    // Lines of sight of voxels in front of the Mandelbulb zoom's target: traced to their
    // bounding spheres, then on in other lanes of another packet, they end at exactly the
    // points one trace reaches (eval_children traces on only the lines of the children it
    // keeps, regrouped four at a time).
    let p = path_preset("mandelbulb").unwrap();
    let (mut sh, t, _) = at_target("mandelbulb");
    let eye = p.path.camera(0, 300, 1e15, 40.0).eye;
    let dist = (t - eye).length();
    let dir = (t - eye) / dist;
    sh.view = View { eye, scale: dist };
    let mut pr = Probe::new();
    let h = 1e-3 * dist;
    let hd = h * 3f64.sqrt();
    let reach = hd * sh.sight_limits().0;
    let c: [DVec3; 4] = std::array::from_fn(|k| t - dir * (hd * (3.0 + 5.0 * k as f64)));
    let lines = sh.sight_lines(c, [true, true, false, true], h);
    let once = sh.trace4(&mut pr, lines, h, reach, false);
    let near = sh.trace4(&mut pr, lines, h, hd, true);
    let passed = near
        .iter()
        .filter(|s| matches!(s, Sight::Passed(_)))
        .count();
    assert!(passed >= 2, "{passed} lines passed their spheres");
    let on: [Option<SightLine>; 4] = std::array::from_fn(|k| match near[3 - k] {
        Sight::Passed(l) => Some(l),
        _ => None,
    });
    let far = sh.trace4(&mut pr, on, h, reach, false);
    for k in 0..4 {
        let two = match near[k] {
            Sight::Passed(_) => far[3 - k],
            s => s,
        };
        let (a, b) = (once[k].hit().map(|x| x.p), two.hit().map(|x| x.p));
        assert_eq!(a, b, "line {k}");
        assert_eq!(a.is_some(), k != 2, "line {k}: {:?}", once[k]);
        if let Sight::Passed(l) = near[k] {
            assert!(l.t > hd && l.steps >= 1, "line {k}: passed at {l:?}");
        }
        // The scalar trace's point, up to the packet's rounding.
        if let Some(a) = a {
            let scalar = sh.sight_point(&mut pr, c[k], h).expect("scalar trace").p;
            let moved = (scalar - a).length();
            assert!(moved <= 1e-9 * h, "line {k}: packet point moved {moved:e}");
        }
    }
}

#[test]
fn four_distances_at_once_match_one_at_a_time() {
    // Four lanes at once, f64 on shallow frames and double-double on deep ones: within a
    // few ulps of the scalar paths (the packets' transcendental functions are wide's,
    // not libm's).
    for name in ["mandelbulb", "menger"] {
        let (mut sh, t, deep) = at_target(name);
        let mut pr = Probe::new();
        let q: [DVec3; 4] = std::array::from_fn(|k| {
            t + DVec3::new(1e-3 * k as f64, -7e-4 * k as f64, 3e-4) - DVec3::splat(1e-4)
        });
        for (origin, q) in [(sh.origin, q), (deep, q.map(|q| q - t))] {
            sh.origin = origin;
            let four = sh.distance4(&mut pr, q);
            for k in 0..4 {
                let one = sh.distance(&mut pr, q[k]);
                assert!(
                    (four[k] - one).abs() <= 1e-13 * one.abs().max(1e-3),
                    "{name} lane {k} (deep {}): {} against {one}",
                    origin.deep,
                    four[k]
                );
            }
        }
    }
}
