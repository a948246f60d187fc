// Fractals (fathom-core fractals/): `fn frac_<Name>(p: vec3f, <params>) -> vec2f` returning
// (distance estimate, orbit trap). Use the accurate `*_p` functions of common.wgsl rather than
// the built-in transcendentals, which Vulkan allows to be coarse. The CPU code iterates masked
// packets; here each invocation is one point, so "all lanes escaped" becomes a `break`.

// --- Mandelbulb (fractals/mandelbulb.rs) ---

// The spherical power map by acos/atan2, any power. Returns (z', r^(power-1)).
fn bulb_step_trig(z: vec3f, r: f32, power: f32, c: vec3f, offsets: vec2f) -> vec4f {
    let safe_r = max(r, 1e-30);
    let theta = (acos_p(clamp(z.z / safe_r, -1.0, 1.0)) + offsets.y) * power;
    let phi = (atan2_p(z.y, z.x) + offsets.x) * power;
    let rp1 = pow(safe_r, power - 1.0);
    let zr = rp1 * safe_r;
    let t = sincos_p(theta);
    let f = sincos_p(phi);
    return vec4f(vec3f(zr * t.x * f.y, zr * f.x * t.x, zr * t.y) + c, rp1);
}

fn csq(v: vec2f) -> vec2f {
    return vec2f(v.x * v.x - v.y * v.y, (v.x + v.x) * v.y);
}

// Power 8 without trigonometry: complex eighth powers of (z, rho) and of the azimuth.
fn bulb_step_pow8(z: vec3f, r: f32, c: vec3f) -> vec4f {
    let rho = sqrt(z.x * z.x + z.y * z.y);
    let on_axis = rho <= 1e-30;
    let inv = 1.0 / max(rho, 1e-30);
    let u = vec2f(select(z.x * inv, 1.0, on_axis), select(z.y * inv, 0.0, on_axis));
    let av = csq(csq(csq(vec2f(z.z, rho))));
    let uv = csq(csq(csq(u)));
    let r2 = r * r;
    let r7 = r2 * r2 * r2 * r;
    return vec4f(vec3f(av.y * uv.x, av.y * uv.y, av.x) + c, r7);
}

fn frac_Mandelbulb(c: vec3f, power: f32, iterations: u32, bailout: f32, safety: f32, azimuth_offset: f32, polar_offset: f32) -> vec2f {
    // Mandelbulber's angle offsets, degrees; at zero the trig-free power-8 step applies.
    let offsets = vec2f(azimuth_offset, polar_offset) * 0.017453292519943295;
    let fast8 = power == 8.0 && azimuth_offset == 0.0 && polar_offset == 0.0;
    var z = c;
    var dr = 1.0;
    var r = length(z);
    var trap = r;
    var live = r < bailout;
    // Escaped at the last iteration (with none, the ball is the set): with the points that
    // never escape, measured from the set's own surface, ln(r / bailout) (see `iterate`).
    var last = iterations == 0u && !live;
    for (var i = 0u; i < iterations; i++) {
        if !live {
            break;
        }
        var s: vec4f;
        if fast8 {
            s = bulb_step_pow8(z, r, c);
        } else {
            s = bulb_step_trig(z, r, power, c, offsets);
        }
        dr = s.w * power * dr + 1.0;
        z = s.xyz;
        r = length(z);
        trap = min(trap, r);
        live = r < bailout;
        last = !live && i + 1u == iterations;
    }
    let rr = max(r, 1e-30);
    // ln(r / bailout) r / dr near the set's surface (f32 needs no series: the CPU's is for
    // double-double depths).
    let d = select(0.5 * log(rr), log(rr / bailout), live || last) * rr / dr;
    return vec2f(select(d, max(d, -INSIDE_DEPTH), live) * safety, trap);
}

// --- Mandelbox (fractals/mandelbox.rs) ---

