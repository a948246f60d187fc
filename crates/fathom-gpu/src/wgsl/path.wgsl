// The GPU path tracer: fathom-pathtrace's integrator (integrator.rs, bsdf.rs, microfacet.rs,
// lights.rs, sampler.rs, camera.rs, march.rs) in WGSL, on the same tape and parameter buffer
// as every other pass. One invocation traces one sample of one pixel and adds it to the
// pixel's running sums; one dispatch is one sample per pixel.
//
// The interpreter is called from ONE site (`pt_trace`'s loop): the driver inlines every call
// site with the whole registry dispatch, so the path is a small state machine (march a path
// ray, probe the normal and material, march shadow rays) around that one call.
//
// The PT_* constants come from fathom_pathtrace::shared (generated ahead of this file); the
// scene's lights, environment and materials are baked by path.rs from the CPU tracer's own
// preparation of the scene (fathom_pathtrace::PathTracer), so both read a scene alike.

struct PtCone {
    dir: vec4f,      // unit direction towards the light; w: 1 - cos(angular radius) (0: delta)
    radiance: vec4f, // radiance in the cone (irradiance for a delta light); w: 1 = casts shadows
}

struct PtGlobals {
    eye: vec4f,        // w: lens radius (0: pinhole)
    forward: vec4f,    // w: focus distance
    right: vec4f,      // w: tan(fov / 2)
    up: vec4f,         // w: eps_slope
    env_top: vec4f,    // w: environment light scale (env_light)
    env_bottom: vec4f, // w: t_max
    dims: vec4u,       // width, height, max steps, max bounces
    dims2: vec4u,      // cone lights, materials, seed, light sampling (1/0)
    pass_info: vec4u,  // sample index, first row, end row, environment sampled (1/0)
    cones: array<PtCone, 8>,
}

// `struct PtPx`, the running sums of one pixel, is in accum.wgsl.

@group(1) @binding(0) var<uniform> pg: PtGlobals;
// Per material PT_MATERIAL_VEC4S vec4s, see path.rs (`material_rows`).
@group(1) @binding(1) var<storage, read> pt_materials: array<vec4f>;
// E, W (PT_ALBEDO_TABLE^2 each), E_avg, W_avg (PT_ALBEDO_TABLE each): microfacet.rs.
@group(1) @binding(2) var<storage, read> pt_tables: array<f32>;
@group(1) @binding(3) var<storage, read_write> pt_accum: array<PtPx>;
@group(1) @binding(4) var pt_out: texture_storage_2d<rgba8unorm, write>;
// Non-finite paths dropped.
@group(1) @binding(5) var<storage, read_write> pt_counters: array<atomic<u32>, 4>;

const PT_INV_PI: f32 = 0.318309886183791;
const PT_MIN_COS: f32 = 1e-4;
const PT_NO_ID: u32 = 0xffffffffu;
const PT_INF: f32 = 3.0e38;

// ---------------------------------------------------------------- sampler.rs

fn pt_hash(x0: u32) -> u32 {
    var x = x0;
    x ^= x >> 16u;
    x *= 0x7feb352du;
    x ^= x >> 15u;
    x *= 0x846ca68bu;
    x ^= x >> 16u;
    return x;
}

fn pt_hash2(a: u32, b: u32) -> u32 {
    return pt_hash(a ^ (pt_hash(b) + 0x9e3779b9u));
}

fn pt_lk_permute(x0: u32, seed: u32) -> u32 {
    var x = x0 + seed;
    x ^= x * 0x6c50b47cu;
    x ^= x * 0xb82f1e52u;
    x ^= x * 0xc7afe638u;
    x ^= x * 0x8d22f6e6u;
    return x;
}

fn pt_owen(x: u32, seed: u32) -> u32 {
    return reverseBits(pt_lk_permute(reverseBits(x), seed));
}

fn pt_sobol1(i0: u32) -> u32 {
    var i = i0;
    var v = 0x80000000u;
    var x = 0u;
    loop {
        if i == 0u {
            break;
        }
        if (i & 1u) != 0u {
            x ^= v;
        }
        i >>= 1u;
        v ^= v >> 1u;
    }
    return x;
}

// A 32-bit fraction to [0, 1) (its top 24 bits, so it never rounds up to 1).
fn pt_unit(x: u32) -> f32 {
    return f32(x >> 8u) * (1.0 / 16777216.0);
}

var<private> s_pixel_seed: u32;
var<private> s_index: u32;
var<private> s_dim: u32;

fn next_2d() -> vec2f {
    let s = pt_hash2(s_pixel_seed, s_dim);
    s_dim += 1u;
    let i = pt_owen(s_index, pt_hash2(s, 1u));
    return vec2f(pt_unit(pt_owen(reverseBits(i), pt_hash2(s, 2u))), pt_unit(pt_owen(pt_sobol1(i), pt_hash2(s, 3u))));
}

