// The à-trous denoiser of fathom-pathtrace (denoise.rs) in WGSL, pass for pass, on the path
// tracer's accumulation buffer: demodulate by the first-hit albedo, PT_ATROUS_PASSES passes of
// the 5x5 B3-spline kernel with holes weighted by normal, depth and luminance (against the
// prefiltered standard deviation, the variance filtered with the squared weights), remodulate.
// Every pass reads `dn_a` and writes `dn_b`; the host swaps them between passes.

struct DnGlobals {
    dims: vec4u,   // width, height, step (pixels between taps), 0
    sigmas: vec4f, // normal exponent, depth scale, luminance scale, 0
}

struct DnPx {
    irr: vec4f,    // demodulated colour, variance of its luminance
    guide: vec4f,  // normal, depth (-1: no surface)
    albedo: vec4f, // albedo (floored at PT_DENOISE_MIN_ALBEDO), |grad depth| per pixel
}

@group(0) @binding(0) var<uniform> dg: DnGlobals;
@group(0) @binding(1) var<storage, read> dn_accum: array<PtPx>;
@group(0) @binding(2) var<storage, read_write> dn_a: array<DnPx>;
@group(0) @binding(3) var<storage, read_write> dn_b: array<DnPx>;
@group(0) @binding(4) var dn_out: texture_storage_2d<rgba8unorm, write>;
@group(0) @binding(5) var<storage, read_write> dn_colour: array<vec4f>;

fn dn_lum(c: vec3f) -> f32 {
    return 0.2126 * c.x + 0.7152 * c.y + 0.0722 * c.z;
}

fn dn_index(gid: vec3u) -> i32 {
    if gid.x >= dg.dims.x || gid.y >= dg.dims.y {
        return -1;
    }
    return i32(gid.y * dg.dims.x + gid.x);
}

// The frame progressive.rs's `frame` makes of a pixel, demodulated.
@compute @workgroup_size(8, 8)
fn dn_prepare(@builtin(global_invocation_id) gid: vec3u) {
    let i = dn_index(gid);
    if i < 0 {
        return;
    }
    let p = dn_accum[i];
    let n = p.sum.w;
    let nn = max(n, 1.0);
    let colour = p.sum.xyz / nn;
    var albedo = vec3f(1.0);
    if n > 0.0 {
        albedo = p.albedo.xyz / nn;
    }
    albedo = max(albedo, vec3f(PT_DENOISE_MIN_ALBEDO));
    let ln = length(p.normal.xyz);
    let normal = select(vec3f(0.0), p.normal.xyz / ln, ln > 0.0);
    let hits = p.stats.w;
    let depth = select(-1.0, p.albedo.w / hits, hits * 2.0 > n);
    var variance = 0.0;
    if n > 1.0 {
        variance = p.stats.y / (n - 1.0) / nn;
    }
    let a = max(dn_lum(albedo), PT_DENOISE_MIN_ALBEDO);
    dn_b[i] = DnPx(vec4f(colour / albedo, variance / (a * a)), vec4f(normal, depth), vec4f(albedo, 0.0));
}

// The depth gradient: the largest difference to a 4-neighbour with a surface.
@compute @workgroup_size(8, 8)
fn dn_gradient(@builtin(global_invocation_id) gid: vec3u) {
    let i = dn_index(gid);
    if i < 0 {
        return;
    }
    var p = dn_a[i];
    let z = p.guide.w;
    var g = 0.0;
    let w = i32(dg.dims.x);
    let h = i32(dg.dims.y);
    for (var k = 0; k < 4; k++) {
        let qx = i32(gid.x) + select(select(0, 1, k == 0), -1, k == 1);
        let qy = i32(gid.y) + select(select(0, 1, k == 2), -1, k == 3);
        if qx < 0 || qy < 0 || qx >= w || qy >= h {
            continue;
        }
        let zq = dn_a[qy * w + qx].guide.w;
        if z >= 0.0 && zq >= 0.0 {
            g = max(g, abs(z - zq));
        }
    }
    p.albedo.w = g;
    dn_b[i] = p;
}

