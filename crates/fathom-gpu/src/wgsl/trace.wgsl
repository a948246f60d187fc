// The render passes, mirroring fathom-trace (tracer.rs, prepass.rs, shade.rs, render.rs):
// a multi-resolution cone-marching prepass (blocks of 8, 4, 2 pixels), the depth pass with
// enhanced sphere tracing, and the colour pass (normals, Blinn-Phong, soft shadows, AO, fog).
// Positions are camera-relative: the eye arrives split into f32 hi + lo parts (from f64 on the
// CPU) and a point is `eye_hi + (eye_lo + offset + dir * t)`, so `t` stays small and precise
// when the camera is far from the origin.

struct Light {
    dir: vec4f,    // unit direction towards the light; w = 1 when it casts shadows
    colour: vec4f, // colour times intensity
}

struct Globals {
    eye_hi: vec4f,     // w: pixel angle (footprint per unit distance)
    eye_lo: vec4f,     // w: tan(fov / 2)
    forward: vec4f,    // w: t_max
    right: vec4f,      // w: eps_slope (0.5 * pixel angle * pixel_epsilon)
    up: vec4f,         // w: t_start (distance bound at the eye)
    sky_top: vec4f,    // w: ambient
    sky_bottom: vec4f, // w: ao strength
    pal_a: vec4f,      // w: ao range
    pal_b: vec4f,      // w: shadow softness
    pal_c: vec4f,      // w: fog density
    pal_d: vec4f,      // w: eye separation (stereo)
    dims: vec4u,       // view width, view height, projection (0 mono, 1 side-by-side, 2 ODS), max steps
    dims2: vec4u,      // lights, materials, eyes, 0
    lights: array<Light, 8>,
    rows: vec4u,       // the output rows [x, y) the depth and colour passes of this submit cover
}

// One pixel of the G-buffer read back into a Frame.
struct GPx {
    cd: vec4f,   // linear colour, depth (-1 = miss)
    n: vec4f,    // normal, 0
    misc: vec4u, // material id, steps, hit, 0
}

@group(1) @binding(2) var<uniform> g: Globals;
@group(1) @binding(3) var<storage, read> materials: array<vec4f>;
@group(1) @binding(4) var<storage, read_write> grid: array<f32>;
@group(1) @binding(5) var<storage, read_write> gbuf: array<GPx>;
@group(1) @binding(6) var out_tex: texture_storage_2d<rgba8unorm, write>;
// Distance evaluations: prepass, depth pass, colour pass.
@group(1) @binding(7) var<storage, read_write> counters: array<atomic<u32>, 4>;

// Block size of prepass level l: 8, 4, 2 pixels (fathom_core::shared::PREPASS_LEVELS).
fn level_block(l: u32) -> u32 {
    return PREPASS_COARSEST >> l;
}

struct Ray {
    off: vec3f, // origin relative to the eye
    dir: vec3f,
}

fn view_w() -> u32 {
    return g.dims.x;
}

fn view_h() -> u32 {
    return g.dims.y;
}

fn eyes() -> u32 {
    return g.dims2.z;
}

// The world point at distance t along a ray, formed relative to the eye.
fn at(r: Ray, t: f32) -> vec3f {
    return g.eye_hi.xyz + (g.eye_lo.xyz + (r.off + r.dir * t));
}

// The ray through per-eye pixel position (px, py) (pixel centres at +0.5) of eye `eye`:
// fathom_core::camera::Projection::ray, in f32.
fn view_ray(eye: u32, px: f32, py: f32) -> Ray {
    let w = f32(view_w());
    let h = f32(view_h());
    let f = g.forward.xyz;
    let r = g.right.xyz;
    let u = g.up.xyz;
    let side = select(-1.0, 1.0, eye == 1u);
    let half_sep = 0.5 * g.pal_d.w;
    if g.dims.z == 2u {
        // Omni-directional stereo, equirectangular: longitude across, latitude down.
        let lon = px / w * 2.0 * PI - PI;
        let lat = 0.5 * PI - py / h * PI;
        let dir = r * (sin(lon) * cos(lat)) + u * sin(lat) + f * (cos(lon) * cos(lat));
        let off = (r * cos(lon) - f * sin(lon)) * (side * half_sep);
        return Ray(off, dir);
    }
    let th = g.eye_lo.w;
    let sx = (2.0 * px - w) / h * th;
    let sy = (h - 2.0 * py) / h * th;
    let dir = normalize(f + r * sx + u * sy);
    var off = vec3f(0.0);
    if g.dims.z == 1u {
        off = r * (side * half_sep);
    }
    return Ray(off, dir);
}