fn next_1d() -> f32 {
    return next_2d().x;
}

// ---------------------------------------------------------------- sampling.rs

struct Basis {
    s: vec3f,
    t: vec3f,
    n: vec3f,
}

fn pt_basis(n: vec3f) -> Basis {
    let sg = select(-1.0, 1.0, n.z >= 0.0);
    let a = -1.0 / (sg + n.z);
    let b = n.x * n.y * a;
    return Basis(vec3f(1.0 + sg * n.x * n.x * a, sg * b, -sg * n.x), vec3f(b, sg + n.y * n.y * a, -n.y), n);
}

fn to_local(f: Basis, v: vec3f) -> vec3f {
    return vec3f(dot(v, f.s), dot(v, f.t), dot(v, f.n));
}

fn to_world(f: Basis, v: vec3f) -> vec3f {
    return f.s * v.x + f.t * v.y + f.n * v.z;
}

fn cosine_hemisphere(u: vec2f) -> vec3f {
    let r = sqrt(u.x);
    let phi = 2.0 * PI * u.y;
    return vec3f(r * cos(phi), r * sin(phi), sqrt(max(1.0 - u.x, 0.0)));
}

fn uniform_sphere(u: vec2f) -> vec3f {
    let z = 1.0 - 2.0 * u.x;
    let r = sqrt(max(1.0 - z * z, 0.0));
    let phi = 2.0 * PI * u.y;
    return vec3f(r * cos(phi), r * sin(phi), z);
}

fn uniform_cone(u: vec2f, omc: f32) -> vec3f {
    let o = u.x * omc;
    let r = sqrt(max(o * (2.0 - o), 0.0));
    let phi = 2.0 * PI * u.y;
    return vec3f(r * cos(phi), r * sin(phi), 1.0 - o);
}

fn cone_pdf(omc: f32) -> f32 {
    return 1.0 / (2.0 * PI * omc);
}

fn power_heuristic(a: f32, b: f32) -> f32 {
    let a2 = a * a;
    let b2 = b * b;
    return select(0.0, a2 / (a2 + b2), a2 + b2 > 0.0);
}

fn luminance(c: vec3f) -> f32 {
    return 0.2126 * c.x + 0.7152 * c.y + 0.0722 * c.z;
}

fn pt_finite(x: f32) -> bool {
    return x == x && abs(x) <= 3.4e38;
}

// camera.rs: Shirley and Chiu's concentric map.
fn concentric_disk(u: vec2f) -> vec2f {
    let a = 2.0 * u.x - 1.0;
    let b = 2.0 * u.y - 1.0;
    if a == 0.0 && b == 0.0 {
        return vec2f(0.0);
    }
    var r = b;
    var th = 0.5 * PI - 0.25 * PI * (a / b);
    if abs(a) > abs(b) {
        r = a;
        th = 0.25 * PI * (b / a);
    }
    return vec2f(r * cos(th), r * sin(th));
}

// ---------------------------------------------------------------- microfacet.rs

fn ggx_d(h: vec3f, alpha: f32) -> f32 {
    let a2 = alpha * alpha;
    let k = h.z * h.z * (a2 - 1.0) + 1.0;
    return a2 / (PI * k * k);
}

fn ggx_lambda(w: vec3f, alpha: f32) -> f32 {
    let c2 = w.z * w.z;
    if c2 <= 0.0 {
        return PT_INF;
    }
    let t2 = max(1.0 - c2, 0.0) / c2;
    return 0.5 * (sqrt(1.0 + alpha * alpha * t2) - 1.0);
}

fn ggx_g1(w: vec3f, alpha: f32) -> f32 {
    return 1.0 / (1.0 + ggx_lambda(w, alpha));
}

fn ggx_g2(wo: vec3f, wi: vec3f, alpha: f32) -> f32 {
    return 1.0 / (1.0 + ggx_lambda(wo, alpha) + ggx_lambda(wi, alpha));
}

fn sample_vndf(wo: vec3f, alpha: f32, u: vec2f) -> vec3f {
    let v = normalize(vec3f(alpha * wo.x, alpha * wo.y, wo.z));
    let len2 = v.x * v.x + v.y * v.y;
    var t1 = vec3f(1.0, 0.0, 0.0);
    if len2 > 0.0 {
        t1 = vec3f(-v.y, v.x, 0.0) / sqrt(len2);
    }
    let t2 = cross(v, t1);
    let r = sqrt(u.x);
    let phi = 2.0 * PI * u.y;
    let p1 = r * cos(phi);
    let s = 0.5 * (1.0 + v.z);
    let p2 = (1.0 - s) * sqrt(max(1.0 - p1 * p1, 0.0)) + s * (r * sin(phi));
    let nh = t1 * p1 + t2 * p2 + v * sqrt(max(1.0 - p1 * p1 - p2 * p2, 0.0));
    return normalize(vec3f(alpha * nh.x, alpha * nh.y, max(nh.z, 1e-12)));
}

