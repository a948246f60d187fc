use super::*;
use crate::error::MeshLoadError;
use proptest::prelude::*;

const QUAD: &str = "# a unit quad in the xz plane, two triangles
v 0 0 0
v 1 0 0
v 1 0 1
v 0 0 1
vt 0 0
vt 1 0
vt 1 1
vt 0 1
vn 0 1 0
f 1/1/1 4/4/1 3/3/1 2/2/1
";

fn temp(name: &str, contents: &[u8]) -> std::path::PathBuf {
    let dir = std::env::temp_dir().join(format!("fathom-micro-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let p = dir.join(name);
    std::fs::write(&p, contents).unwrap();
    p
}

#[test]
fn obj_quad_loads_with_uvs_and_normals() {
    let raw = obj::parse(QUAD, "quad.obj").unwrap();
    assert_eq!(raw.triangles.len(), 2);
    let (m, r) = TriangleMesh::build(raw, None, "quad.obj").unwrap();
    assert_eq!((r.triangles, r.vertices, r.normals_computed), (2, 4, false));
    assert_eq!(r.uv_source, "file");
    assert!(m.normals.iter().all(|n| (*n - DVec3::Y).length() < 1e-12));
    assert!((0..2).all(|t| m.face_normal(t).dot(DVec3::Y) > 0.99));
    // A file on disk reads the same.
    let p = temp("quad.obj", QUAD.as_bytes());
    let (m2, _) = load(p.to_str().unwrap(), None).unwrap();
    assert_eq!(m2.triangles, m.triangles);
}

fn syntax(text: &str) -> (usize, usize, String) {
    match obj::parse(text, "bad.obj") {
        Err(MeshLoadError::Syntax { line, col, msg, .. }) => (line, col, msg),
        other => panic!("expected a syntax error for {text:?}, got {other:?}"),
    }
}

#[test]
fn bad_obj_lines_name_line_and_column() {
    let (l, c, m) = syntax("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\n");
    assert_eq!((l, c), (4, 7), "{m}");
    assert!(
        m.contains("vertex index 4 is out of range") && m.contains("3 defined"),
        "{m}"
    );
    let (l, c, m) = syntax("v 0 0 0\nv 1 zero 0\n");
    assert_eq!((l, c), (2, 5));
    assert!(
        m.contains("expected a number") && m.contains("`zero`"),
        "{m}"
    );
    let (l, _, m) = syntax("v 0 0\n");
    assert_eq!(l, 1);
    assert!(m.contains("needs 3 numbers"), "{m}");
    let (_, _, m) = syntax("v 0 0 0\nf 0 1 1\n");
    assert!(m.contains("index 0 is out of range"), "{m}");
    let (_, _, m) = syntax("v 0 0 0\nvt 0 0\nf 1/9 1/1 1/1\n");
    assert!(m.contains("texture coordinate index 9"), "{m}");
    let (_, _, m) = syntax("v 0 0 0\nf 1/2/3/4 1 1\n");
    assert!(m.contains("expected a face vertex"), "{m}");
    let (_, _, m) = syntax("v 1 2 3 0\n");
    assert!(m.contains("weight w"), "{m}");
    let (_, _, m) = syntax("v 1 2 3 1e39\n");
    assert!(m.contains("weight w") || m.contains("must not"), "{m}");
}

#[test]
fn missing_oversized_and_unknown_files_are_refused_clearly() {
    let e = load("/nonexistent/mesh.obj", None).unwrap_err().to_string();
    assert!(
        e.contains("/nonexistent/mesh.obj") && e.contains("cannot read"),
        "{e}"
    );
    let p = temp("huge.obj", b"");
    std::fs::File::options()
        .write(true)
        .open(&p)
        .unwrap()
        .set_len(limits::MAX_MESH_FILE_BYTES + 1)
        .unwrap();
    let e = load(p.to_str().unwrap(), None).unwrap_err();
    assert!(matches!(e, MeshLoadError::FileTooLarge { .. }), "{e}");
    let _ = std::fs::remove_file(&p);
    let e = load("thing.stl", None).unwrap_err().to_string();
    assert!(e.contains("obj, gltf, glb") && e.contains("teapot"), "{e}");
}

#[test]
fn meshes_over_the_size_limit_are_refused_before_allocation() {
    let mut text = String::from("v 0 0 0\nv 1 0 0\nv 0 1 0\n");
    // One face line with MAX_TRIANGLES + 2 corners fans into MAX_TRIANGLES triangles, then one
    // more face: the scan refuses it without tobj ever seeing it.
    text += "f";
    for _ in 0..limits::MAX_TRIANGLES + 2 {
        text += " 1";
    }
    text += "\nf 1 2 3\n";
    let e = obj::parse(&text, "big.obj").unwrap_err();
    assert!(
        matches!(
            e,
            MeshLoadError::TooLarge {
                what: "triangles",
                ..
            }
        ),
        "{e}"
    );
    assert!(e.to_string().contains(&limits::MAX_TRIANGLES.to_string()));
}

#[test]
fn bad_triangles_are_skipped_and_counted() {
    // Triangle 1 fine, 2 has a NaN vertex, 3 is degenerate (collinear), 4 repeats a vertex,
    // 5 has zero UV area; a sixth shares edge 1-2 with two others (non-manifold).
    let text = "v 0 0 0\nv 1 0 0\nv 0 0 1\nv nan 0 0\nv 2 0 0\nv 0 1 0\nv 1 1 1\nv 1 -1 1
vt 0 0\nvt 1 0\nvt 0 1\nvt 0.5 0.5
f 1/1 3/3 2/2
f 1/1 4/2 2/3
f 1/1 2/2 5/3
f 1/1 1/2 2/3
f 1/4 2/4 6/4
f 1/1 2/2 7/3
f 2/1 1/2 8/3
";
    let raw = obj::parse(text, "mixed.obj").unwrap();
    let (m, r) = TriangleMesh::build(raw, None, "mixed.obj").unwrap();
    assert_eq!(r.input_triangles, 7);
    assert_eq!(
        (
            r.skipped_non_finite,
            r.skipped_degenerate,
            r.skipped_zero_uv_area
        ),
        (1, 2, 1),
        "{r}"
    );
    assert_eq!(r.triangles, 3);
    assert_eq!(r.non_manifold_edges, 1, "{r}");
    assert!(m.positions.iter().all(|p| p.is_finite()));
    assert!(r.to_string().contains("1 non-manifold"));
}

#[test]
fn meshes_without_uvs_need_a_projection() {
    let text = "v 0 0 0\nv 1 0 0\nv 0 0 1\nv 0 1 0\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n";
    let raw = obj::parse(text, "tet.obj").unwrap();
    let e = TriangleMesh::build(raw.clone(), None, "tet.obj")
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("no UV coordinates") && e.contains("planar, box or spherical"),
        "{e}"
    );
    for (proj, _) in uv::PROJECTIONS {
        let (m, r) = TriangleMesh::build(raw.clone(), Some(*proj), "tet.obj").unwrap();
        assert_eq!(r.skipped_zero_uv_area + r.triangles, 4, "{}", proj.name());
        assert!(r.normals_computed);
        assert!(m.uvs.iter().flatten().all(|u| u.is_finite()));
    }
    assert!(
        UvProjection::parse("cylindrical")
            .unwrap_err()
            .contains("planar, box, spherical")
    );
}

fn gltf_json(positions: &[[f32; 3]], indices: &[u16]) -> String {
    use base64::Engine;
    let mut bytes: Vec<u8> = bytemuck::cast_slice(positions).to_vec();
    let ioff = bytes.len();
    bytes.extend_from_slice(bytemuck::cast_slice(indices));
    while !bytes.len().is_multiple_of(4) {
        bytes.push(0);
    }
    let (lo, hi) = positions
        .iter()
        .fold(([f32::MAX; 3], [f32::MIN; 3]), |(l, h), p| {
            (
                [0, 1, 2].map(|i| l[i].min(p[i])),
                [0, 1, 2].map(|i| h[i].max(p[i])),
            )
        });
    let b64 = base64::engine::general_purpose::STANDARD.encode(&bytes);
    format!(
        r#"{{"asset":{{"version":"2.0"}},"scene":0,"scenes":[{{"nodes":[0]}}],
"nodes":[{{"mesh":0,"translation":[0,2,0]}}],
"meshes":[{{"primitives":[{{"attributes":{{"POSITION":0}},"indices":1}}]}}],
"buffers":[{{"byteLength":{len},"uri":"data:application/octet-stream;base64,{b64}"}}],
"bufferViews":[{{"buffer":0,"byteOffset":0,"byteLength":{plen}}},{{"buffer":0,"byteOffset":{ioff},"byteLength":{ilen}}}],
"accessors":[{{"bufferView":0,"componentType":5126,"count":{np},"type":"VEC3","min":{lo:?},"max":{hi:?}}},
{{"bufferView":1,"componentType":5123,"count":{ni},"type":"SCALAR"}}]}}"#,
        len = bytes.len(),
        plen = ioff,
        ilen = indices.len() * 2,
        np = positions.len(),
        ni = indices.len(),
    )
}

