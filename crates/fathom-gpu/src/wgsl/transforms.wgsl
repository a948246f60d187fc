// Domain operators (fathom-core transforms.rs): `fn xf_<Name>(p: ptr<function, vec3f>,
// k: ptr<function, f32>, <params>)`, updating the point and the distance scale in place like
// the Rust `apply(p: &mut V3, k: &mut S)`. Entries with a bake function take the offset `a` of
// their baked slots instead of named parameters.

// Sorts the coordinates so that x >= y >= z (transforms.rs sort_desc).
fn sort_desc(v: vec3f) -> vec3f {
    var q = v;
    if q.x < q.y {
        q = vec3f(q.y, q.x, q.z);
    }
    if q.x < q.z {
        q = vec3f(q.z, q.y, q.x);
    }
    if q.y < q.z {
        q = vec3f(q.x, q.z, q.y);
    }
    return q;
}

fn fold_to_positive(p: vec3f, n: vec3f, offset: f32) -> vec3f {
    let t = min(dot(n, p) - offset, 0.0);
    return p - n * (t + t);
}

fn fold_to_negative(p: vec3f, n: vec3f) -> vec3f {
    let t = max(dot(n, p), 0.0);
    return p - n * (t + t);
}

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
    *p = sort_desc(abs(*p));
}

fn xf_ScaleAbout(p: ptr<function, vec3f>, k: ptr<function, f32>, factor: f32, centre: vec3f) {
    *p = *p * factor - centre * (factor - 1.0);
    *k = *k / factor;
}

fn xf_Mirror(p: ptr<function, vec3f>, k: ptr<function, f32>, axes: vec3f) {
    let q = *p;
    *p = select(q, abs(q), abs(axes) > vec3f(0.0));
}

fn repeat1(c: f32, per: f32) -> f32 {
    return select(c, c - per * round_away(c / max(per, 1e-30)), per > 0.0);
}

fn xf_Repeat(p: ptr<function, vec3f>, k: ptr<function, f32>, period: vec3f) {
    let q = *p;
    *p = vec3f(repeat1(q.x, period.x), repeat1(q.y, period.y), repeat1(q.z, period.z));
}

fn repeat_limited1(c: f32, per: f32, count: f32) -> f32 {
    let n = floor(count);
    let i = clamp(round_away(c / max(per, 1e-30)), -n, n);
    return select(c, c - per * i, per > 0.0);
}

fn xf_RepeatLimited(p: ptr<function, vec3f>, k: ptr<function, f32>, period: vec3f, count: vec3f) {
    let q = *p;
    *p = vec3f(repeat_limited1(q.x, period.x, count.x), repeat_limited1(q.y, period.y, count.y), repeat_limited1(q.z, period.z, count.z));
}

fn xf_Twist(p: ptr<function, vec3f>, k: ptr<function, f32>, rate: f32, safety: f32) {
    let q = *p;
    let sc = sincos_p(rate * q.y);
    *p = vec3f(sc.y * q.x - sc.x * q.z, q.y, sc.x * q.x + sc.y * q.z);
    *k = *k * safety;
}

fn xf_Bend(p: ptr<function, vec3f>, k: ptr<function, f32>, rate: f32, safety: f32) {
    let q = *p;
    let sc = sincos_p(rate * q.x);
    *p = vec3f(sc.y * q.x - sc.x * q.y, sc.x * q.x + sc.y * q.y, q.z);
    *k = *k * safety;
}

fn xf_Elongate(p: ptr<function, vec3f>, k: ptr<function, f32>, h: vec3f) {
    *p = *p - clamp(*p, -h, h);
}

// Baked: the unit normal, then the offset.
fn xf_FoldPlane(p: ptr<function, vec3f>, k: ptr<function, f32>, a: u32) {
    *p = fold_to_positive(*p, param_vec3(a), params[a + 3u]);
}

fn xf_FoldOctahedral(p: ptr<function, vec3f>, k: ptr<function, f32>) {
    var q = *p;
    if q.x + q.y < 0.0 {
        q = vec3f(-q.y, -q.x, q.z);
    }
    if q.x + q.z < 0.0 {
        q = vec3f(-q.z, q.y, -q.x);
    }
    if q.y + q.z < 0.0 {
        q = vec3f(q.x, -q.z, -q.y);
    }
    *p = sort_desc(q);
}

const ICO_N1: vec3f = vec3f(-0.8090169943749475, 0.30901699437494745, 0.5);
const ICO_N2: vec3f = vec3f(0.30901699437494745, -0.5, 0.8090169943749475);

fn xf_FoldIcosahedral(p: ptr<function, vec3f>, k: ptr<function, f32>) {
    var q = *p;
    for (var i = 0; i < 3; i++) {
        q = abs(q);
        q = fold_to_negative(q, ICO_N2);
        q = fold_to_negative(q, ICO_N1);
    }
    *p = q;
}