fn reflect_pdf(wo: vec3f, wi: vec3f, alpha: f32) -> f32 {
    let h = normalize(wo + wi);
    let oh = dot(wo, h);
    if !(oh > 0.0) || wo.z <= 0.0 {
        return 0.0;
    }
    return ggx_g1(wo, alpha) * oh * ggx_d(h, alpha) / wo.z / (4.0 * oh);
}

// AlbedoTables::lookup: (E, W) at cos `mu` and roughness `r`.
fn tab_lookup(mu: f32, r: f32) -> vec2f {
    let n = PT_ALBEDO_TABLE;
    let nf = f32(n);
    let x = clamp(mu * nf - 0.5, 0.0, nf - 1.0);
    let y = clamp(r * (nf - 1.0), 0.0, nf - 1.0);
    let i0 = u32(floor(x));
    let j0 = u32(floor(y));
    let i1 = min(i0 + 1u, n - 1u);
    let j1 = min(j0 + 1u, n - 1u);
    let fx = x - f32(i0);
    let fy = y - f32(j0);
    var out = vec2f(0.0);
    for (var k = 0u; k < 2u; k++) {
        let o = k * n * n;
        let a = pt_tables[o + j0 * n + i0] * (1.0 - fx) + pt_tables[o + j0 * n + i1] * fx;
        let b = pt_tables[o + j1 * n + i0] * (1.0 - fx) + pt_tables[o + j1 * n + i1] * fx;
        out[k] = a * (1.0 - fy) + b * fy;
    }
    return out;
}

// AlbedoTables::averages.
fn tab_averages(r: f32) -> vec2f {
    let n = PT_ALBEDO_TABLE;
    let y = clamp(r * f32(n - 1u), 0.0, f32(n - 1u));
    let j0 = u32(floor(y));
    let j1 = min(j0 + 1u, n - 1u);
    let fy = y - f32(j0);
    let o = 2u * n * n;
    return vec2f(
        pt_tables[o + j0] * (1.0 - fy) + pt_tables[o + j1] * fy,
        pt_tables[o + n + j0] * (1.0 - fy) + pt_tables[o + n + j1] * fy,
    );
}

// ---------------------------------------------------------------- material.rs, colour.rs

struct Mat {
    base: vec3f,
    metallic: f32,
    roughness: f32,
    specular: f32,
    spec_tint: f32,
    transmission: f32,
    emitted: vec3f,
    ior: f32,
    absorption: vec3f,
}

// Look::at for material `i`: its material with its colouring layer (at most one, a cosine
// gradient) applied.
fn look_at(i: u32, pos: vec3f, n: vec3f, trap: f32) -> Mat {
    let o = i * PT_MATERIAL_VEC4S;
    let r0 = pt_materials[o];
    let r1 = pt_materials[o + 1u];
    let r2 = pt_materials[o + 2u];
    let r3 = pt_materials[o + 3u];
    var m = Mat(r0.xyz, r0.w, r1.x, r1.y, r1.z, r1.w, r2.xyz, r2.w, r3.xyz);
    let w = r3.w;
    if w > 0.0 {
        let l = pt_materials[o + 4u];
        var x = clamp(trap, 0.0, 4.0);
        if l.x == 1.0 {
            x = pos.y;
        } else if l.x == 2.0 {
            x = length(pos);
        } else if l.x == 3.0 {
            x = n.y;
        }
        let span = l.w - l.z;
        let t = select(0.0, (x - l.z) / span, span != 0.0);
        let pa = pt_materials[o + 5u].xyz;
        let pb = pt_materials[o + 6u].xyz;
        let pc = pt_materials[o + 7u].xyz;
        let pd = pt_materials[o + 8u].xyz;
        let a = (pc * t + pd) * (2.0 * PI);
        let c = clamp(pa + pb * vec3f(cos_p(a.x), cos_p(a.y), cos_p(a.z)), vec3f(0.0), vec3f(1.0));
        let wc = min(w, 1.0);
        let scalar = luminance(c);
        if l.y == 0.0 {
            m.base = clamp(mix(m.base, c, wc), vec3f(0.0), vec3f(1.0));
        } else if l.y == 1.0 {
            m.roughness = clamp(m.roughness + (scalar - m.roughness) * wc, 0.0, 1.0);
        } else if l.y == 2.0 {
            m.metallic = clamp(m.metallic + (scalar - m.metallic) * wc, 0.0, 1.0);
        } else {
            m.emitted += c * w;
        }
    }
    return m;
}

fn mix_mat(a: Mat, b: Mat, w: f32) -> Mat {
    return Mat(mix(a.base, b.base, w), mix(a.metallic, b.metallic, w), mix(a.roughness, b.roughness, w),
        mix(a.specular, b.specular, w), mix(a.spec_tint, b.spec_tint, w), mix(a.transmission, b.transmission, w),
        mix(a.emitted, b.emitted, w), mix(a.ior, b.ior, w), mix(a.absorption, b.absorption, w));
}

