//! glTF 2.0 (`.gltf` with external or embedded buffers, `.glb`) through the `gltf` crate.
//! Every triangle primitive of every mesh the default scene reaches is read with its node's
//! world transform (normals by the inverse transpose). Buffers are resolved here rather than by
//! `gltf::import`, which would also decode every image and fail on a missing texture we do not
//! need; accessor counts are checked against the limits before any vertex is read.

use super::{RawMesh, check_counts, read_limited};
use crate::error::MeshLoadError;
use crate::limits;
use base64::Engine;
use glam::{DMat3, DMat4, DVec2, DVec3};
use std::collections::HashSet;
use std::path::Path;

/// Reads a `.gltf` or `.glb` file.
pub fn load(path: &Path) -> Result<RawMesh, MeshLoadError> {
    let bytes = read_limited(path)?;
    parse(&bytes, path.parent(), &path.display().to_string())
}

fn invalid(origin: &str, msg: impl Into<String>) -> MeshLoadError {
    MeshLoadError::Invalid {
        origin: origin.into(),
        msg: msg.into(),
    }
}

/// Refuses what the `gltf` crate (1.4.1) would panic on instead of reporting, before its
/// validation runs:
/// - a primitive's `POSITION`, `NORMAL`, `TEXCOORD_0` or indices naming an accessor that does
///   not exist, or one of a type its reader does not handle (its validation indexes the
///   accessors with the `POSITION` number unchecked; its readers hit `unreachable!` or a
///   debug assertion on other types);
/// - an accessor of count 0 (the spec's minimum is 1; its reader computes `count - 1`);
/// - a buffer view whose stride is smaller than an element of an accessor reading it (a debug
///   assertion in its reader).
fn check_before_validation(json: &gltf::json::Root, origin: &str) -> Result<(), MeshLoadError> {
    use gltf::json::accessor::{ComponentType as C, Type as T};
    use gltf::json::validation::Checked;
    let n = json.accessors.len();
    for (m, mesh) in json.meshes.iter().enumerate() {
        for (p, prim) in mesh.primitives.iter().enumerate() {
            let expect = |what: &str, index: usize, types: &[T], comps: &[C]| {
                let fail = |msg: String| {
                    Err(invalid(
                        origin,
                        format!("mesh {m} primitive {p}: {what} {msg}"),
                    ))
                };
                let Some(a) = json.accessors.get(index) else {
                    return fail(format!("names accessor {index}, but the file has {n}"));
                };
                match (&a.type_, &a.component_type) {
                    (Checked::Valid(t), Checked::Valid(c))
                        if types.contains(t) && comps.contains(&c.0) =>
                    {
                        Ok(())
                    }
                    (t, c) => {
                        let list = |v: Vec<&str>| v.join(", ");
                        let found = match (t, c) {
                            (Checked::Valid(t), Checked::Valid(c)) => {
                                format!("{} of {}", type_name(*t), component_name(c.0))
                            }
                            _ => "of an invalid type".into(),
                        };
                        fail(format!(
                            "accessor {index} is {found}; expected {} of {}",
                            list(types.iter().map(|t| type_name(*t)).collect()),
                            list(comps.iter().map(|c| component_name(*c)).collect()),
                        ))
                    }
                }
            };
            let attr =
                |s: gltf::Semantic| prim.attributes.get(&Checked::Valid(s)).map(|a| a.value());
            if let Some(a) = attr(gltf::Semantic::Positions) {
                expect("POSITION", a, &[T::Vec3], &[C::F32])?;
            }
            if let Some(a) = attr(gltf::Semantic::Normals) {
                expect("NORMAL", a, &[T::Vec3], &[C::F32])?;
            }
            if let Some(a) = attr(gltf::Semantic::TexCoords(0)) {
                expect("TEXCOORD_0", a, &[T::Vec2], &[C::U8, C::U16, C::F32])?;
            }
            if let Some(a) = prim.indices {
                expect("indices", a.value(), &[T::Scalar], &[C::U8, C::U16, C::U32])?;
            }
        }
    }
    for (i, a) in json.accessors.iter().enumerate() {
        if a.count.0 == 0 {
            return Err(invalid(
                origin,
                format!("accessor {i} has count 0 (at least 1)"),
            ));
        }
        let (Checked::Valid(ty), Checked::Valid(ct)) = (&a.type_, &a.component_type) else {
            continue;
        };
        let size = ty.multiplicity() * ct.0.size();
        let stride = a
            .buffer_view
            .and_then(|v| json.buffer_views.get(v.value()))
            .and_then(|v| v.byte_stride);
        if let Some(s) = stride
            && s.0 < size
        {
            return Err(invalid(
                origin,
                format!(
                    "accessor {i}: its buffer view's stride {} is smaller than an element \
                     ({size} bytes)",
                    s.0
                ),
            ));
        }
    }
    Ok(())
}

