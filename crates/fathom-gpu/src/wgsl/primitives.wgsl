// Primitives (fathom-core primitives.rs): `fn prim_<Name>(p: vec3f, <params in declaration
// order>) -> f32`. Scalar -> f32, Int -> u32, Vec3 -> vec3f; entries with a bake function take
// `a`, the offset of their baked slots. The dispatch is generated from the registry table, so a
// missing or mistyped function fails validation naming the entry.
// `select(b, a, m)` below is the CPU's `S::select(m, a, b)`.


fn len2(x: f32, y: f32) -> f32 {
    return sqrt(x * x + y * y);
}

// box_q: the box distance from per-axis signed offsets.
fn box_q(x: f32, y: f32, z: f32) -> f32 {
    return length(vec3f(max(x, 0.0), max(y, 0.0), max(z, 0.0))) + min(max(max(x, y), z), 0.0);
}

// box_q2: 2D box distance from two signed offsets (also the extrusion of a 2D distance).
fn box_q2(x: f32, y: f32) -> f32 {
    return len2(max(x, 0.0), max(y, 0.0)) + min(max(x, y), 0.0);
}

fn box3(p: vec3f, size: vec3f) -> f32 {
    let q = abs(p) - size;
    return box_q(q.x, q.y, q.z);
}

// Exact frustum along y: radius r1 at y = -h, r2 at y = +h.
fn capped_cone(p: vec3f, h: f32, r1: f32, r2: f32) -> f32 {
    let qx = len2(p.x, p.z);
    let qy = p.y;
    let k2x = r2 - r1;
    let k2y = 2.0 * h;
    let ca_x = qx - min(qx, select(r2, r1, qy < 0.0));
    let ca_y = abs(qy) - h;
    let k2k2 = max(k2x * k2x + k2y * k2y, TINY);
    let t = clamp(((r2 - qx) * k2x + (h - qy) * k2y) / k2k2, 0.0, 1.0);
    let cb_x = qx - r2 + k2x * t;
    let cb_y = qy - h + k2y * t;
    let inside = cb_x < 0.0 && ca_y < 0.0;
    let d = sqrt(min(ca_x * ca_x + ca_y * ca_y, cb_x * cb_x + cb_y * cb_y));
    return select(d, -d, inside);
}

// 2D distance to an equilateral triangle of side 2r, one vertex towards +y.
fn equilateral_triangle(x0: f32, y0: f32, r: f32) -> f32 {
    let k = 1.7320508075688772;
    var x = abs(x0) - r;
    var y = y0 + r / k;
    let flip = (x + k * y) > 0.0;
    let fx = select(x, (x - k * y) * 0.5, flip);
    let fy = select(y, (-k * x - y) * 0.5, flip);
    x = fx - clamp(fx, -2.0 * r, 0.0);
    y = fy;
    let l = len2(x, y);
    return select(l, -l, y > 0.0);
}

fn segment_dist2(p: vec3f, a: vec3f, b: vec3f) -> f32 {
    let pa = p - a;
    let ba = b - a;
    let h = clamp(dot(pa, ba) / max(dot(ba, ba), TINY), 0.0, 1.0);
    let e = pa - ba * h;
    return dot(e, e);
}

fn tri_edge2(e: vec3f, q: vec3f) -> f32 {
    let t = clamp(dot(e, q) / max(dot(e, e), TINY), 0.0, 1.0);
    let v = e * t - q;
    return dot(v, v);
}

fn triangle_dist2(p: vec3f, a: vec3f, b: vec3f, c: vec3f) -> f32 {
    let ba = b - a;
    let cb = c - b;
    let ac = a - c;
    let pa = p - a;
    let pb = p - b;
    let pc = p - c;
    let nor = cross(ba, ac);
    let inside = dot(cross(ba, nor), pa) > 0.0 && dot(cross(cb, nor), pb) > 0.0 && dot(cross(ac, nor), pc) > 0.0;
    let edges = min(min(tri_edge2(ba, pa), tri_edge2(cb, pb)), tri_edge2(ac, pc));
    let np = dot(nor, pa);
    let face = np * np / max(dot(nor, nor), TINY);
    return select(edges, face, inside);
}