// ---------------------------------------------------------------- bsdf.rs

struct Bsdf {
    alpha: f32,
    rough: f32,
    base: vec3f,
    f0_diel: vec3f,
    f0_metal: vec3f,
    w_diel: f32,
    w_metal: f32,
    w_glass: f32,
    eta: f32,
    e_avg: f32,
    w_avg: f32,
}

fn bsdf_new(m: Mat) -> Bsdf {
    let lum = luminance(m.base);
    let tint = select(vec3f(1.0), m.base / lum, lum > 0.0);
    let spec_colour = mix(vec3f(1.0), tint, m.spec_tint);
    let f0 = min(0.08 * m.specular * spec_colour, vec3f(1.0));
    let alpha = max(m.roughness * m.roughness, PT_MIN_ALPHA);
    let rough = sqrt(alpha);
    let avg = tab_averages(rough);
    return Bsdf(alpha, rough, m.base, f0, m.base, (1.0 - m.metallic) * (1.0 - m.transmission), m.metallic,
        (1.0 - m.metallic) * m.transmission, m.ior, avg.x, avg.y);
}

fn bsdf_interior(m: Mat) -> Bsdf {
    var b = bsdf_new(m);
    b.w_diel = 0.0;
    b.w_metal = 0.0;
    b.w_glass = 1.0;
    b.eta = 1.0 / m.ior;
    return b;
}

fn has_smooth_part(b: Bsdf) -> bool {
    return b.w_diel + b.w_metal > 0.0;
}

fn f90(f0: vec3f) -> vec3f {
    return min(f0 * 50.0, vec3f(1.0));
}

fn schlick(f0: vec3f, c: f32) -> vec3f {
    let w = pow(clamp(1.0 - c, 0.0, 1.0), 5.0);
    return f0 + (f90(f0) - f0) * w;
}

fn fresnel_dielectric(ci0: f32, eta: f32) -> f32 {
    let ci = clamp(ci0, 0.0, 1.0);
    let s2t = (1.0 - ci * ci) / (eta * eta);
    if s2t >= 1.0 {
        return 1.0;
    }
    let ct = sqrt(1.0 - s2t);
    let rs = (ci - eta * ct) / (ci + eta * ct);
    let rp = (eta * ci - ct) / (eta * ci + ct);
    return 0.5 * (rs * rs + rp * rp);
}

fn f_ms(f0: vec3f, e_avg: f32) -> vec3f {
    let favg = f0 + (f90(f0) - f0) / 21.0;
    return favg * favg * e_avg / (vec3f(1.0) - favg * (1.0 - e_avg));
}

fn layer_albedo(b: Bsdf, f0: vec3f, mu: f32) -> vec3f {
    let ew = tab_lookup(mu, b.rough);
    return f0 * (ew.x - ew.y) + f90(f0) * ew.y + f_ms(f0, b.e_avg) * (1.0 - ew.x);
}

fn layer_albedo_avg(b: Bsdf, f0: vec3f) -> vec3f {
    return f0 * (b.e_avg - b.w_avg) + f90(f0) * b.w_avg + f_ms(f0, b.e_avg) * (1.0 - b.e_avg);
}

fn bsdf_eval(b: Bsdf, wo: vec3f, wi: vec3f) -> vec3f {
    if wo.z <= 0.0 || wi.z <= 0.0 || !has_smooth_part(b) {
        return vec3f(0.0);
    }
    let h = normalize(wo + wi);
    let oh = max(dot(wo, h), 0.0);
    let ss = ggx_d(h, b.alpha) * ggx_g2(wo, wi, b.alpha) / (4.0 * wo.z * wi.z);
    let eo = tab_lookup(wo.z, b.rough).x;
    let ei = tab_lookup(wi.z, b.rough).x;
    var ms = 0.0;
    if b.e_avg < 1.0 - 1e-6 {
        ms = (1.0 - eo) * (1.0 - ei) * PT_INV_PI / (1.0 - b.e_avg);
    }
    var f = vec3f(0.0);
    if b.w_diel > 0.0 {
        let eso = layer_albedo(b, b.f0_diel, wo.z);
        let esi = layer_albedo(b, b.f0_diel, wi.z);
        let avg = layer_albedo_avg(b, b.f0_diel);
        let diffuse = b.base * (vec3f(1.0) - eso) * (vec3f(1.0) - esi) * PT_INV_PI / max(vec3f(1.0) - avg, vec3f(1e-9));
        f += b.w_diel * (schlick(b.f0_diel, oh) * ss + f_ms(b.f0_diel, b.e_avg) * ms + diffuse);
    }
    if b.w_metal > 0.0 {
        f += b.w_metal * (schlick(b.f0_metal, oh) * ss + f_ms(b.f0_metal, b.e_avg) * ms);
    }
    return f;
}