// The B3-spline taps 1/16, 1/4, 3/8, 1/4, 1/16 (denoise.rs's KERNEL).
fn dn_kernel(k: i32) -> f32 {
    if k == 2 {
        return 0.375;
    }
    return select(0.0625, 0.25, k == 1 || k == 3);
}

fn weight_normal(np: vec3f, nq: vec3f, sigma: f32) -> f32 {
    if all(np == vec3f(0.0)) && all(nq == vec3f(0.0)) {
        return 1.0;
    }
    let d = dot(np, nq);
    if d <= 0.0 {
        return 0.0;
    }
    return pow(d, sigma);
}

fn weight_depth(zp: f32, zq: f32, grad: f32, dist: f32, sigma: f32) -> f32 {
    if zp < 0.0 && zq < 0.0 {
        return 1.0;
    }
    if zp < 0.0 || zq < 0.0 {
        return 0.0;
    }
    let scale = sigma * grad * dist + 1e-3 * abs(zp) + 1e-9;
    return exp(-abs(zp - zq) / scale);
}

// One à-trous pass with step dg.dims.z.
@compute @workgroup_size(8, 8)
fn dn_atrous(@builtin(global_invocation_id) gid: vec3u) {
    let i = dn_index(gid);
    if i < 0 {
        return;
    }
    let w = i32(dg.dims.x);
    let h = i32(dg.dims.y);
    let x = i32(gid.x);
    let y = i32(gid.y);
    // The standard deviation after a 3x3 Gaussian blur of the variance.
    var vs = 0.0;
    var vw = 0.0;
    for (var ky = 0; ky < 3; ky++) {
        for (var kx = 0; kx < 3; kx++) {
            let qx = x + kx - 1;
            let qy = y + ky - 1;
            if qx < 0 || qy < 0 || qx >= w || qy >= h {
                continue;
            }
            let gw = select(0.25, 0.5, kx == 1) * select(0.25, 0.5, ky == 1);
            vs += gw * dn_a[qy * w + qx].irr.w;
            vw += gw;
        }
    }
    let sd = sqrt(max(vs / vw, 0.0));
    let p = dn_a[i];
    let lp = dn_lum(p.irr.xyz);
    let step = i32(dg.dims.z);
    var sum = vec3f(0.0);
    var wsum = 0.0;
    var vsum = 0.0;
    for (var ky = 0; ky < 5; ky++) {
        for (var kx = 0; kx < 5; kx++) {
            let dx = (kx - 2) * step;
            let dy = (ky - 2) * step;
            let qx = x + dx;
            let qy = y + dy;
            if qx < 0 || qy < 0 || qx >= w || qy >= h {
                continue;
            }
            let q = dn_a[qy * w + qx];
            let dist = sqrt(f32(dx * dx + dy * dy));
            let wt = dn_kernel(kx) * dn_kernel(ky)
                * weight_normal(p.guide.xyz, q.guide.xyz, dg.sigmas.x)
                * weight_depth(p.guide.w, q.guide.w, p.albedo.w, dist, dg.sigmas.y)
                * exp(-abs(lp - dn_lum(q.irr.xyz)) / (dg.sigmas.z * sd + 1e-6));
            sum += wt * q.irr.xyz;
            wsum += wt;
            vsum += wt * wt * q.irr.w;
        }
    }
    // The centre tap always has weight 3/8 * 3/8 > 0.
    dn_b[i] = DnPx(vec4f(sum / wsum, vsum / (wsum * wsum)), p.guide, p.albedo);
}

// Remodulate: the denoised colour, for reading back and for the window.
@compute @workgroup_size(8, 8)
fn dn_finish(@builtin(global_invocation_id) gid: vec3u) {
    let i = dn_index(gid);
    if i < 0 {
        return;
    }
    let p = dn_a[i];
    let c = p.irr.xyz * p.albedo.xyz;
    dn_colour[i] = vec4f(c, 1.0);
    textureStore(dn_out, vec2i(gid.xy), vec4f(to_srgb(c.x), to_srgb(c.y), to_srgb(c.z), 1.0));
}