#[test]
fn gltf_with_an_embedded_buffer_loads_with_its_node_transform() {
    let json = gltf_json(
        &[[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]],
        &[0, 2, 1],
    );
    let raw = gltf::parse(json.as_bytes(), None, "tri.gltf").unwrap();
    assert_eq!(raw.triangles, vec![[0, 2, 1]]);
    assert!(
        raw.positions.iter().all(|p| p.y == 2.0),
        "translation applied"
    );
    assert!(raw.corner_uvs.is_none());
    let (_, r) = TriangleMesh::build(raw, Some(UvProjection::Planar), "tri.gltf").unwrap();
    assert_eq!(r.triangles, 1);
    // Out-of-range indices and broken JSON are clear errors.
    let bad = gltf_json(
        &[[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]],
        &[0, 2, 7],
    );
    let e = gltf::parse(bad.as_bytes(), None, "bad.gltf")
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("bad.gltf") && e.contains("index 7 is out of range"),
        "{e}"
    );
    let e = gltf::parse(b"{\"asset\":", None, "cut.gltf")
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("cut.gltf") && e.contains("not a valid glTF"),
        "{e}"
    );
}

#[test]
fn builtin_meshes_are_clean_and_outward() {
    for (name, _) in BUILTINS {
        let (m, r) = load(name, None).unwrap();
        assert_eq!(
            (
                r.skipped_non_finite,
                r.skipped_zero_uv_area,
                r.non_manifold_edges
            ),
            (0, 0, 0),
            "{name}: {r}"
        );
        // Signed volume by the divergence theorem: positive when faces point outward.
        let vol: f64 = m
            .triangles
            .iter()
            .map(|t| {
                let [a, b, c] = t.map(|i| m.positions[i as usize]);
                a.dot(b.cross(c)) / 6.0
            })
            .sum();
        if *name != "triangle" {
            assert!(vol > 0.1, "{name}: volume {vol}");
        }
        // Vertex normals agree with the faces around them.
        for (t, tri) in m.triangles.iter().enumerate() {
            let f = m.face_normal(t);
            for &i in tri {
                assert!(m.normals[i as usize].dot(f) > -0.2, "{name}: triangle {t}");
            }
        }
    }
    // The teapot's collapsed patch rows (lid knob, bottom centre) are the only degenerates.
    let (_, r) = load("teapot", None).unwrap();
    assert!(
        r.skipped_degenerate > 0 && r.skipped_degenerate < r.input_triangles / 50,
        "{r}"
    );
}