// Probabilities of (GGX, cosine, glass).
fn lobe_probabilities(b: Bsdf, wo: vec3f) -> vec3f {
    let mu = max(wo.z, 1e-6);
    let ew = tab_lookup(mu, b.rough);
    var p_ggx = 0.0;
    var p_cos = 0.0;
    if b.w_diel > 0.0 {
        p_ggx += b.w_diel * luminance(b.f0_diel * (ew.x - ew.y) + f90(b.f0_diel) * ew.y);
        let es = luminance(layer_albedo(b, b.f0_diel, mu));
        p_cos += b.w_diel * (luminance(f_ms(b.f0_diel, b.e_avg)) * (1.0 - ew.x) + luminance(b.base) * (1.0 - es));
    }
    if b.w_metal > 0.0 {
        p_ggx += b.w_metal * luminance(b.f0_metal * (ew.x - ew.y) + f90(b.f0_metal) * ew.y);
        p_cos += b.w_metal * luminance(f_ms(b.f0_metal, b.e_avg)) * (1.0 - ew.x);
    }
    let sum = p_ggx + p_cos + b.w_glass;
    if sum > 0.0 {
        return vec3f(p_ggx, p_cos, b.w_glass) / sum;
    }
    return vec3f(0.0, 1.0, 0.0);
}

fn bsdf_pdf(b: Bsdf, wo: vec3f, wi: vec3f) -> f32 {
    if wo.z <= 0.0 || wi.z <= 0.0 {
        return 0.0;
    }
    let p = lobe_probabilities(b, wo);
    return p.x * reflect_pdf(wo, wi, b.alpha) + p.y * wi.z * PT_INV_PI;
}

struct BsdfSample {
    wi: vec3f,
    weight: vec3f,
    pdf: f32,
    ok: bool,
    delta: bool,
    transmitted: bool,
}

fn bsdf_sample(b: Bsdf, wo: vec3f, u_lobe: f32, u: vec2f) -> BsdfSample {
    var out = BsdfSample(vec3f(0.0), vec3f(0.0), 0.0, false, false, false);
    if wo.z <= 0.0 {
        return out;
    }
    let p = lobe_probabilities(b, wo);
    if u_lobe < p.z {
        let u2 = u_lobe / p.z;
        let f = fresnel_dielectric(wo.z, b.eta);
        out.weight = vec3f(b.w_glass / p.z);
        out.ok = true;
        out.delta = true;
        if u2 < f {
            out.wi = vec3f(-wo.x, -wo.y, wo.z);
            return out;
        }
        let s2t = (1.0 - wo.z * wo.z) / (b.eta * b.eta);
        let ct = sqrt(max(1.0 - s2t, 0.0));
        out.wi = normalize(vec3f(-wo.x / b.eta, -wo.y / b.eta, -ct));
        out.transmitted = true;
        return out;
    }
    var wi: vec3f;
    if u_lobe < p.z + p.x {
        let h = sample_vndf(wo, b.alpha, u);
        wi = 2.0 * dot(wo, h) * h - wo;
    } else {
        wi = cosine_hemisphere(u);
    }
    if wi.z <= 0.0 {
        return out;
    }
    let pdf = bsdf_pdf(b, wo, wi);
    if !(pdf > 0.0) {
        return out;
    }
    out.wi = wi;
    out.pdf = pdf;
    out.weight = bsdf_eval(b, wo, wi) * wi.z / pdf;
    out.ok = true;
    return out;
}

fn bsdf_albedo(b: Bsdf) -> vec3f {
    let s = b.w_diel + b.w_metal + b.w_glass;
    if s <= 0.0 {
        return vec3f(1.0);
    }
    return (b.base * (b.w_diel + b.w_metal) + vec3f(b.w_glass)) / s;
}

// ---------------------------------------------------------------- lights.rs

fn env_radiance(d: vec3f) -> vec3f {
    return mix(pg.env_bottom.xyz, pg.env_top.xyz, sqrt(clamp(d.y, 0.0, 1.0)));
}

fn cone_is_delta(c: PtCone) -> bool {
    return c.dir.w <= 0.0 || c.radiance.w < 0.5;
}

// ---------------------------------------------------------------- integrator.rs

const ST_MARCH: u32 = 0u;
const ST_PROBE: u32 = 1u;
const ST_SHADOW: u32 = 2u;
const ST_DONE: u32 = 3u;

const M_GO: u32 = 0u;
const M_HIT: u32 = 1u;
const M_MISS: u32 = 2u;

