// Shared declarations of every fathom compute shader: the tape and parameter buffers, the value
// and point types of the interpreter, and the scalar helpers that mirror fathom-core's `Real`
// where WGSL's built-ins differ from Rust's.

// Tape instructions: (op, param, arg, reserved), see docs/tape.md.
@group(0) @binding(0) var<storage, read> instrs: array<vec4<u32>>;
// The parameter buffer, converted to f32.
@group(0) @binding(1) var<storage, read> params: array<f32>;

// NO_TRAP, TINY, IFS_BAIL2, MAX_STACK, MAX_EXECUTED, OMEGA, SHADOW_STEPS, AO_SAMPLES and the
// prepass levels come from fathom_core::shared (generated ahead of this file).
const PI: f32 = 3.14159265358979;

// A value of the distance field: distance, materials and blend, orbit trap (value.rs).
struct Val {
    d: f32,
    id: f32,
    id2: f32,
    blend: f32,
    trap: f32,
}

// A saved interpreter point (eval::Point).
struct Pt {
    p: vec3f,
    k: f32,
    trap: f32,
}

fn val_solid(d: f32, id: f32, trap: f32) -> Val {
    return Val(d, id, id, 0.0, trap);
}

// Value::select: m ? a : b.
fn val_select(m: bool, a: Val, b: Val) -> Val {
    if m {
        return a;
    }
    return b;
}

// Value::blend: `a` with weight w, `b` with weight 1 - w, the stronger one's material primary.
fn val_blend(d: f32, a: Val, b: Val, w: f32) -> Val {
    let a_wins = w >= 0.5;
    return Val(d, select(b.id, a.id, a_wins), select(a.id, b.id, a_wins), min(w, 1.0 - w), mix(b.trap, a.trap, w));
}

// Real::round: half away from zero (WGSL's round is half to even).
fn round_away(x: f32) -> f32 {
    let t = trunc(x);
    return select(t, t + sign(x), abs(x - t) >= 0.5);
}

// Real::signum as on the f64 path: +1 for +0, -1 for negative numbers.
fn signum(x: f32) -> f32 {
    return select(1.0, -1.0, x < 0.0);
}

fn max_elem(v: vec3f) -> f32 {
    return max(v.x, max(v.y, v.z));
}

fn min_elem(v: vec3f) -> f32 {
    return min(v.x, min(v.y, v.z));
}

fn param_vec3(o: u32) -> vec3f {
    return vec3f(params[o], params[o + 1u], params[o + 2u]);
}

// Accurate transcendental functions. Vulkan lets sin and cos be off by 2^-11 absolute and
// acos/atan2 by thousands of ulps (lavapipe uses such fast versions), which moves fractal
// distance estimates by ~1e-3 relative. These are Cephes' single-precision polynomials (the
// same family `wide` uses on the CPU's packet path), good to a few ulps, so the GPU agrees with
// the CPU to 1e-4 on every device.

// (sin x, cos x) by Cody-Waite reduction modulo pi/2 and minimax polynomials on [-pi/4, pi/4].
fn sincos_p(x: f32) -> vec2f {
    let j = round(x * 0.636619772367581343);
    var r = x - j * 1.5703125;
    r = r - j * 4.837512969970703125e-4;
    r = r - j * 7.54978995489188216e-8;
    let z = r * r;
    let s = r + r * z * (-1.6666654611e-1 + z * (8.3321608736e-3 + z * -1.9515295891e-4));
    let c = 1.0 - 0.5 * z + z * z * (4.166664568298827e-2 + z * (-1.388731625493765e-3 + z * 2.443315711809948e-5));
    let q = i32(j) & 3;
    if q == 0 {
        return vec2f(s, c);
    } else if q == 1 {
        return vec2f(c, -s);
    } else if q == 2 {
        return vec2f(-s, -c);
    }
    return vec2f(-c, s);
}

fn sin_p(x: f32) -> f32 {
    return sincos_p(x).x;
}

fn cos_p(x: f32) -> f32 {
    return sincos_p(x).y;
}

// atan on [0, 1].
fn atan01_p(t: f32) -> f32 {
    var x = t;
    var y0 = 0.0;
    if x > 0.4142135623730950 {
        y0 = 0.25 * PI;
        x = (x - 1.0) / (x + 1.0);
    }
    let z = x * x;
    return y0 + (((8.05374449538e-2 * z - 1.38776856032e-1) * z + 1.99777106478e-1) * z - 3.33329491539e-1) * z * x + x;
}

// atan2(y, x): the angle of the point (x, y), in [-pi, pi].
fn atan2_p(y: f32, x: f32) -> f32 {
    let ax = abs(x);
    let ay = abs(y);
    let hi = max(ax, ay);
    if hi == 0.0 {
        return 0.0;
    }
    var a = atan01_p(min(ax, ay) / hi);
    if ay > ax {
        a = 0.5 * PI - a;
    }
    if x < 0.0 {
        a = PI - a;
    }
    return select(a, -a, y < 0.0);
}

// asin on [-0.5, 0.5] (Cephes asinf's polynomial).
fn asin_small_p(x: f32) -> f32 {
    let z = x * x;
    return x + x * z * ((((4.2163199048e-2 * z + 2.4181311049e-2) * z + 4.5470025998e-2) * z + 7.4953002686e-2) * z + 1.6666752422e-1);
}

fn asin_p(x: f32) -> f32 {
    let a = abs(x);
    if a <= 0.5 {
        return asin_small_p(x);
    }
    let r = 0.5 * PI - 2.0 * asin_small_p(sqrt(0.5 * (1.0 - a)));
    return select(r, -r, x < 0.0);
}

// acos on [-1, 1], accurate near both ends (Cephes acosf).
fn acos_p(x: f32) -> f32 {
    if x < -0.5 {
        return PI - 2.0 * asin_small_p(sqrt(0.5 * (1.0 + x)));
    }
    if x > 0.5 {
        return 2.0 * asin_small_p(sqrt(0.5 * (1.0 - x)));
    }
    return 0.5 * PI - asin_small_p(x);
}