// Cone radius at t = 0 covering the spread of ray origins over a block (ODS only):
// Projection::cone_base.
fn cone_base(block: u32) -> f32 {
    if g.dims.z == 2u {
        return 0.5 * g.pal_d.w * f32(block) * 2.0 * PI / f32(view_w());
    }
    return 0.0;
}

struct March {
    t: f32,
    hit: bool,
    steps: u32,
}

// tracer::march for one ray: enhanced sphere tracing (omega > 1) or cone marching (cone > 0).
fn march(r: Ray, t0: f32, t_max: f32, max_steps: u32, eps_slope: f32, cone: f32, cone0: f32, omega0: f32) -> March {
    var t = t0;
    var live = t < t_max;
    var hit = false;
    var steps = 0u;
    var omega = omega0;
    var prev_d = 0.0;
    var prev_step = 0.0;
    for (var i = 0u; i < max_steps; i++) {
        if !live {
            break;
        }
        let d = eval_distance(at(r, t));
        steps += 1u;
        let fail = omega > 1.0 && ((abs(d) + prev_d) < prev_step || d < 0.0);
        let free = d - cone * t - cone0;
        if !fail && free < eps_slope * t {
            hit = true;
            live = false;
            break;
        }
        let step = free * omega;
        let t_back = t - prev_step + prev_d;
        let t_next = select(t + step, t_back, fail);
        prev_step = select(step, prev_d, fail);
        prev_d = select(d, prev_d, fail);
        omega = select(omega, 1.0, fail);
        t = t_next;
        let finite = d == d && abs(d) <= 3.4e38;
        if t >= t_max || !finite {
            live = false;
        }
    }
    return March(t, hit || live, steps);
}

// Grid geometry of prepass level `l`: (cells per row, rows per eye, offset in `grid`).
fn level_dims(l: u32) -> vec3u {
    var off = 0u;
    for (var i = 0u; i < l; i++) {
        let b = level_block(i);
        off += ((view_w() + b - 1u) / b) * ((view_h() + b - 1u) / b) * eyes();
    }
    let b = level_block(l);
    return vec3u((view_w() + b - 1u) / b, (view_h() + b - 1u) / b, off);
}

// StartGrid::start_at: the safe start at per-eye pixel position (px, py), the minimum over the
// 2x2 cells of level `l` whose centres surround it; level 3 means "no prepass yet".
fn start_at(l: u32, eye: u32, px: f32, py: f32) -> f32 {
    if l >= 3u {
        return g.up.w;
    }
    let dims = level_dims(l);
    let b = f32(level_block(l));
    let fx = i32(floor(px / b - 0.5));
    let fy = i32(floor(py / b - 0.5));
    var m = 3.4e38;
    for (var dy = 0; dy < 2; dy++) {
        for (var dx = 0; dx < 2; dx++) {
            let x = u32(clamp(fx + dx, 0, i32(dims.x) - 1));
            let y = u32(clamp(fy + dy, 0, i32(dims.y) - 1));
            m = min(m, grid[dims.z + (eye * dims.y + y) * dims.x + x]);
        }
    }
    return m;
}

fn prepass_level(l: u32, gid: vec3u) {
    let dims = level_dims(l);
    if gid.x >= dims.x || gid.y >= dims.y * eyes() {
        return;
    }
    let eye = gid.y / dims.y;
    let cy = gid.y % dims.y;
    let block = level_block(l);
    let px = min(f32(gid.x * block) + 0.5 * f32(block), f32(view_w()));
    let py = min(f32(cy * block) + 0.5 * f32(block), f32(view_h()));
    let slope = 0.75 * f32(block) * g.eye_hi.w;
    let t0 = select(start_at(l - 1u, eye, px, py), g.up.w, l == 0u);
    let m = march(view_ray(eye, px, py), t0, g.forward.w, g.dims.w, 0.25 * slope + g.right.w, slope, cone_base(block), 1.0);
    grid[dims.z + (eye * dims.y + cy) * dims.x + gid.x] = m.t * (1.0 - 1e-3);
    atomicAdd(&counters[0], m.steps);
}