var<private> st: u32;
// The ray being marched (path or shadow ray) and march.rs's state.
var<private> r_o: vec3f;
var<private> r_d: vec3f;
var<private> r_eps0: f32;
var<private> r_tmax: f32;
var<private> r_inside: bool;
var<private> m_t: f32;
var<private> m_omega: f32;
var<private> m_prev_d: f32;
var<private> m_prev_step: f32;
var<private> m_steps: u32;
var<private> m_eps: f32;
// The path.
var<private> path_o: vec3f;
var<private> path_d: vec3f;
var<private> path_eps0: f32;
var<private> path_inside: bool;
var<private> beta: vec3f;
var<private> radiance: vec3f;
var<private> prev_pdf: f32; // < 0: none (the camera or a delta lobe)
var<private> seen_from_camera: bool;
var<private> interior: vec3f;
var<private> interior_mat: Mat;
var<private> bounce: u32;
// The first surface, for the denoiser.
var<private> a_albedo: vec3f;
var<private> a_normal: vec3f;
var<private> a_depth: f32;
var<private> a_id: u32;
// The surface being shaded.
var<private> h_p: vec3f;
var<private> h_t: f32;
var<private> h_eps: f32;
var<private> h_probe: u32;
var<private> h_grad: vec3f;
var<private> h_n: vec3f;
var<private> h_frame: Basis;
var<private> h_wo: vec3f;
var<private> h_bsdf: Bsdf;
var<private> h_mat: Mat;
// Next-event estimation: the next light to sample (cones, then the environment), the
// contribution waiting for its shadow ray.
var<private> l_next: u32;
var<private> l_pending: vec3f;

fn start_march(o: vec3f, d: vec3f, eps0: f32, t_max: f32, inside: bool) {
    r_o = o;
    r_d = d;
    r_eps0 = eps0;
    r_tmax = min(t_max, pg.env_bottom.w);
    r_inside = inside;
    m_t = 0.0;
    m_omega = OMEGA;
    m_prev_d = 0.0;
    m_prev_step = 0.0;
    m_steps = 0u;
}

// One step of march.rs's `march` with the field's value `d` at the current point.
fn march_step(d: f32) -> u32 {
    let dist = select(d, -d, r_inside);
    m_steps += 1u;
    let slope = pg.up.w;
    if !pt_finite(dist) {
        m_eps = r_eps0 + slope * m_t;
        return M_MISS;
    }
    let fail = m_omega > 1.0 && (abs(dist) + m_prev_d < m_prev_step || dist < 0.0);
    let eps = r_eps0 + slope * m_t;
    if !fail && dist < eps {
        m_eps = eps;
        return M_HIT;
    }
    if fail {
        m_t = m_t - m_prev_step + m_prev_d;
        m_prev_step = m_prev_d;
        m_omega = 1.0;
    } else {
        let step = dist * m_omega;
        m_t += step;
        m_prev_step = step;
        m_prev_d = dist;
    }
    if m_t >= r_tmax {
        m_t = r_tmax;
        m_eps = eps;
        return M_MISS;
    }
    if m_steps >= pg.dims.z {
        m_eps = r_eps0 + slope * m_t;
        return M_HIT;
    }
    return M_GO;
}

fn emitter_weight(light_pdf: f32) -> f32 {
    if prev_pdf >= 0.0 && pg.dims2.w == 1u {
        return power_heuristic(prev_pdf, light_pdf);
    }
    return 1.0;
}

fn start_path_ray(o: vec3f, d: vec3f, eps0: f32, inside: bool) {
    path_o = o;
    path_d = d;
    path_eps0 = eps0;
    path_inside = inside;
    start_march(o, d, eps0, PT_INF, inside);
    st = ST_MARCH;
}

// The path ray's march ended.
fn path_march_end(hit: bool) {
    if path_inside {
        let t = select(pg.env_bottom.w, m_t, hit);
        beta *= exp(-interior * t);
    }
    if !hit {
        if !path_inside {
            let scale = select(pg.env_top.w, 1.0, seen_from_camera);
            let light_pdf = select(0.0, 0.25 * PT_INV_PI, pg.env_top.w > 0.0);
            var l = env_radiance(path_d) * scale * emitter_weight(light_pdf);
            for (var i = 0u; i < pg.dims2.x; i++) {
                let c = pg.cones[i];
                if !cone_is_delta(c) && 1.0 - dot(path_d, c.dir.xyz) <= c.dir.w {
                    l += c.radiance.xyz * emitter_weight(cone_pdf(c.dir.w));
                }
            }
            radiance += beta * l;
        }
        st = ST_DONE;
        return;
    }
    h_p = path_o + path_d * m_t;
    h_t = m_t;
    h_eps = max(m_eps, PT_MIN_EPSILON);
    h_probe = 0u;
    h_grad = vec3f(0.0);
    st = ST_PROBE;
}

// The point the probe `h_probe` evaluates: the six central differences of march.rs's
// `normal`, then the hit itself for its material.
fn probe_point() -> vec3f {
    if h_probe >= 6u {
        return h_p;
    }
    var e = vec3f(0.0);
    e[h_probe / 2u] = select(h_eps, -h_eps, (h_probe & 1u) == 1u);
    return h_p + e;
}

