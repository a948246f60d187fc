//! Every writer's file read back by an independent reader (ply-rs, stl_io, tobj, gltf) gives
//! the mesh that was streamed into it.

use super::create;
use crate::{IsoMesh, MeshOptions, Method, mesh, plan};
use fathom_core::primitives::Primitive;
use fathom_core::{Call, Node, Scene, Tape};
use glam::DVec3;
use std::path::PathBuf;

fn torus_mesh_into(path: Option<&std::path::Path>) -> IsoMesh {
    let scene = Scene::new(Node::new(
        Call::new(Primitive::Torus)
            .with("major", &[0.8])
            .with("minor", &[0.3]),
    ));
    let tape = Tape::compile(&scene).unwrap();
    let o = MeshOptions {
        bounds: Some((DVec3::splat(-1.2), DVec3::splat(1.2))),
        resolution: 24,
        method: Method::DualContouring,
        ..MeshOptions::default()
    };
    let p = plan(&scene, &tape, &o).unwrap();
    let mut m = IsoMesh::default();
    mesh(&scene, &tape, &p, &o, &mut m, &|_, _| {}).unwrap();
    if let Some(path) = path {
        let mut sink = create(path).unwrap();
        mesh(&scene, &tape, &p, &o, sink.as_mut(), &|_, _| {}).unwrap();
    }
    m
}

fn dir(tag: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("fathom-mesh-{tag}-{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d
}

#[test]
fn ply_reads_back_with_ply_rs() {
    let d = dir("ply");
    let path = d.join("t.ply");
    let m = torus_mesh_into(Some(&path));
    let mut f = std::fs::File::open(&path).unwrap();
    let parser = ply_rs::parser::Parser::<ply_rs::ply::DefaultElement>::new();
    let ply = parser.read_ply(&mut f).unwrap();
    let verts = &ply.payload["vertex"];
    let faces = &ply.payload["face"];
    assert_eq!((verts.len(), faces.len()), (m.verts.len(), m.tris.len()));
    use ply_rs::ply::Property;
    for (v, want) in verts.iter().zip(&m.verts).step_by(97) {
        let Property::Float(x) = v["x"] else { panic!() };
        let Property::UChar(r) = v["red"] else {
            panic!()
        };
        assert_eq!((x, r), (want.p[0], want.colour[0]));
    }
    for (f, want) in faces.iter().zip(&m.tris).step_by(89) {
        let Property::ListUInt(ref ids) = f["vertex_indices"] else {
            panic!()
        };
        assert_eq!(ids[..], want[..]);
    }
    assert!(
        std::fs::read_dir(&d).unwrap().count() == 1,
        "spool files left behind"
    );
    std::fs::remove_dir_all(&d).ok();
}

#[test]
fn stl_reads_back_with_stl_io() {
    let d = dir("stl");
    let path = d.join("t.stl");
    let m = torus_mesh_into(Some(&path));
    let mut f = std::fs::File::open(&path).unwrap();
    let stl = stl_io::read_stl(&mut f).unwrap();
    assert_eq!(stl.faces.len(), m.tris.len());
    for (face, want) in stl.faces.iter().zip(&m.tris).step_by(53) {
        for (&got, &w) in face.vertices.iter().zip(want) {
            assert_eq!(stl.vertices[got].0, m.verts[w as usize].p);
        }
    }
    std::fs::remove_dir_all(&d).ok();
}

#[test]
fn obj_reads_back_with_tobj() {
    let d = dir("obj");
    let path = d.join("t.obj");
    let m = torus_mesh_into(Some(&path));
    let (models, _) = tobj::load_obj(&path, &tobj::LoadOptions::default()).unwrap();
    let mm = &models[0].mesh;
    assert_eq!(mm.positions.len(), 3 * m.verts.len());
    assert_eq!(mm.indices.len(), 3 * m.tris.len());
    assert_eq!(mm.vertex_color.len(), 3 * m.verts.len());
    let pos = |i: u32| [0, 1, 2].map(|a| mm.positions[3 * i as usize + a]);
    let same = m
        .tris
        .iter()
        .enumerate()
        .all(|(k, t)| (0..3).all(|c| pos(mm.indices[3 * k + c]) == m.verts[t[c] as usize].p));
    assert!(same, "OBJ triangles differ from the mesh's");
    std::fs::remove_dir_all(&d).ok();
}

#[test]
fn glb_reads_back_with_gltf() {
    let d = dir("glb");
    let path = d.join("t.glb");
    let m = torus_mesh_into(Some(&path));
    let (doc, buffers, _) = gltf::import(&path).unwrap();
    let prim = doc.meshes().next().unwrap().primitives().next().unwrap();
    let r = prim.reader(|b| Some(&buffers[b.index()]));
    let pos: Vec<[f32; 3]> = r.read_positions().unwrap().collect();
    let idx: Vec<u32> = r.read_indices().unwrap().into_u32().collect();
    assert_eq!(pos.len(), m.verts.len());
    assert_eq!(pos[17], m.verts[17].p);
    let want: Vec<u32> = m.tris.iter().flatten().copied().collect();
    assert!(idx == want, "GLB indices differ from the mesh's");
    assert!(r.read_colors(0).is_some());
    std::fs::remove_dir_all(&d).ok();
}

#[test]
fn unknown_extensions_and_unwritable_paths_fail_at_once() {
    let e = create(std::path::Path::new("x.fbx"))
        .err()
        .unwrap()
        .to_string();
    assert!(e.contains(".ply, .stl, .obj, .glb"), "{e}");
    let e = create(std::path::Path::new("/nonexistent-dir/x.ply"))
        .err()
        .unwrap();
    assert!(matches!(e, crate::IsoMeshError::Write(_)), "{e}");
    assert!(e.to_string().contains("does not exist"), "{e}");
}

#[test]
fn an_unfinished_sink_leaves_the_old_file_and_no_spools() {
    let d = std::env::temp_dir().join(format!("fathom-mesh-unfinished-{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    for ext in ["ply", "stl", "obj", "glb"] {
        let path = d.join(format!("m.{ext}"));
        std::fs::write(&path, b"old").unwrap();
        let mut sink = create(&path).unwrap();
        let v = crate::Vertex {
            p: [0.0, 1.0, 2.0],
            colour: [1, 2, 3],
        };
        sink.vertices(&[v; 3]).unwrap();
        // A refused or failed run drops its sink without finishing it.
        drop(sink);
        assert_eq!(std::fs::read(&path).unwrap(), b"old", "{ext}");
        let left: Vec<_> = std::fs::read_dir(&d)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        assert_eq!(left.len(), 1, "{ext}: {left:?}");
        std::fs::remove_file(&path).unwrap();
    }
    std::fs::remove_dir_all(&d).ok();
}