/// An accessor type's name in glTF files.
fn type_name(t: gltf::json::accessor::Type) -> &'static str {
    use gltf::json::accessor::Type as T;
    match t {
        T::Scalar => "SCALAR",
        T::Vec2 => "VEC2",
        T::Vec3 => "VEC3",
        T::Vec4 => "VEC4",
        T::Mat2 => "MAT2",
        T::Mat3 => "MAT3",
        T::Mat4 => "MAT4",
    }
}

/// A component type's name in the glTF specification.
fn component_name(c: gltf::json::accessor::ComponentType) -> &'static str {
    use gltf::json::accessor::ComponentType as C;
    match c {
        C::I8 => "BYTE",
        C::U8 => "UNSIGNED_BYTE",
        C::I16 => "SHORT",
        C::U16 => "UNSIGNED_SHORT",
        C::U32 => "UNSIGNED_INT",
        C::F32 => "FLOAT",
    }
}

/// Parses glTF or GLB bytes; external buffers are looked up relative to `dir`.
pub fn parse(bytes: &[u8], dir: Option<&Path>, origin: &str) -> Result<RawMesh, MeshLoadError> {
    let not_gltf = |e: gltf::Error| invalid(origin, format!("not a valid glTF 2.0 file: {e}"));
    let raw = gltf::Gltf::from_slice_without_validation(bytes).map_err(not_gltf)?;
    let json = raw.document.into_json();
    check_before_validation(&json, origin)?;
    let doc = gltf::Gltf {
        document: gltf::Document::from_json(json).map_err(not_gltf)?,
        blob: raw.blob,
    };
    // Every buffer's declared size first: together they may not pass the file limit.
    let declared: u64 = doc.buffers().map(|b| b.length() as u64).sum();
    if declared > limits::MAX_MESH_FILE_BYTES {
        return Err(invalid(
            origin,
            format!(
                "the buffers declare {declared} bytes in all; a mesh's buffers are limited \
                 to {} bytes",
                limits::MAX_MESH_FILE_BYTES
            ),
        ));
    }
    let mut buffers = Vec::new();
    for b in doc.buffers() {
        let data = match b.source() {
            gltf::buffer::Source::Bin => doc.blob.clone().ok_or_else(|| {
                invalid(
                    origin,
                    format!(
                        "buffer {} refers to the GLB binary chunk, which is missing",
                        b.index()
                    ),
                )
            })?,
            gltf::buffer::Source::Uri(uri) => {
                if let Some(rest) = uri.strip_prefix("data:") {
                    let (_, b64) = rest.split_once(";base64,").ok_or_else(|| {
                        invalid(
                            origin,
                            format!("buffer {}: only base64 data URIs are supported", b.index()),
                        )
                    })?;
                    base64::engine::general_purpose::STANDARD
                        .decode(b64)
                        .map_err(|e| {
                            invalid(
                                origin,
                                format!("buffer {}: bad base64 data: {e}", b.index()),
                            )
                        })?
                } else {
                    let p = dir.unwrap_or(Path::new(".")).join(uri);
                    read_limited(&p)
                        .map_err(|e| invalid(origin, format!("buffer {}: {e}", b.index())))?
                }
            }
        };
        if data.len() < b.length() {
            return Err(invalid(
                origin,
                format!(
                    "buffer {} holds {} bytes but declares {}",
                    b.index(),
                    data.len(),
                    b.length()
                ),
            ));
        }
        buffers.push(data);
    }
    // Meshes with their world transforms: the default scene's nodes, or every mesh once.
    let instances = instances(&doc, origin)?;
    // Sizes first, from the accessors, before reading anything.
    let (mut nv, mut nt) = (0u64, 0u64);
    for (mesh, _) in &instances {
        for p in mesh
            .primitives()
            .filter(|p| p.mode() == gltf::mesh::Mode::Triangles)
        {
            let v = p.get(&gltf::Semantic::Positions).map_or(0, |a| a.count()) as u64;
            nv += v;
            nt += p.indices().map_or(v, |a| a.count() as u64) / 3;
        }
    }
    check_counts(origin, nv, nt)?;
    check_ranges(&instances, origin)?;
    let mut raw = RawMesh::default();
    let (mut normals, mut uvs) = (Vec::new(), Vec::new());
    let (mut all_n, mut all_t) = (true, true);
    let mut primitives = 0;
    for (mesh, m) in &instances {
        let nm = DMat3::from_mat4(*m).inverse().transpose();
        for p in mesh
            .primitives()
            .filter(|p| p.mode() == gltf::mesh::Mode::Triangles)
        {
            primitives += 1;
            let r = p.reader(|b| buffers.get(b.index()).map(|d| &d[..]));
            let pos: Vec<DVec3> = r
                .read_positions()
                .ok_or_else(|| {
                    invalid(
                        origin,
                        format!("mesh {} has a primitive without positions", mesh.index()),
                    )
                })?
                .map(|q| m.transform_point3(DVec3::new(q[0] as f64, q[1] as f64, q[2] as f64)))
                .collect();
            let n: Option<Vec<DVec3>> = r.read_normals().map(|it| {
                it.map(|q| nm * DVec3::new(q[0] as f64, q[1] as f64, q[2] as f64))
                    .collect()
            });
            let t: Option<Vec<DVec2>> = r.read_tex_coords(0).map(|it| {
                it.into_f32()
                    .map(|q| DVec2::new(q[0] as f64, q[1] as f64))
                    .collect()
            });
            let idx: Vec<u32> = match r.read_indices() {
                Some(i) => i.into_u32().collect(),
                None => (0..pos.len() as u32).collect(),
            };
            if let Some(&bad) = idx.iter().find(|&&i| i as usize >= pos.len()) {
                return Err(invalid(
                    origin,
                    format!(
                        "mesh {}: index {bad} is out of range ({} vertices)",
                        mesh.index(),
                        pos.len()
                    ),
                ));
            }
            let n = n.filter(|n| n.len() == pos.len());
            let t = t.filter(|t| t.len() == pos.len());
            all_n &= n.is_some();
            all_t &= t.is_some();
            let base = raw.positions.len() as u32;
            raw.positions.extend(&pos);
            for tri in idx.chunks_exact(3) {
                raw.triangles
                    .push([tri[0] + base, tri[1] + base, tri[2] + base]);
                if let Some(n) = &n {
                    normals.push([0, 1, 2].map(|k| n[tri[k] as usize]));
                }
                if let Some(t) = &t {
                    uvs.push([0, 1, 2].map(|k| t[tri[k] as usize]));
                }
            }
        }
    }
    if primitives == 0 {
        return Err(invalid(origin, "the file has no triangle primitives"));
    }
    raw.corner_normals = all_n.then_some(normals);
    raw.corner_uvs = all_t.then_some(uvs);
    Ok(raw)
}

