// Microgeometry on the GPU (fathom-micro, docs/micro.md): the shell's tetrahedra are
// rasterised with their outward faces, back faces culled, so each fragment is a ray entering
// one tetrahedron; the fragment marches the texture inside that tetrahedron with fathom-gpu's
// tape interpreter (eval_tape, prepended to this file) and writes the hit's depth, so the
// depth test keeps the nearest hit over all tetrahedra (the global march). A fragment that
// leaves its tetrahedron without a hit is discarded. march_span and surface mirror
// crates/fathom-micro/src/march.rs constant for constant; shade mirrors shade.rs.

struct MicroGlobals {
    view_proj: mat4x4f,
    eye: vec4f,         // w: eps_slope (half the pixel angle times pixel_epsilon)
    sky_top: vec4f,     // w: ambient
    sky_bottom: vec4f,  // w: pixel angle
    cell_min: vec4f,    // w: max steps
    cell_size: vec4f,   // w: 1 to show the base mesh
    base_albedo: vec4f, // w: base specular
    misc: vec4f,        // x: base shininess, y: materials, z: lights, w: 1 to rotate normals
    lights: array<vec4f, 16>, // per light: direction, colour
}

// One tetrahedron (tet.rs): barycentric planes, shell coordinates, corner normals.
// normals[0].w: the prism's Lipschitz factor; normals[1].w: the base face (4 = none).
struct GTet {
    planes: array<vec4f, 4>,
    tex: array<vec4f, 4>,
    normals: array<vec4f, 4>,
}

@group(1) @binding(0) var<uniform> mg: MicroGlobals;
@group(1) @binding(1) var<storage, read> tets: array<GTet>;
@group(1) @binding(2) var<storage, read> mats: array<vec4f>;
// Distance evaluations marching, shading; fragments run.
@group(1) @binding(3) var<storage, read_write> counters: array<atomic<u32>, 4>;

const TILE_EPS: f32 = 1e-4;

struct VIn {
    @location(0) pos: vec3f,
    @location(1) tet: u32,
}

struct VOut {
    @builtin(position) clip: vec4f,
    @location(0) world: vec3f,
    @location(1) @interpolate(flat) tet: u32,
}

@vertex
fn vs_main(v: VIn) -> VOut {
    var o: VOut;
    o.clip = mg.view_proj * vec4f(v.pos, 1.0);
    o.world = v.pos;
    o.tet = v.tet;
    return o;
}

struct FOut {
    @location(0) colour: vec4f, // linear colour, ray distance
    @location(1) normal: vec4f,
    @location(2) id_steps: vec2u,
    @builtin(frag_depth) depth: f32,
}

fn bary(t: u32, p: vec3f) -> vec4f {
    var b: vec4f;
    for (var k = 0u; k < 4u; k++) {
        b[k] = dot(tets[t].planes[k].xyz, p) + tets[t].planes[k].w;
    }
    return b;
}

fn shell_at(t: u32, b: vec4f) -> vec3f {
    var s = vec3f(0.0);
    for (var k = 0u; k < 4u; k++) {
        s += tets[t].tex[k].xyz * b[k];
    }
    return s;
}

fn scene_point(s: vec3f, cu: f32, cv: f32) -> vec3f {
    return mg.cell_min.xyz + vec3f(s.x - cu, s.y, s.z - cv) * mg.cell_size.xyz;
}

fn sgn(x: f32) -> f32 {
    return select(select(0.0, -1.0, x < 0.0), 1.0, x > 0.0);
}

// Transpose Jacobian times n: sum_k (S_k . n) grad lambda_k, S_k the scene-space vertex.
fn jac_t(t: u32, n: vec3f) -> vec3f {
    var g = vec3f(0.0);
    for (var k = 0u; k < 4u; k++) {
        g += dot(tets[t].tex[k].xyz * mg.cell_size.xyz, n) * tets[t].planes[k].xyz;
    }
    return g;
}

// Rodrigues: the rotation taking unit a to unit b, applied to x (march::rotate_between).
fn rotate_between(a: vec3f, b: vec3f, x: vec3f) -> vec3f {
    let v = cross(a, b);
    let c = dot(a, b);
    if c <= -0.999999 {
        return x;
    }
    return x * c + cross(v, x) + v * (dot(v, x) / (1.0 + c));
}

fn safe_normalize(v: vec3f, fallback: vec3f) -> vec3f {
    let l = length(v);
    return select(fallback, v / l, l > 1e-30);
}

fn sky(dir: vec3f) -> vec3f {
    let u = sqrt(clamp(dir.y, 0.0, 1.0));
    return mix(mg.sky_bottom.xyz, mg.sky_top.xyz, u);
}

// shade.rs: hemisphere ambient plus Blinn-Phong per light. m0 = albedo + specular,
// m1.x = shininess.
fn shade(m0: vec4f, shininess: f32, n: vec3f, dir: vec3f) -> vec3f {
    var c = m0.xyz * (mg.sky_top.w * (0.7 + 0.3 * n.y));
    for (var i = 0u; i < u32(mg.misc.z); i++) {
        let l = mg.lights[2u * i].xyz;
        let lc = mg.lights[2u * i + 1u].xyz;
        let ndl = max(dot(n, l), 0.0);
        let h = safe_normalize(l - dir, vec3f(0.0));
        let sp = m0.w * pow(max(dot(n, h), 1e-6), shininess);
        c += (m0.xyz + vec3f(sp)) * lc * ndl;
    }
    return c;
}

