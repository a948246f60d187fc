// Fractals (fathom-core fractals.rs): `fn frac_<Name>(p: vec3f, <params>) -> vec2f` returning
// (distance estimate, orbit trap). Use the accurate `*_p` functions of common.wgsl rather than
// the built-in transcendentals, which Vulkan allows to be coarse. The CPU code iterates masked packets; here each invocation
// is one point, so "all lanes escaped" becomes an ordinary `break`.

fn frac_Mandelbulb(c: vec3f, power: f32, iterations: u32, bailout: f32) -> vec2f {
    var z = c;
    var dr = 1.0;
    var r = length(z);
    var trap = r;
    for (var i = 0u; i < iterations; i++) {
        if !(r < bailout) {
            break;
        }
        let safe_r = max(r, 1e-30);
        let theta = acos_p(clamp(z.z / safe_r, -1.0, 1.0)) * power;
        let phi = atan2_p(z.y, z.x) * power;
        let rp1 = pow(safe_r, power - 1.0);
        dr = rp1 * power * dr + 1.0;
        let zr = rp1 * safe_r;
        let sct = sincos_p(theta);
        let scp = sincos_p(phi);
        let st = sct.x;
        let ct = sct.y;
        let sp = scp.x;
        let cp = scp.y;
        z = vec3f(zr * st * cp, zr * sp * st, zr * ct) + c;
        r = length(z);
        trap = min(trap, r);
    }
    let d = 0.5 * log(max(r, 1e-30)) * r / dr;
    return vec2f(d, trap);
}