fn prim_Empty(p: vec3f) -> f32 {
    return 1e20;
}

fn prim_Sphere(p: vec3f, radius: f32) -> f32 {
    return length(p) - radius;
}

fn prim_Box(p: vec3f, size: vec3f) -> f32 {
    return box3(p, size);
}

fn prim_RoundBox(p: vec3f, size: vec3f, radius: f32) -> f32 {
    return box3(p, max(size - vec3f(radius), vec3f(0.0))) - radius;
}

fn prim_BoxFrame(p0: vec3f, size: vec3f, thickness: f32) -> f32 {
    let e = thickness * 0.5;
    let p = abs(p0) - size;
    let q = abs(p + vec3f(e)) - vec3f(e);
    return min(min(box_q(p.x, q.y, q.z), box_q(q.x, p.y, q.z)), box_q(q.x, q.y, p.z));
}

fn prim_Torus(p: vec3f, major: f32, minor: f32) -> f32 {
    return len2(len2(p.x, p.z) - major, p.y) - minor;
}

// Baked: sin_a, cos_a, major, minor.
fn prim_CappedTorus(p: vec3f, a: u32) -> f32 {
    let sin_a = params[a];
    let cos_a = params[a + 1u];
    let major = params[a + 2u];
    let minor = params[a + 3u];
    let px = abs(p.x);
    let beyond = (cos_a * px) > (sin_a * p.y);
    let kk = select(len2(px, p.y), px * sin_a + p.y * cos_a, beyond);
    return sqrt(max(dot(p, p) + major * major - 2.0 * major * kk, 0.0)) - minor;
}

fn prim_Link(p: vec3f, half_length: f32, major: f32, minor: f32) -> f32 {
    let qy = max(abs(p.y) - half_length, 0.0);
    return len2(len2(p.x, qy) - major, p.z) - minor;
}

fn prim_Cylinder(p: vec3f, radius: f32) -> f32 {
    return len2(p.x, p.z) - radius;
}

fn prim_CappedCylinder(p: vec3f, radius: f32, half_height: f32) -> f32 {
    return box_q2(len2(p.x, p.z) - radius, abs(p.y) - half_height);
}

fn prim_RoundedCylinder(p: vec3f, radius: f32, half_height: f32, rounding: f32) -> f32 {
    return box_q2(len2(p.x, p.z) - max(radius - rounding, 0.0), abs(p.y) - max(half_height - rounding, 0.0)) - rounding;
}

fn prim_Cone(p: vec3f, radius: f32, half_height: f32) -> f32 {
    return capped_cone(p, half_height, radius, 0.0);
}

fn prim_CappedCone(p: vec3f, half_height: f32, bottom: f32, top: f32) -> f32 {
    return capped_cone(p, half_height, bottom, top);
}

fn prim_RoundCone(p: vec3f, bottom: f32, top: f32, half_height: f32) -> f32 {
    let h = half_height * 2.0;
    let b = clamp((bottom - top) / max(h, TINY), -1.0, 1.0);
    let a = sqrt(max(1.0 - b * b, 0.0));
    let qx = len2(p.x, p.z);
    let qy = p.y + half_height;
    let kk = a * qy - b * qx;
    let d1 = len2(qx, qy) - bottom;
    let d2 = len2(qx, qy - h) - top;
    let dm = qx * a + qy * b - bottom;
    let hull = select(select(dm, d2, kk > a * h), d1, kk < 0.0);
    return select(hull, min(d1, d2), abs(bottom - top) >= h);
}

// Baked: the unit normal.
fn prim_Plane(p: vec3f, a: u32) -> f32 {
    return dot(p, param_vec3(a));
}

fn prim_HexPrism(p: vec3f, radius: f32, half_height: f32) -> f32 {
    let kx = -0.8660254037844386;
    let ky = 0.5;
    let kz = 0.5773502691896258;
    var ax = abs(p.x);
    var az = abs(p.z);
    let t = 2.0 * min(kx * ax + ky * az, 0.0);
    ax -= t * kx;
    az -= t * ky;
    let cx = clamp(ax, -kz * radius, kz * radius);
    let l = len2(ax - cx, az - radius);
    return box_q2(select(l, -l, az < radius), abs(p.y) - half_height);
}