/// A generated OBJ line: mostly valid, sometimes broken in the ways files are.
fn obj_line() -> impl Strategy<Value = String> {
    let num = prop_oneof![
        (-1e3f64..1e3).prop_map(|x| format!("{x}")),
        Just("nan".to_string()),
        Just("inf".to_string()),
        Just("1e40".to_string()),
        Just("x".to_string()),
        Just("".to_string()),
    ];
    let idx = prop_oneof![
        (-6i64..8).prop_map(|i| i.to_string()),
        Just("99999999999999999999".to_string()),
        (-6i64..8, -6i64..8).prop_map(|(a, b)| format!("{a}/{b}")),
        (-6i64..8, -6i64..8).prop_map(|(a, b)| format!("{a}//{b}")),
        (-6i64..8, -6i64..8, -6i64..8).prop_map(|(a, b, c)| format!("{a}/{b}/{c}")),
        Just("1/".to_string()),
        Just("/".to_string()),
    ];
    prop_oneof![
        4 => proptest::collection::vec(num.clone(), 0..5).prop_map(|v| format!("v {}", v.join(" "))),
        2 => proptest::collection::vec(num.clone(), 0..4).prop_map(|v| format!("vt {}", v.join(" "))),
        2 => proptest::collection::vec(num, 0..4).prop_map(|v| format!("vn {}", v.join(" "))),
        4 => proptest::collection::vec(idx, 0..6).prop_map(|v| format!("f {}", v.join(" "))),
        1 => Just("o thing".to_string()),
        1 => Just("# comment".to_string()),
        1 => Just("usemtl x".to_string()),
        1 => "[ -~]{0,12}",
    ]
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 400, ..ProptestConfig::default() })]

    /// Loading never panics; a syntax error points inside the text; whatever loads cleans.
    #[test]
    fn obj_loader_survives_generated_text(lines in proptest::collection::vec(obj_line(), 0..24)) {
        let text = lines.join("\n");
        match obj::parse(&text, "fuzz.obj") {
            Ok(raw) => {
                let _ = TriangleMesh::build(raw, Some(UvProjection::Box), "fuzz.obj");
            }
            Err(MeshLoadError::Syntax { line, col, .. }) => {
                prop_assert!(line >= 1 && line <= lines.len().max(1));
                prop_assert!(col >= 1);
            }
            Err(_) => {}
        }
    }
}