fn on_probe(v: Val) {
    if h_probe < 6u {
        h_grad[h_probe / 2u] += select(v.d, -v.d, (h_probe & 1u) == 1u);
        h_probe += 1u;
        if h_probe < 6u {
            return;
        }
        let len = length(h_grad);
        h_n = select(vec3f(0.0, 1.0, 0.0), h_grad / len, len > 0.0 && pt_finite(len));
        if !path_inside {
            // One more evaluation, at the hit, for the material.
            return;
        }
    }
    on_surface(v);
}

fn on_surface(v: Val) {
    let n_out = h_n;
    var n = n_out;
    var id = PT_NO_ID;
    if path_inside {
        h_mat = interior_mat;
        n = -n_out;
        h_bsdf = bsdf_interior(h_mat);
    } else {
        // PathTracer::material_at.
        let last = max(pg.dims2.y, 1u) - 1u;
        let i1 = min(u32(max(v.id, 0.0)), last);
        let i2 = min(u32(max(v.id2, 0.0)), last);
        let w = clamp(v.blend, 0.0, 1.0);
        h_mat = look_at(i1, h_p, n_out, v.trap);
        id = i1;
        if w > 0.0 && i2 != i1 {
            h_mat = mix_mat(h_mat, look_at(i2, h_p, n_out, v.trap), w);
            id = select(i1, i2, w > 0.5);
        }
        h_bsdf = bsdf_new(h_mat);
        radiance += beta * h_mat.emitted;
    }
    h_n = n;
    if bounce == 0u {
        a_albedo = bsdf_albedo(h_bsdf);
        a_normal = n_out;
        a_depth = h_t;
        a_id = id;
    }
    if bounce == pg.dims.w {
        st = ST_DONE;
        return;
    }
    h_frame = pt_basis(n);
    var wo = to_local(h_frame, -path_d);
    if wo.z < PT_MIN_COS {
        wo.z = PT_MIN_COS;
        wo = normalize(wo);
    }
    h_wo = wo;
    if has_smooth_part(h_bsdf) {
        l_next = 0u;
        next_light();
    } else {
        continue_path();
    }
}

// Next-event estimation (PathTracer::direct / direct_if_enabled): each light in turn, each
// with one sample; returns after starting a shadow ray, and continues the path after the last.
fn next_light() {
    let sampling = pg.dims2.w == 1u;
    let lift = PT_SURFACE_LIFT * h_eps;
    loop {
        if l_next > pg.dims2.x {
            break;
        }
        let li = l_next;
        l_next += 1u;
        var wi: vec3f;
        var lr: vec3f;
        var lpdf = 0.0;
        var delta = false;
        var shadows = true;
        if li < pg.dims2.x {
            let c = pg.cones[li];
            if !(sampling || cone_is_delta(c)) {
                continue;
            }
            let u = next_2d();
            shadows = c.radiance.w > 0.5;
            lr = c.radiance.xyz;
            if c.dir.w <= 0.0 {
                wi = c.dir.xyz;
                delta = true;
            } else {
                wi = to_world(pt_basis(c.dir.xyz), uniform_cone(u, c.dir.w));
                lpdf = cone_pdf(c.dir.w);
            }
        } else {
            if !(sampling && pg.pass_info.w == 1u) {
                continue;
            }
            wi = uniform_sphere(next_2d());
            lr = env_radiance(wi) * pg.env_top.w;
            lpdf = 0.25 * PT_INV_PI;
        }
        let wl = to_local(h_frame, wi);
        if wl.z <= 0.0 {
            continue;
        }
        let f = bsdf_eval(h_bsdf, h_wo, wl) * wl.z;
        if max_elem(f) <= 0.0 || (!delta && lpdf <= 0.0) {
            continue;
        }
        var w = 1.0;
        var pdf = 1.0;
        if !delta && sampling {
            w = power_heuristic(lpdf, bsdf_pdf(h_bsdf, h_wo, wl));
            pdf = lpdf;
        } else if !delta {
            pdf = lpdf;
        }
        l_pending = beta * f * lr * (w / pdf);
        if shadows {
            start_march(h_p + h_n * lift, wi, h_eps, PT_INF, false);
            st = ST_SHADOW;
            return;
        }
        radiance += l_pending;
    }
    continue_path();
}