fn prim_TriPrism(p: vec3f, half_side: f32, half_height: f32) -> f32 {
    return box_q2(equilateral_triangle(p.x, p.z, half_side), abs(p.y) - half_height);
}

fn prim_Capsule(p: vec3f, radius: f32, half_height: f32) -> f32 {
    let qy = p.y - clamp(p.y, -half_height, half_height);
    return length(vec3f(p.x, qy, p.z)) - radius;
}

fn prim_CapsuleSegment(p: vec3f, a: vec3f, b: vec3f, radius: f32) -> f32 {
    return sqrt(segment_dist2(p, a, b)) - radius;
}

// Baked: sin_a, cos_a, radius.
fn prim_SolidAngle(p: vec3f, a: u32) -> f32 {
    let sin_a = params[a];
    let cos_a = params[a + 1u];
    let radius = params[a + 2u];
    let qx = len2(p.x, p.z);
    let qy = p.y;
    let l = len2(qx, qy) - radius;
    let t = clamp(qx * sin_a + qy * cos_a, 0.0, radius);
    let m = len2(qx - sin_a * t, qy - cos_a * t);
    let s = cos_a * qx - sin_a * qy;
    return max(l, select(m, -m, s < 0.0));
}

// Baked: radius, h, w.
fn prim_CutSphere(p: vec3f, a: u32) -> f32 {
    let radius = params[a];
    let h = params[a + 1u];
    let w = params[a + 2u];
    let qx = len2(p.x, p.z);
    let qy = p.y;
    let s = max((h - radius) * qx * qx + w * w * (h + radius - 2.0 * qy), h * qx - w * qy);
    let ds = len2(qx, qy) - radius;
    let cut_d = select(len2(qx - w, qy - h), h - qy, qx < w);
    let d = select(cut_d, ds, s < 0.0);
    return select(d, ds, h <= -radius);
}

// Baked: radius, h, w, thickness.
fn prim_CutHollowSphere(p: vec3f, a: u32) -> f32 {
    let radius = params[a];
    let h = params[a + 1u];
    let w = params[a + 2u];
    let thickness = params[a + 3u];
    let qx = len2(p.x, p.z);
    let qy = p.y;
    let rim = (h * qx) < (w * qy);
    return select(abs(len2(qx, qy) - radius), len2(qx - w, qy - h), rim) - thickness;
}

// Baked: radius, cut_radius, offset, ca, cb.
fn prim_DeathStar(p: vec3f, a: u32) -> f32 {
    let radius = params[a];
    let cut_radius = params[a + 1u];
    let offset = params[a + 2u];
    let ca = params[a + 3u];
    let cb = params[a + 4u];
    let qx = p.x;
    let qy = len2(p.y, p.z);
    let rim = (qx * cb - qy * ca) > offset * max(cb - qy, 0.0);
    let carved = max(len2(qx, qy) - radius, cut_radius - len2(qx - offset, qy));
    return select(carved, len2(qx - ca, qy - cb), rim);
}

// Baked: inv_r (vec3), min_r, max_r.
fn prim_Ellipsoid(p: vec3f, a: u32) -> f32 {
    let inv_r = param_vec3(a);
    let min_r = params[a + 3u];
    let max_r = params[a + 4u];
    return max((length(p * inv_r) - 1.0) * min_r, length(p) - max_r);
}

fn prim_Rhombus(p: vec3f, half_x: f32, half_z: f32, half_height: f32, radius: f32) -> f32 {
    let ax = abs(p.x);
    let ay = abs(p.y);
    let az = abs(p.z);
    let bb = max(half_x * half_x + half_z * half_z, TINY);
    let nd = half_x * (half_x - 2.0 * ax) - half_z * (half_z - 2.0 * az);
    let f = clamp(nd / bb, -1.0, 1.0);
    let l = len2(ax - 0.5 * half_x * (1.0 - f), az - 0.5 * half_z * (1.0 + f));
    let s = ax * half_z + az * half_x - half_x * half_z;
    return box_q2(select(l, -l, s < 0.0) - radius, ay - half_height);
}