/// `json` with the `k`-th number after `"field":` (or its array's first) replaced by `value`.
fn set_number(json: &str, field: &str, k: usize, value: &str) -> String {
    let key = format!("\"{field}\":");
    let Some((at, _)) = json.match_indices(&key).nth(k) else {
        return json.to_string();
    };
    let mut start = at + key.len();
    if json[start..].starts_with('[') {
        start += 1;
    }
    let len = json[start..]
        .find(|c: char| !(c.is_ascii_digit() || c == '-' || c == '.'))
        .unwrap_or(0);
    format!("{}{value}{}", &json[..start], &json[start + len..])
}

/// Files the fuzz test below found to panic inside the `gltf` crate (1.4.1), now refused
/// with what is wrong.
#[test]
fn gltf_files_the_gltf_crate_panicked_on_are_refused() {
    let json = gltf_json(
        &[[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]],
        &[0, 2, 1],
    )
    .replacen("{\"buffer\":0,", "{\"buffer\":0,\"byteStride\":12,", 1);
    assert!(gltf::parse(json.as_bytes(), None, "ok.gltf").is_ok());
    for (field, value, says) in [
        (
            "POSITION",
            "2",
            "POSITION names accessor 2, but the file has 2",
        ),
        ("count", "0", "accessor 0 has count 0 (at least 1)"),
        (
            "indices",
            "0",
            "indices accessor 0 is VEC3 of FLOAT; expected SCALAR of UNSIGNED_BYTE, \
             UNSIGNED_SHORT, UNSIGNED_INT",
        ),
        (
            "byteStride",
            "4",
            "stride 4 is smaller than an element (12 bytes)",
        ),
    ] {
        let e = gltf::parse(
            set_number(&json, field, 0, value).as_bytes(),
            None,
            "bad.gltf",
        )
        .unwrap_err()
        .to_string();
        assert!(
            e.starts_with("bad.gltf: ") && e.contains(says),
            "{field}: {e}"
        );
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 256, ..ProptestConfig::default() })]

    /// A valid glTF with its counts, offsets, lengths, types and references replaced by
    /// random numbers, or its bytes overwritten: a clear error naming the file, or a mesh whose
    /// indices are all in range. Never a panic, and never an allocation the header asks for
    /// without the bytes to back it.
    #[test]
    fn gltf_loader_survives_edited_numbers(
        edits in proptest::collection::vec((
            prop_oneof![
                Just("byteLength"), Just("byteOffset"), Just("count"), Just("componentType"),
                Just("buffer"), Just("bufferView"), Just("POSITION"), Just("indices"),
                Just("mesh"), Just("nodes"), Just("scene"), Just("byteStride"),
            ],
            0usize..2,
            prop_oneof![
                Just("0".to_string()), Just("1".to_string()), Just("3".to_string()),
                Just("-1".to_string()), Just("5121".to_string()), Just("5125".to_string()),
                Just("4294967295".to_string()), Just("18446744073709551616".to_string()),
                Just("1e300".to_string()), (0u64..100).prop_map(|v| v.to_string()),
            ],
        ), 1..4),
        bytes in proptest::collection::vec((0usize..1200, any::<u8>()), 0..3),
    ) {
        let mut json = gltf_json(
            &[[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0], [1.0, 1.0, 1.0]],
            &[0, 2, 1, 1, 2, 3],
        )
        .replacen("{\"buffer\":0,", "{\"buffer\":0,\"byteStride\":12,", 1);
        for (field, k, value) in &edits {
            json = set_number(&json, field, *k, value);
        }
        let mut b = json.into_bytes();
        for (at, v) in bytes {
            if at < b.len() {
                b[at] = v;
            }
        }
        match gltf::parse(&b, None, "fuzz.gltf") {
            Ok(raw) => {
                let n = raw.positions.len();
                prop_assert!(raw.triangles.iter().flatten().all(|&i| (i as usize) < n));
                let _ = TriangleMesh::build(raw, Some(UvProjection::Box), "fuzz.gltf");
            }
            Err(e) => prop_assert!(e.to_string().contains("fuzz.gltf"), "{}", e),
        }
    }

    /// Any bytes, with or without the GLB magic in front: an error or a mesh, never a panic.
    #[test]
    fn gltf_loader_survives_random_bytes(
        glb in any::<bool>(),
        bytes in proptest::collection::vec(any::<u8>(), 0..200),
    ) {
        let mut b = if glb { b"glTF\x02\0\0\0".to_vec() } else { Vec::new() };
        b.extend(bytes);
        let _ = gltf::parse(&b, None, "fuzz.glb");
    }
}