/// A node's name for messages: `node 3 (`wheel`)`, or `node 3` when it has none.
fn node_name(n: &gltf::Node) -> String {
    match n.name() {
        Some(name) => format!("node {} (`{name}`)", n.index()),
        None => format!("node {}", n.index()),
    }
}

/// The meshes the default scene (or the first) reaches, each with its node's world
/// transform; every mesh once, untransformed, when the file has no scene. The node graph is
/// walked iteratively, after checking it is what glTF requires (2.0, section 3.5.3): a set
/// of disjoint trees, each node with at most one parent and none its own ancestor, the
/// scene's nodes being roots. So a node reached once is read once: no cycle recurses and no
/// shared child multiplies the vertices behind it.
fn instances<'a>(
    doc: &'a gltf::Gltf,
    origin: &str,
) -> Result<Vec<(gltf::Mesh<'a>, DMat4)>, MeshLoadError> {
    let Some(scene) = doc.default_scene().or_else(|| doc.scenes().next()) else {
        return Ok(doc.meshes().map(|m| (m, DMat4::IDENTITY)).collect());
    };
    let nodes: Vec<gltf::Node> = doc.nodes().collect();
    let mut parent: Vec<Option<usize>> = vec![None; nodes.len()];
    for n in &nodes {
        for c in n.children() {
            if let Some(p) = parent[c.index()] {
                let msg = if p == n.index() {
                    format!(
                        "{} lists {} twice among its children",
                        node_name(n),
                        node_name(&c)
                    )
                } else {
                    format!(
                        "{} is a child of both {} and {}; a glTF node has at most one parent",
                        node_name(&c),
                        node_name(&nodes[p]),
                        node_name(n)
                    )
                };
                return Err(invalid(origin, msg));
            }
            parent[c.index()] = Some(n.index());
        }
    }
    // With one parent each, a cycle is a loop of parent links: follow them from every node,
    // colouring the nodes of the current chain, so each node is visited once in all.
    let mut state = vec![0u8; nodes.len()]; // 0 unseen, 1 on the current chain, 2 done
    for start in 0..nodes.len() {
        let mut chain = Vec::new();
        let mut at = Some(start);
        while let Some(i) = at {
            match state[i] {
                2 => break,
                1 => {
                    let from = chain.iter().position(|&c| c == i).unwrap_or(0);
                    // Parent to child: i, its child on the loop, ..., i again.
                    let mut names = vec![node_name(&nodes[i])];
                    names.extend(chain[from..].iter().rev().map(|&c| node_name(&nodes[c])));
                    return Err(invalid(
                        origin,
                        format!(
                            "{} is its own ancestor ({}); glTF node hierarchies have no cycles",
                            node_name(&nodes[i]),
                            names.join(" -> ")
                        ),
                    ));
                }
                _ => {
                    state[i] = 1;
                    chain.push(i);
                    at = parent[i];
                }
            }
        }
        for c in chain {
            state[c] = 2;
        }
    }
    let mut roots = HashSet::new();
    let mut out = Vec::new();
    let mut stack: Vec<(gltf::Node, DMat4)> = Vec::new();
    for n in scene.nodes() {
        if let Some(p) = parent[n.index()] {
            return Err(invalid(
                origin,
                format!(
                    "scene {} lists {} as a root, but it is a child of {}",
                    scene.index(),
                    node_name(&n),
                    node_name(&nodes[p])
                ),
            ));
        }
        if !roots.insert(n.index()) {
            return Err(invalid(
                origin,
                format!("scene {} lists {} twice", scene.index(), node_name(&n)),
            ));
        }
        stack.push((n, DMat4::IDENTITY));
        while let Some((n, up)) = stack.pop() {
            let m = up
                * DMat4::from_cols_array_2d(&n.transform().matrix().map(|c| c.map(|x| x as f64)));
            if let Some(mesh) = n.mesh() {
                out.push((mesh, m));
            }
            // Reversed, so children are read in the file's order.
            let kids: Vec<gltf::Node> = n.children().collect();
            stack.extend(kids.into_iter().rev().map(|c| (c, m)));
        }
    }
    Ok(out)
}