fn prim_Octahedron(p: vec3f, size: f32) -> f32 {
    let a = abs(p);
    let m = a.x + a.y + a.z - size;
    let c1 = 3.0 * a.x < m;
    let c2 = 3.0 * a.y < m;
    let c3 = 3.0 * a.z < m;
    let q = select(select(vec3f(a.z, a.x, a.y), vec3f(a.y, a.z, a.x), c2), a, c1);
    let kk = clamp(0.5 * (q.z - q.y + size), 0.0, size);
    let edge = length(vec3f(q.x, q.y - size + kk, q.z - kk));
    return select(m * 0.5773502691896258, edge, c1 || c2 || c3);
}

fn prim_OctahedronBound(p: vec3f, size: f32) -> f32 {
    return (abs(p.x) + abs(p.y) + abs(p.z) - size) * 0.5773502691896258;
}

fn prim_Pyramid(p: vec3f, base: f32, height: f32) -> f32 {
    let inv = 1.0 / base;
    let h = height * inv;
    let m2 = h * h + 0.25;
    let ax = abs(p.x) * inv;
    let az = abs(p.z) * inv;
    let py = p.y * inv + h * 0.5;
    let sw = az > ax;
    let px = select(ax, az, sw) - 0.5;
    let pz = select(az, ax, sw) - 0.5;
    let qx = pz;
    let qy = h * py - 0.5 * px;
    let qz = h * px + 0.5 * py;
    let s = max(-qx, 0.0);
    let t = clamp((qy - 0.5 * pz) / (m2 + 0.25), 0.0, 1.0);
    let a = m2 * (qx + s) * (qx + s) + qy * qy;
    let bq = qx + 0.5 * t;
    let by = qy - m2 * t;
    let b = m2 * bq * bq + by * by;
    let d2 = select(min(a, b), 0.0, min(qy, -qx * m2 - qy * 0.5) > 0.0);
    let lateral = sqrt((d2 + qz * qz) / m2);
    let inside = max(qz, -py) < 0.0;
    let bx = max(ax - 0.5, 0.0);
    let bz = max(az - 0.5, 0.0);
    let below = sqrt(bx * bx + bz * bz + py * py);
    let d = select(select(lateral, max(-lateral, -py), inside), below, py < 0.0);
    return d * base;
}

fn prim_Triangle(p: vec3f, a: vec3f, b: vec3f, c: vec3f) -> f32 {
    return sqrt(triangle_dist2(p, a, b, c));
}

fn prim_Quad(p: vec3f, a: vec3f, b: vec3f, c: vec3f, d: vec3f) -> f32 {
    return sqrt(min(triangle_dist2(p, a, b, c), triangle_dist2(p, a, c, d)));
}

// Baked: arc_radius, arc_offset, tip.
fn prim_Vesica(p: vec3f, a: u32) -> f32 {
    let arc_radius = params[a];
    let arc_offset = params[a + 1u];
    let tip = params[a + 2u];
    let qx = len2(p.x, p.z);
    let qy = abs(p.y);
    let to_tip = (qy - tip) * arc_offset > qx * tip;
    return select(len2(qx + arc_offset, qy) - arc_radius, len2(qx, qy - tip), to_tip);
}

// Baked: sin_a, cos_a.
fn prim_InfiniteCone(p: vec3f, a: u32) -> f32 {
    let sin_a = params[a];
    let cos_a = params[a + 1u];
    let qx = len2(p.x, p.z);
    let qy = p.y;
    let t = max(qx * sin_a + qy * cos_a, 0.0);
    let d = len2(qx - sin_a * t, qy - cos_a * t);
    return select(d, -d, (qx * cos_a - qy * sin_a) < 0.0);
}

fn prim_Slab(p: vec3f, half_thickness: f32) -> f32 {
    return abs(p.y) - half_thickness;
}