@compute @workgroup_size(8, 8)
fn prepass_0(@builtin(global_invocation_id) gid: vec3u) {
    prepass_level(0u, gid);
}

@compute @workgroup_size(8, 8)
fn prepass_1(@builtin(global_invocation_id) gid: vec3u) {
    prepass_level(1u, gid);
}

@compute @workgroup_size(8, 8)
fn prepass_2(@builtin(global_invocation_id) gid: vec3u) {
    prepass_level(2u, gid);
}

// Output pixel -> (eye, per-eye x, per-eye y).
fn split_eye(x: u32, y: u32) -> vec3u {
    if g.dims.z == 1u {
        return vec3u(x / view_w(), x % view_w(), y);
    }
    if g.dims.z == 2u {
        return vec3u(y / view_h(), x, y % view_h());
    }
    return vec3u(0u, x, y);
}

fn out_size() -> vec2u {
    if g.dims.z == 1u {
        return vec2u(2u * view_w(), view_h());
    }
    if g.dims.z == 2u {
        return vec2u(view_w(), 2u * view_h());
    }
    return vec2u(view_w(), view_h());
}

// dims2.w = 1 when the prepass ran.
@compute @workgroup_size(8, 8)
fn depth(@builtin(global_invocation_id) gid0: vec3u) {
    let size = out_size();
    let gid = vec3u(gid0.x, gid0.y + g.rows.x, gid0.z);
    if gid.x >= size.x || gid.y >= min(size.y, g.rows.y) {
        return;
    }
    let e = split_eye(gid.x, gid.y);
    let px = f32(e.y) + 0.5;
    let py = f32(e.z) + 0.5;
    let t0 = start_at(select(3u, 2u, g.dims2.w == 1u), e.x, px, py);
    let m = march(view_ray(e.x, px, py), t0, g.forward.w, g.dims.w, g.right.w, 0.0, 0.0, OMEGA);
    let i = gid.y * size.x + gid.x;
    let finite = m.t == m.t && abs(m.t) <= 3.4e38;
    let hit = m.hit && finite;
    gbuf[i].cd = vec4f(0.0, 0.0, 0.0, select(-1.0, m.t, hit));
    gbuf[i].misc = vec4u(0xffffffffu, m.steps, select(0u, 1u, hit), 0u);
    atomicAdd(&counters[1], m.steps);
}

fn sky(dir: vec3f) -> vec3f {
    let u = sqrt(clamp(dir.y, 0.0, 1.0));
    return mix(g.sky_bottom.xyz, g.sky_top.xyz, u);
}

// shade::soft_shadow: Aaltonen's improved penumbra estimate. Returns (factor, evaluations).
fn soft_shadow(ro: vec3f, l: vec3f, eps: f32, k: f32) -> vec2f {
    var res = 1.0;
    var ph = 1e20;
    var t = eps;
    var evals = 0.0;
    let t_max = g.forward.w;
    for (var i = 0u; i < SHADOW_STEPS; i++) {
        let h = eval_distance(ro + l * t);
        evals += 1.0;
        let hp = max(h, 0.0);
        let y0 = hp * hp / (2.0 * ph);
        let far = y0 >= hp;
        let y = select(y0, 0.0, far);
        let d = select(sqrt(max(hp * hp - y * y, 0.0)), hp, far);
        let est = k * d / max(t - y, 1e-12);
        let blocked = h < eps * 0.25;
        res = select(min(res, est), 0.0, blocked);
        ph = max(hp, 1e-12);
        t = t + max(hp, eps);
        let finite = h == h && abs(h) <= 3.4e38;
        if blocked || !(res > 1e-3) || !(t < t_max) || !finite {
            break;
        }
    }
    let r = clamp(res, 0.0, 1.0);
    return vec2f(r * r * (3.0 - 2.0 * r), evals);
}