@fragment
fn fs_main(in: VOut) -> FOut {
    let t = in.tet;
    let o = mg.eye.xyz;
    let d = normalize(in.world - o);
    // Tet::clip.
    var t_in = -3.4e38;
    var t_out = 3.4e38;
    var face_in = 4u;
    var face_out = 4u;
    for (var k = 0u; k < 4u; k++) {
        let w = tets[t].planes[k];
        let b0 = dot(w.xyz, o) + w.w;
        let db = dot(w.xyz, d);
        if db > 0.0 {
            let tt = -b0 / db;
            if tt > t_in {
                t_in = tt;
                face_in = k;
            }
        } else if db < 0.0 {
            let tt = -b0 / db;
            if tt < t_out {
                t_out = tt;
                face_out = k;
            }
        }
    }
    if t_in < 0.0 {
        t_in = 0.0;
        face_in = 4u;
    }
    atomicAdd(&counters[2], 1u);
    if !(t_in < t_out) {
        discard;
    }
    let bottom = u32(tets[t].normals[1].w);
    let show_base = mg.cell_size.w > 0.5;
    var hit = 0u; // 1 texture, 2 base
    var th = 0.0;
    var cu = 0.0;
    var cv = 0.0;
    var steps = 0u;
    let max_steps = u32(mg.cell_min.w);
    if show_base && face_in == bottom {
        hit = 2u;
        th = t_in;
    } else {
        // march::march_span.
        let t0 = t_in;
        let t1 = t_out;
        let s0 = shell_at(t, bary(t, o + d * t0));
        let ds = (shell_at(t, bary(t, o + d * t1)) - s0) / (t1 - t0);
        let l = max(tets[t].normals[0].w, 1e-30);
        var tt = t0;
        loop {
            if !(tt < t1) || hit != 0u {
                break;
            }
            let s = s0 + ds * (tt - t0);
            let su = floor(s.x + TILE_EPS * sgn(ds.x));
            let sv = floor(s.z + TILE_EPS * sgn(ds.z));
            var end = t1;
            if ds.x > 0.0 {
                end = min(end, t0 + (su + 1.0 - s0.x) / ds.x);
            } else if ds.x < 0.0 {
                end = min(end, t0 + (su - s0.x) / ds.x);
            }
            if ds.z > 0.0 {
                end = min(end, t0 + (sv + 1.0 - s0.z) / ds.z);
            } else if ds.z < 0.0 {
                end = min(end, t0 + (sv - s0.z) / ds.z);
            }
            if end <= tt {
                end = min(t1, tt + 1e-6 * (t1 - t0));
            }
            loop {
                let q = scene_point(s0 + ds * (tt - t0), su, sv);
                let dist = eval_distance(q) / l;
                steps += 1u;
                if dist < mg.eye.w * tt || steps >= max_steps {
                    hit = 1u;
                    th = tt;
                    cu = su;
                    cv = sv;
                    break;
                }
                tt += dist;
                if tt >= end {
                    break;
                }
            }
            if hit == 0u {
                tt = end;
            }
        }
        if hit == 0u && show_base && face_out == bottom {
            hit = 2u;
            th = t_out;
        }
    }
    atomicAdd(&counters[0], steps);
    if hit == 0u {
        discard;
    }
    // march::surface.
    let p = o + d * th;
    let b = bary(t, p);
    var ni = vec3f(0.0);
    for (var k = 0u; k < 4u; k++) {
        ni += tets[t].normals[k].xyz * b[k];
    }
    ni = safe_normalize(ni, vec3f(0.0));
    var n = ni;
    var m0 = mg.base_albedo;
    var shin = mg.misc.x;
    var id = 0xfffffffeu;
    if hit == 1u {
        let q = scene_point(shell_at(t, b), cu, cv);
        let h = max(0.5 * mg.sky_bottom.w * th * tets[t].normals[0].w, 1e-9);
        // One call site for the four normal probes and the material (the driver inlines
        // every call of the interpreter).
        var ns = vec3f(0.0);
        var v: Val;
        for (var j = 0u; j < 5u; j++) {
            var qq = q;
            if j < 4u {
                qq = q + tetra(j) * h;
            }
            let r = eval_tape(qq);
            if j < 4u {
                ns += tetra(j) * r.d;
            } else {
                v = r;
            }
        }
        atomicAdd(&counters[1], 5u);
        ns = safe_normalize(ns, vec3f(0.0, 1.0, 0.0));
        let ng = safe_normalize(jac_t(t, ns), ni);
        n = ng;
        if mg.misc.w > 0.5 {
            let nh = safe_normalize(jac_t(t, vec3f(0.0, 1.0, 0.0)), ni);
            n = safe_normalize(rotate_between(nh, ni, ng), ni);
        }
        let nm = u32(mg.misc.y);
        id = min(u32(max(v.id, 0.0)), nm - 1u);
        m0 = mats[2u * id];
        shin = mats[2u * id + 1u].x;
    }
    var out: FOut;
    out.colour = vec4f(shade(m0, shin, n, d), th);
    out.normal = vec4f(n, 0.0);
    out.id_steps = vec2u(id, steps);
    let c = mg.view_proj * vec4f(p, 1.0);
    out.depth = clamp(c.z / c.w, 0.0, 1.0);
    return out;
}
