// Primitives (fathom-core primitives.rs): `fn prim_<Name>(p: vec3f, <params in declaration
// order>) -> f32`. Scalar -> f32, Int -> u32, Vec3 -> vec3f; the dispatch is generated from the
// registry table, so a missing or mistyped function fails validation naming the entry.

fn prim_Empty(p: vec3f) -> f32 {
    return 1e20;
}

fn prim_Sphere(p: vec3f, radius: f32) -> f32 {
    return length(p) - radius;
}

fn prim_Box(p: vec3f, size: vec3f) -> f32 {
    let q = abs(p) - size;
    return length(max(q, vec3f(0.0))) + min(max_elem(q), 0.0);
}

fn prim_Torus(p: vec3f, major: f32, minor: f32) -> f32 {
    let qx = sqrt(p.x * p.x + p.z * p.z) - major;
    return sqrt(qx * qx + p.y * p.y) - minor;
}

fn prim_Plane(p: vec3f, normal: vec3f) -> f32 {
    return dot(p, normal * (1.0 / length(normal)));
}