@compute @workgroup_size(8, 8)
fn shade(@builtin(global_invocation_id) gid0: vec3u) {
    let size = out_size();
    let gid = vec3u(gid0.x, gid0.y + g.rows.x, gid0.z);
    if gid.x >= size.x || gid.y >= min(size.y, g.rows.y) {
        return;
    }
    let i = gid.y * size.x + gid.x;
    let e = split_eye(gid.x, gid.y);
    let ray = view_ray(e.x, f32(e.y) + 0.5, f32(e.z) + 0.5);
    let t = gbuf[i].cd.w;
    var col = sky(ray.dir);
    var n = vec3f(0.0);
    var id = 0xffffffffu;
    var evals = 0u;
    if gbuf[i].misc.z == 1u {
        let p = at(ray, t);
        let h = max(t * g.eye_hi.w, 1e-12);
        let ao_range = g.pal_a.w;
        // One call site for the hit's value, the normal's four probes (Evaluator::normal,
        // offset h / 2) and the AO samples: every call of the interpreter is inlined by the
        // driver, so fewer sites compile much faster.
        var v: Val;
        var occ = 0.0;
        var aw = 1.0;
        for (var j = 0u; j < 5u + AO_SAMPLES; j++) {
            var q = p;
            var hh = 0.0;
            if j < 4u {
                q = p + tetra(j) * (h * 0.5);
            } else if j > 4u {
                hh = ao_range * (0.1 + 0.9 * f32(j - 5u) / f32(AO_SAMPLES - 1u));
                q = p + n * hh;
            }
            let r = eval_tape(q);
            if j < 4u {
                n += tetra(j) * r.d;
            } else if j == 4u {
                v = r;
                n = n / max(length(n), 1e-30);
            } else {
                occ += clamp(1.0 - r.d / hh, 0.0, 1.0) * aw;
                aw *= 0.7;
            }
        }
        evals = 5u + AO_SAMPLES;
        let nm = g.dims2.y;
        let i1 = min(u32(max(v.id, 0.0)), nm - 1u);
        let i2 = min(u32(max(v.id2, 0.0)), nm - 1u);
        let w = clamp(v.blend, 0.0, 1.0);
        let m0 = mix(materials[2u * i1], materials[2u * i2], w);
        let m1 = mix(materials[2u * i1 + 1u], materials[2u * i2 + 1u], w);
        id = i1;
        let trap = min(v.trap, 4.0);
        let pc = clamp(g.pal_a.xyz + g.pal_b.xyz * cos(2.0 * PI * (g.pal_c.xyz * trap + g.pal_d.xyz)), vec3f(0.0), vec3f(1.0));
        let albedo = mix(m0.xyz, pc, m1.y);
        // The AO weights 0.7^i summed over the five samples.
        let ao = clamp(1.0 - (g.sky_bottom.w / 2.7731) * occ, 0.0, 1.0);
        let hemi = 0.7 + 0.3 * n.y;
        col = albedo * (g.sky_top.w * ao) * hemi;
        for (var li = 0u; li < g.dims2.x; li++) {
            let lt = g.lights[li];
            let l = lt.dir.xyz;
            let ndl = max(dot(n, l), 0.0);
            var vis = 1.0;
            if lt.dir.w > 0.5 && ndl > 0.0 {
                let s = soft_shadow(p + n * (h * 2.0), l, h, g.pal_b.w);
                vis = s.x;
                evals += u32(s.y);
            }
            let half = normalize(l - ray.dir);
            let ndh = max(dot(n, half), 0.0);
            let sp = m0.w * pow(max(ndh, 1e-6), m1.x);
            col += (albedo + vec3f(sp)) * (lt.colour.xyz * (vis * ndl));
        }
        let fog = g.pal_c.w;
        if fog > 0.0 {
            let f = 1.0 - exp(-fog * t);
            col += (g.sky_bottom.xyz - col) * f;
        }
    }
    // post::sanitize: no NaN leaves the renderer.
    col = select(col, vec3f(0.0), col != col);
    gbuf[i].cd = vec4f(col, t);
    gbuf[i].n = vec4f(n, 0.0);
    gbuf[i].misc.x = id;
    textureStore(out_tex, vec2i(gid.xy), vec4f(to_srgb(col.x), to_srgb(col.y), to_srgb(col.z), 1.0));
    atomicAdd(&counters[2], evals);
}