fn frac_Mandelbox(c: vec3f, scale: f32, min_radius: f32, fixed_radius: f32, folding_limit: f32, iterations: u32, bailout: f32, safety: f32) -> vec2f {
    let fixed2 = fixed_radius * fixed_radius;
    let min2 = max(min_radius * min_radius, 1e-12);
    let abs_scale = abs(scale);
    let lim = vec3f(folding_limit);
    let bail2 = bailout * bailout;
    var z = c;
    var dr = 1.0;
    var r2 = dot(z, z);
    var trap = r2;
    var live = r2 < bail2;
    for (var i = 0u; i < iterations; i++) {
        if !live {
            break;
        }
        let b = clamp(z, -lim, lim) * 2.0 - z;
        let f = fixed2 / clamp(dot(b, b), min2, fixed2);
        z = b * (f * scale) + c;
        dr = dr * f * abs_scale + 1.0;
        r2 = dot(z, z);
        trap = min(trap, r2);
        live = r2 < bail2;
    }
    return vec2f(sqrt(r2) / dr * safety, sqrt(trap));
}

// --- IFS fractals (fractals/ifs.rs, koch.rs) ---

const INV_SQRT3: f32 = 0.5773502691896258;

fn scale_about(p: vec3f, scale: f32, offset: vec3f) -> vec3f {
    return p * scale - offset * (scale - 1.0);
}

fn unit_box(p: vec3f) -> f32 {
    let q = abs(p) - vec3f(1.0);
    return length(max(q, vec3f(0.0))) + min(max_elem(q), 0.0);
}

fn frac_Menger(p: vec3f, iterations: u32, scale: f32, offset: vec3f) -> vec2f {
    let cut = 0.5 * offset.z * (scale - 1.0);
    let inv = 1.0 / scale;
    var z = p;
    var k = 1.0;
    var r2 = dot(z, z);
    var trap = r2;
    for (var i = 0u; i < iterations; i++) {
        if !(r2 < IFS_BAIL2) {
            break;
        }
        var q = scale_about(sort_desc(abs(z)), scale, offset);
        q.z = abs(q.z + cut) - cut;
        z = q;
        k *= inv;
        r2 = dot(z, z);
        trap = min(trap, r2);
    }
    return vec2f(unit_box(z) * k, sqrt(trap));
}

// fold_sum: reflects (a, b) across a + b = 0 when on the negative side.
fn fold_sum(a: f32, b: f32) -> vec2f {
    if a + b < 0.0 {
        return vec2f(-b, -a);
    }
    return vec2f(a, b);
}

fn tetrahedron(p: vec3f) -> f32 {
    let a = max(p.x + p.y - p.z, p.x - p.y + p.z);
    let b = max(p.y + p.z - p.x, -(p.x + p.y + p.z));
    return (max(a, b) - 1.0) * INV_SQRT3;
}

fn frac_Sierpinski(p: vec3f, iterations: u32, scale: f32, offset: vec3f) -> vec2f {
    let inv = 1.0 / scale;
    var z = p;
    var k = 1.0;
    var r2 = dot(z, z);
    var trap = r2;
    for (var i = 0u; i < iterations; i++) {
        if !(r2 < IFS_BAIL2) {
            break;
        }
        let xy = fold_sum(z.x, z.y);
        let xz = fold_sum(xy.x, z.z);
        let yz = fold_sum(xy.y, xz.y);
        z = scale_about(vec3f(xz.x, yz.x, yz.y), scale, offset);
        k *= inv;
        r2 = dot(z, z);
        trap = min(trap, r2);
    }
    return vec2f(tetrahedron(z) * k, sqrt(trap));
}

const SQRT3_2: f32 = 0.8660254037844386;

fn koch_mirror(x: f32, y: f32, x0: f32, nx: f32, ny: f32) -> vec2f {
    let t = min((x - x0) * nx + y * ny, 0.0);
    let t2 = t + t;
    return vec2f(x - t2 * nx, y - t2 * ny);
}

