// Domain operators (fathom-core transforms.rs): `fn xf_<Name>(p: ptr<function, vec3f>,
// k: ptr<function, f32>, <params>)`, updating the point and the distance scale in place like
// the Rust `apply(p: &mut V3, k: &mut S)`. Entries with a bake function take the offset `a` of
// their baked slots instead of named parameters.

fn xf_Translate(p: ptr<function, vec3f>, k: ptr<function, f32>, offset: vec3f) {
    *p = *p - offset;
}

// Baked: three rows of the inverse rotation matrix.
fn xf_Rotate(p: ptr<function, vec3f>, k: ptr<function, f32>, a: u32) {
    let q = *p;
    *p = vec3f(dot(param_vec3(a), q), dot(param_vec3(a + 3u), q), dot(param_vec3(a + 6u), q));
}

fn xf_Scale(p: ptr<function, vec3f>, k: ptr<function, f32>, factor: f32) {
    *p = *p * (1.0 / factor);
    *k = *k * factor;
}

fn xf_FoldAbs(p: ptr<function, vec3f>, k: ptr<function, f32>) {
    *p = abs(*p);
}

fn xf_FoldMenger(p: ptr<function, vec3f>, k: ptr<function, f32>) {
    var q = abs(*p);
    if q.x < q.y {
        q = vec3f(q.y, q.x, q.z);
    }
    if q.x < q.z {
        q = vec3f(q.z, q.y, q.x);
    }
    if q.y < q.z {
        q = vec3f(q.x, q.z, q.y);
    }
    *p = q;
}

fn xf_ScaleAbout(p: ptr<function, vec3f>, k: ptr<function, f32>, factor: f32, centre: vec3f) {
    *p = *p * factor - centre * (factor - 1.0);
    *k = *k / factor;
}