/// Inputs that once needed care, replayed every run.
#[test]
fn obj_corpus_replays() {
    let corpus = [
        "",
        "f",
        "v",
        "v 0 0 0\nf 1 1 1",
        "v 0 0 0\nf -1 -1 -1",
        "v 0 0 0\nf -2 1 1",
        "v 0 0 0\nvt 0 0\nf 1/99999999999999999999 1 1",
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3 4",
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1/1 2 3",
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 1\nf 1//1 2 3",
        "v 0 0 0 1 2\n",
        "v nan nan nan\nv inf 0 0\nv 0 0 0\nf 1 2 3",
        "v 1e38 1e38 1e38\nv -1e38 0 0\nv 0 1e38 0\nf 1 2 3",
        "\u{feff}v 0 0 0",
        "mtllib missing.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3",
    ];
    for text in corpus {
        if let Ok(raw) = obj::parse(text, "corpus.obj") {
            let _ = TriangleMesh::build(raw, Some(UvProjection::Planar), "corpus.obj");
        }
    }
}

/// `gltf_json`'s triangle with its scene and nodes replaced.
fn gltf_with_nodes(scene_nodes: &str, nodes: &str) -> String {
    gltf_json(
        &[[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]],
        &[0, 2, 1],
    )
    .replace(
        r#""scenes":[{"nodes":[0]}]"#,
        &format!(r#""scenes":[{{"nodes":{scene_nodes}}}]"#),
    )
    .replace(
        r#""nodes":[{"mesh":0,"translation":[0,2,0]}]"#,
        &format!(r#""nodes":{nodes}"#),
    )
}

#[test]
fn gltf_node_cycles_are_refused_by_name() {
    let t = std::time::Instant::now();
    let self_child = gltf_with_nodes("[0]", r#"[{"name":"loop","mesh":0,"children":[0]}]"#);
    let e = gltf::parse(self_child.as_bytes(), None, "self.gltf")
        .unwrap_err()
        .to_string();
    assert!(
        e.starts_with("self.gltf: ") && e.contains("node 0 (`loop`)") && e.contains("ancestor"),
        "{e}"
    );
    let two = gltf_with_nodes(
        "[0]",
        r#"[{"name":"a","mesh":0,"children":[1]},{"name":"b","children":[0]}]"#,
    );
    let e = gltf::parse(two.as_bytes(), None, "two.gltf")
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("`a`") && e.contains("`b`") && e.contains("ancestor"),
        "{e}"
    );
    // A cycle off the scene's trees is refused too (the file is not valid glTF).
    let aside = gltf_with_nodes(
        "[0]",
        r#"[{"mesh":0},{"name":"x","children":[2]},{"name":"y","children":[1]}]"#,
    );
    let e = gltf::parse(aside.as_bytes(), None, "aside.gltf")
        .unwrap_err()
        .to_string();
    assert!(e.contains("`x`") && e.contains("ancestor"), "{e}");
    assert!(t.elapsed().as_secs_f64() < 5.0);
}

#[test]
fn a_deep_gltf_node_chain_is_walked_without_recursion() {
    // 200,001 nodes, each the child of the one before, the last holding the mesh: the
    // recursive walk overflowed the stack.
    let n = 200_001;
    let mut nodes = String::from("[");
    for i in 0..n {
        if i + 1 < n {
            nodes.push_str(&format!(
                r#"{{"children":[{}],"translation":[0,1e-5,0]}},"#,
                i + 1
            ));
        } else {
            nodes.push_str(r#"{"mesh":0}]"#);
        }
    }
    let json = gltf_with_nodes("[0]", &nodes);
    let raw = gltf::parse(json.as_bytes(), None, "chain.gltf").unwrap();
    assert_eq!(raw.triangles.len(), 1);
    // Every translation on the way applies: 200,000 x 1e-5 up.
    assert!(
        (raw.positions[0].y - 2.0).abs() < 1e-6,
        "{}",
        raw.positions[0]
    );
}

#[test]
fn shared_gltf_children_are_refused_before_anything_is_multiplied() {
    // 42 levels, each node listing the next twice: 2^42 instances of the mesh once
    // allocated gigabytes; a node listed twice or under two parents is not a tree.
    let levels = 42;
    let mut nodes = String::from("[");
    for i in 0..levels {
        nodes.push_str(&format!(r#"{{"children":[{0},{0}]}},"#, i + 1));
    }
    nodes.push_str(r#"{"mesh":0}]"#);
    let json = gltf_with_nodes("[0]", &nodes);
    let t = std::time::Instant::now();
    let e = gltf::parse(json.as_bytes(), None, "dag.gltf")
        .unwrap_err()
        .to_string();
    assert!(e.contains("node 0 lists node 1 twice"), "{e}");
    let json = gltf_with_nodes(
        "[0,1]",
        r#"[{"name":"car","children":[2]},{"name":"truck","children":[2]},{"name":"wheel","mesh":0}]"#,
    );
    let e = gltf::parse(json.as_bytes(), None, "dag.gltf")
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("node 2 (`wheel`) is a child of both node 0 (`car`) and node 1 (`truck`)"),
        "{e}"
    );
    // A mesh shared by many nodes is fine, and counts once per node against the limits.
    let json = gltf_with_nodes("[0,1,2]", r#"[{"mesh":0},{"mesh":0},{"mesh":0}]"#);
    assert_eq!(
        gltf::parse(json.as_bytes(), None, "ok.gltf")
            .unwrap()
            .triangles
            .len(),
        3
    );
    assert!(t.elapsed().as_secs_f64() < 5.0);
}

#[test]
fn gltf_accessors_past_their_data_say_which_bytes() {
    let json = gltf_json(
        &[[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]],
        &[0, 2, 1],
    );
    // The position accessor claims 4 elements in a view of 36 bytes.
    let e = gltf::parse(
        set_number(&json, "count", 0, "4").as_bytes(),
        None,
        "over.gltf",
    )
    .unwrap_err()
    .to_string();
    assert!(
        e.contains("POSITION accessor 0") && e.contains("36 bytes of buffer view 0"),
        "{e}"
    );
    // The view claims more than its buffer.
    let e = gltf::parse(
        set_number(&json, "byteLength", 1, "1000").as_bytes(),
        None,
        "view.gltf",
    )
    .unwrap_err()
    .to_string();
    assert!(
        e.contains("buffer view 0 spans bytes 0..1000 of buffer 0"),
        "{e}"
    );
    assert!(!e.contains("without positions"), "{e}");
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 128, ..ProptestConfig::default() })]

    /// Random node graphs (children lists drawn freely, cycles and shared children
    /// included) over the triangle mesh: a mesh or an error naming the file, quickly.
    #[test]
    fn gltf_node_graphs_never_panic(
        graph in proptest::collection::vec(
            (proptest::collection::vec(0usize..8, 0..4), any::<bool>()),
            1..8,
        ),
        roots in proptest::collection::vec(0usize..8, 0..4),
    ) {
        let n = graph.len();
        let nodes: Vec<String> = graph
            .iter()
            .map(|(kids, mesh)| {
                let kids: Vec<String> = kids.iter().map(|k| (k % n).to_string()).collect();
                let mesh = if *mesh { r#""mesh":0,"# } else { "" };
                format!(r#"{{{mesh}"children":[{}]}}"#, kids.join(","))
            })
            .collect();
        let roots: Vec<String> = roots.iter().map(|r| (r % n).to_string()).collect();
        let json = gltf_with_nodes(
            &format!("[{}]", roots.join(",")),
            &format!("[{}]", nodes.join(",")),
        );
        match gltf::parse(json.as_bytes(), None, "graph.gltf") {
            Ok(raw) => prop_assert!(raw.triangles.len() <= n),
            Err(e) => prop_assert!(e.to_string().starts_with("graph.gltf: "), "{}", e),
        }
    }
}