// Baked: iterations, cos(twist), sin(twist), thickness.
fn frac_Koch(p: vec3f, a: u32) -> vec2f {
    let iterations = u32(params[a]);
    let tc = params[a + 1u];
    let ts = params[a + 2u];
    let thickness = params[a + 3u];
    let m = koch_mirror(abs(p.x), p.y, 0.0, -0.5, SQRT3_2);
    let planar = ts == 0.0 && tc > 0.0;
    var z = vec3f(abs(m.x), m.y - INV_SQRT3, p.z);
    var k = 1.0;
    var r2 = dot(z, z);
    var trap = r2;
    for (var i = 0u; i < iterations; i++) {
        if !(r2 < IFS_BAIL2) {
            break;
        }
        let n = koch_mirror(abs(z.x), z.y, 1.0 / 3.0, SQRT3_2, -0.5);
        let x = n.x * 3.0 - 2.0;
        let y = n.y * 3.0;
        let zz = z.z * 3.0;
        if planar {
            z = vec3f(x, y, zz);
        } else {
            z = vec3f(x, tc * y - ts * zz, ts * y + tc * zz);
        }
        k *= 1.0 / 3.0;
        r2 = dot(z, z);
        trap = min(trap, r2);
    }
    let dx = max(abs(z.x) - 1.0, 0.0);
    return vec2f((sqrt(dx * dx + z.y * z.y + z.z * z.z) - thickness) * k, sqrt(trap));
}

const ICO_FOLD_N: vec3f = vec3f(-0.5, -0.8090169943749475, 0.3090169943749474);
const ICO_VERTEX: vec3f = vec3f(0.5257311121191336, 0.0, 0.8506508083520399);
const DODECA_VERTEX: vec3f = vec3f(0.0, 0.3568220897730899, 0.9341723589627157);
const ICO_INRADIUS: f32 = 0.7946544722917661;

fn fold_icosahedral(p0: vec3f) -> vec3f {
    var p = p0;
    for (var i = 0; i < 3; i++) {
        p = abs(p);
        let t = min(dot(p, ICO_FOLD_N), 0.0);
        p -= ICO_FOLD_N * (t + t);
    }
    return p;
}

// The KIFS family: 0 = octahedron, 1 = icosahedron, 2 = dodecahedron. Baked slots:
// iterations, scale, offset (3), rotation rows (9).
fn kifs(p: vec3f, a: u32, kind: u32) -> vec2f {
    let iterations = u32(params[a]);
    let scale = params[a + 1u];
    let offset = param_vec3(a + 2u);
    let r0 = param_vec3(a + 5u);
    let r1 = param_vec3(a + 8u);
    let r2v = param_vec3(a + 11u);
    let identity = r0.x == 1.0 && r1.y == 1.0 && r2v.z == 1.0;
    let inv = 1.0 / scale;
    var z = p;
    var k = 1.0;
    var r2 = dot(z, z);
    var trap = r2;
    for (var i = 0u; i < iterations; i++) {
        if !(r2 < IFS_BAIL2) {
            break;
        }
        var f: vec3f;
        if kind == 0u {
            f = sort_desc(abs(z));
        } else {
            f = fold_icosahedral(z);
        }
        if !identity {
            f = vec3f(dot(r0, f), dot(r1, f), dot(r2v, f));
        }
        z = scale_about(f, scale, offset);
        k *= inv;
        r2 = dot(z, z);
        trap = min(trap, r2);
    }
    var d: f32;
    if kind == 0u {
        let q = abs(z);
        d = (q.x + q.y + q.z - 1.0) * INV_SQRT3;
    } else if kind == 1u {
        d = dot(fold_icosahedral(z), DODECA_VERTEX) - ICO_INRADIUS;
    } else {
        d = dot(fold_icosahedral(z), ICO_VERTEX) - ICO_INRADIUS;
    }
    return vec2f(d * k, sqrt(trap));
}

fn frac_KifsOctahedron(p: vec3f, a: u32) -> vec2f {
    return kifs(p, a, 0u);
}

fn frac_KifsIcosahedron(p: vec3f, a: u32) -> vec2f {
    return kifs(p, a, 1u);
}

fn frac_KifsDodecahedron(p: vec3f, a: u32) -> vec2f {
    return kifs(p, a, 2u);
}
