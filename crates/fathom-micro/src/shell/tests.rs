use super::*;
use crate::mesh;
use crate::texture::Cell;
use glam::DVec2;

fn tiling() -> Tiling {
    Tiling::default()
}

#[test]
fn closed_meshes_give_crack_free_shells() {
    for name in ["bush", "teapot"] {
        let (m, _) = mesh::load(name, None).unwrap();
        let s = Shell::build(&m, 0.02, &tiling()).unwrap();
        let r = &s.report;
        assert_eq!(r.overfull_faces, 0, "{name}: {r:?}");
        // Every face has one or two tetrahedra; a face with one lies on the base, on the top,
        // or on a side over a boundary edge of the mesh. Inconsistent diagonals would leave
        // extra one-sided faces on interior edges.
        let boundary_edges = {
            let mut c: HashMap<(u32, u32), u32> = HashMap::new();
            for t in &m.triangles {
                for k in 0..3 {
                    let (a, b) = (t[k], t[(k + 1) % 3]);
                    *c.entry((a.min(b), a.max(b))).or_default() += 1;
                }
            }
            c.values().filter(|&&n| n == 1).count()
        };
        let expected = 2 * m.triangles.len() + 2 * boundary_edges;
        if r.skipped_inverted == 0 {
            assert_eq!(r.boundary_faces, expected, "{name}: {r:?}");
        } else {
            // Each skipped tetrahedron can expose at most its four faces.
            assert!(
                r.boundary_faces <= expected + 4 * r.skipped_inverted,
                "{name}: {r:?}"
            );
        }
        if name == "bush" {
            assert_eq!(
                (boundary_edges, r.skipped_inverted),
                (0, 0),
                "the bush is closed and smooth"
            );
            assert_eq!(r.tetrahedra, 3 * m.triangles.len());
        }
        // Neighbours are symmetric.
        for (t, nb) in s.neighbours.iter().enumerate() {
            for &o in nb.iter().filter(|&&o| o != NONE) {
                assert!(s.neighbours[o as usize].contains(&(t as u32)));
            }
        }
    }
}

#[test]
fn shell_coordinates_and_the_lipschitz_factor_hold() {
    let (m, _) = mesh::load("bush", None).unwrap();
    let t = Tiling {
        tiles: 1.0,
        cell: Cell {
            min: DVec3::new(-1.0, 0.0, -2.0),
            max: DVec3::new(1.0, 0.5, 2.0),
        },
    };
    let s = Shell::build(&m, 0.05, &t).unwrap();
    let mut rng = fathom_core::rng::SplitMix64(5);
    let mut tightest: f64 = 0.0;
    for tet in s.tets.iter().step_by(37) {
        // Vertices map to their own shell coordinates; h is 0 below and 1 on top.
        for k in 0..4 {
            let b = tet.bary(tet.verts[k]);
            assert!((tet.shell_at(&b) - tet.tex[k]).length() < 1e-9);
            assert_eq!(tet.tex[k].y, if tet.top[k] { 1.0 } else { 0.0 });
        }
        // |q(p1) - q(p2)| <= L |p1 - p2| for points inside, and L is not wildly loose.
        let scene = |p: DVec3| t.scene_point(tet.shell_at(&tet.bary(p)), 0.0, 0.0);
        let inside = |rng: &mut fathom_core::rng::SplitMix64| {
            let w: [f64; 4] = std::array::from_fn(|_| rng.unit() + 1e-3);
            let sum: f64 = w.iter().sum();
            (0..4).map(|k| tet.verts[k] * (w[k] / sum)).sum::<DVec3>()
        };
        for _ in 0..20 {
            let (a, b) = (inside(&mut rng), inside(&mut rng));
            let ratio = (scene(a) - scene(b)).length() / (a - b).length();
            assert!(
                ratio <= tet.lipschitz * (1.0 + 1e-9),
                "{ratio} > {}",
                tet.lipschitz
            );
            tightest = tightest.max(ratio / tet.lipschitz);
        }
    }
    assert!(
        tightest > 0.5,
        "the factor is far above any stretch seen: {tightest}"
    );
}

#[test]
fn bad_shell_heights_are_refused_with_the_range() {
    let (m, _) = mesh::load("bush", None).unwrap();
    for h in [0.0, -0.1, f64::NAN, 100.0] {
        let e = Shell::build(&m, h, &tiling()).unwrap_err().to_string();
        assert!(
            e.contains("shell height") && e.contains("bounding-box diagonal"),
            "{e}"
        );
        // The height itself is reported, not its ratio to the diagonal.
        if h.is_finite() {
            assert!(e.contains(&format!("shell height = {h} ")), "{e}");
        }
    }
    let bad = Tiling {
        tiles: 0.0,
        ..tiling()
    };
    assert!(
        Shell::build(&m, 0.05, &bad)
            .unwrap_err()
            .to_string()
            .contains("tiles")
    );
}

#[test]
fn folded_prisms_are_skipped_and_counted() {
    // A valley whose outer vertices' normals lean across it: offset far enough, they cross
    // over the crease and the prisms turn inside out.
    let raw = mesh::RawMesh {
        positions: vec![
            DVec3::new(0.0, 0.0, 0.0),
            DVec3::new(0.0, 0.0, 1.0),
            DVec3::new(1.0, 0.35, 0.5),
            DVec3::new(-1.0, 0.35, 0.5),
        ],
        triangles: vec![[0, 1, 2], [1, 0, 3]],
        corner_normals: Some(vec![
            [DVec3::Y, DVec3::Y, DVec3::new(-1.0, 0.05, 0.0)],
            [DVec3::Y, DVec3::Y, DVec3::new(1.0, 0.05, 0.0)],
        ]),
        corner_uvs: Some(vec![[DVec2::ZERO, DVec2::Y, DVec2::X]; 2]),
    };
    let (m, _) = mesh::TriangleMesh::build(raw, None, "crease").unwrap();
    let ok = Shell::build(&m, 0.01, &tiling()).unwrap();
    assert_eq!(ok.report.skipped_inverted, 0);
    let folded = Shell::build(&m, 1.1, &tiling()).unwrap();
    assert!(folded.report.skipped_inverted > 0, "{:?}", folded.report);
}
