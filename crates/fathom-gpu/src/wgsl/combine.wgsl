// Combine operators (fathom-core combine.rs): `fn comb_<Name>(a: Val, b: Val, scale: f32,
// <params>) -> Val`, `a` the parent's value, `b` the child's, `scale` the distance scale at the
// parent (blend radii are lengths of the node's own frame).

fn comb_Union(a: Val, b: Val, scale: f32) -> Val {
    return val_select(a.d <= b.d, a, b);
}

fn comb_Subtract(a: Val, b: Val, scale: f32) -> Val {
    var nb = b;
    nb.d = -b.d;
    return val_select(a.d >= nb.d, a, nb);
}

fn comb_Intersect(a: Val, b: Val, scale: f32) -> Val {
    return val_select(a.d >= b.d, a, b);
}

fn comb_SmoothUnion(a: Val, b: Val, scale: f32, k0: f32) -> Val {
    let k = k0 * scale;
    let h = clamp(0.5 + 0.5 * (b.d - a.d) / k, 0.0, 1.0);
    let d = mix(b.d, a.d, h) - k * h * (1.0 - h);
    return val_blend(d, a, b, h);
}

fn comb_SmoothSubtract(a: Val, b: Val, scale: f32, k0: f32) -> Val {
    let k = k0 * scale;
    let h = clamp(0.5 - 0.5 * (a.d + b.d) / k, 0.0, 1.0);
    let d = mix(a.d, -b.d, h) + k * h * (1.0 - h);
    return val_blend(d, b, a, h);
}

fn comb_SmoothIntersect(a: Val, b: Val, scale: f32, k0: f32) -> Val {
    let k = k0 * scale;
    let h = clamp(0.5 - 0.5 * (b.d - a.d) / k, 0.0, 1.0);
    let d = mix(b.d, a.d, h) + k * h * (1.0 - h);
    return val_blend(d, a, b, h);
}