/// Checks that every accessor a triangle primitive reads lies inside its buffer view, and
/// every such view inside its buffer, with the byte ranges in the message (the `gltf`
/// crate's reader returns nothing for an accessor past its data, which would read as a
/// primitive without positions). Only called after the counts passed the limits.
fn check_ranges(instances: &[(gltf::Mesh, DMat4)], origin: &str) -> Result<(), MeshLoadError> {
    let mut seen = HashSet::new();
    for (mesh, _) in instances {
        for (k, p) in mesh
            .primitives()
            .enumerate()
            .filter(|(_, p)| p.mode() == gltf::mesh::Mode::Triangles)
        {
            let used = [
                ("POSITION", p.get(&gltf::Semantic::Positions)),
                ("NORMAL", p.get(&gltf::Semantic::Normals)),
                ("TEXCOORD_0", p.get(&gltf::Semantic::TexCoords(0))),
                ("indices", p.indices()),
            ];
            if used[0].1.is_none() {
                return Err(invalid(
                    origin,
                    format!(
                        "mesh {} primitive {k} has no POSITION attribute",
                        mesh.index()
                    ),
                ));
            }
            for (what, a) in used {
                let Some(a) = a else { continue };
                if !seen.insert(a.index()) {
                    continue;
                }
                let at = |msg: String| {
                    invalid(
                        origin,
                        format!(
                            "mesh {} primitive {k}: {what} accessor {}: {msg}",
                            mesh.index(),
                            a.index()
                        ),
                    )
                };
                let Some(view) = a.view() else {
                    if a.sparse().is_some() {
                        continue;
                    }
                    return Err(at("has no buffer view (fathom reads vertex data from \
                                   buffers)"
                        .into()));
                };
                let size = a.size() as u64;
                let stride = view.stride().map_or(size, |s| s as u64);
                let end = (a.count() as u64 - 1)
                    .checked_mul(stride)
                    .and_then(|v| v.checked_add(a.offset() as u64))
                    .and_then(|v| v.checked_add(size));
                match end {
                    Some(end) if end <= view.length() as u64 => {}
                    _ => {
                        return Err(at(format!(
                            "{} elements of {size} bytes (stride {stride}) from byte {} need \
                             more than the {} bytes of buffer view {}",
                            a.count(),
                            a.offset(),
                            view.length(),
                            view.index()
                        )));
                    }
                }
                let buffer = view.buffer();
                let vend = (view.offset() as u64).checked_add(view.length() as u64);
                if vend.is_none_or(|e| e > buffer.length() as u64) {
                    return Err(at(format!(
                        "buffer view {} spans bytes {}..{} of buffer {}, which holds {}",
                        view.index(),
                        view.offset(),
                        vend.map_or("(overflow)".into(), |e| e.to_string()),
                        buffer.index(),
                        buffer.length()
                    )));
                }
            }
        }
    }
    Ok(())
}