// The BSDF-sampled continuation, Russian roulette, and the next path ray.
fn continue_path() {
    let u_lobe = next_1d();
    let u = next_2d();
    let bs = bsdf_sample(h_bsdf, h_wo, u_lobe, u);
    if !bs.ok {
        st = ST_DONE;
        return;
    }
    beta *= bs.weight;
    let wi = to_world(h_frame, bs.wi);
    var inside = path_inside;
    if bs.transmitted {
        inside = !inside;
        if inside {
            interior = h_mat.absorption;
            interior_mat = h_mat;
        }
    }
    prev_pdf = select(bs.pdf, -1.0, bs.delta);
    seen_from_camera = seen_from_camera && bs.delta;
    if bounce >= PT_RR_START {
        let q = clamp(max_elem(beta), PT_RR_MIN_SURVIVAL, PT_RR_MAX_SURVIVAL);
        if next_1d() >= q {
            st = ST_DONE;
            return;
        }
        beta /= q;
    }
    if max_elem(beta) <= 0.0 {
        st = ST_DONE;
        return;
    }
    let side = select(-1.0, 1.0, dot(wi, h_n) >= 0.0);
    bounce += 1u;
    start_path_ray(h_p + h_n * (side * PT_SURFACE_LIFT * h_eps), wi, h_eps, inside);
}

// One sample of pixel (x, y): PathTracer::sample. Returns the distance evaluations spent.
fn pt_trace(x: u32, y: u32) -> u32 {
    s_pixel_seed = pt_hash2(pt_hash2(x, y), pg.dims2.z);
    s_index = pg.pass_info.x;
    s_dim = 0u;
    let jitter = next_2d();
    let lens_u = next_2d();
    let w = f32(pg.dims.x);
    let h = f32(pg.dims.y);
    let px = f32(x) + jitter.x;
    let py = f32(y) + jitter.y;
    let th = pg.right.w;
    let sx = (2.0 * px - w) / h * th;
    let sy = (h - 2.0 * py) / h * th;
    var d = normalize(pg.forward.xyz + pg.right.xyz * sx + pg.up.xyz * sy);
    var o = pg.eye.xyz;
    if pg.eye.w > 0.0 {
        let focus = pg.eye.xyz + d * (pg.forward.w / dot(d, pg.forward.xyz));
        let l = concentric_disk(lens_u);
        o = pg.eye.xyz + (pg.right.xyz * l.x + pg.up.xyz * l.y) * pg.eye.w;
        d = normalize(focus - o);
    }
    beta = vec3f(1.0);
    radiance = vec3f(0.0);
    prev_pdf = -1.0;
    seen_from_camera = true;
    interior = vec3f(0.0);
    bounce = 0u;
    a_albedo = vec3f(1.0);
    a_normal = vec3f(0.0);
    a_depth = PT_INF;
    a_id = PT_NO_ID;
    start_path_ray(o, d, PT_MIN_EPSILON, false);
    var evals = 0u;
    loop {
        if st == ST_DONE || evals >= PT_MAX_EVALUATIONS {
            break;
        }
        var q = r_o + r_d * m_t;
        if st == ST_PROBE {
            q = probe_point();
        }
        // The only call of the interpreter.
        let v = eval_tape(q);
        evals += 1u;
        if st == ST_PROBE {
            on_probe(v);
        } else {
            let m = march_step(v.d);
            if m != M_GO {
                if st == ST_MARCH {
                    path_march_end(m == M_HIT);
                } else {
                    // A shadow ray: blocked when it hits before the light.
                    if !(m == M_HIT && m_t < r_tmax) {
                        radiance += l_pending;
                    }
                    next_light();
                }
            }
        }
    }
    return evals;
}

@compute @workgroup_size(8, 8)
fn path_trace(@builtin(global_invocation_id) gid0: vec3u) {
    let x = gid0.x;
    let y = gid0.y + pg.pass_info.y;
    if x >= pg.dims.x || y >= min(pg.dims.y, pg.pass_info.z) {
        return;
    }
    let evals = pt_trace(x, y);
    let i = y * pg.dims.x + x;
    var px = pt_accum[i];
    if pg.pass_info.x == 0u {
        px = PtPx(vec4f(0.0), vec4f(0.0), vec4f(0.0), vec4f(0.0, 0.0, 0.0, bitcast<f32>(PT_NO_ID)));
    }
    px.stats.z += f32(evals);
    if a_id != PT_NO_ID {
        px.normal.w = bitcast<f32>(a_id);
    }
    let r = radiance;
    if pt_finite(r.x) && pt_finite(r.y) && pt_finite(r.z) {
        px.sum += vec4f(r, 1.0);
        let l = luminance(r);
        let delta = l - px.stats.x;
        px.stats.x += delta / px.sum.w;
        px.stats.y += delta * (l - px.stats.x);
        px.albedo += vec4f(a_albedo, 0.0);
        px.normal += vec4f(a_normal, 0.0);
        if a_depth < PT_INF {
            px.albedo.w += a_depth;
            px.stats.w += 1.0;
        }
    } else {
        atomicAdd(&pt_counters[0], 1u);
    }
    pt_accum[i] = px;
    let mean = px.sum.xyz / max(px.sum.w, 1.0);
    textureStore(pt_out, vec2i(i32(x), i32(y)), vec4f(to_srgb(mean.x), to_srgb(mean.y), to_srgb(mean.z), 1.0));
}
