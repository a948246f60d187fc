// Display conversions shared by the render passes and the path tracer (fathom-image's post.rs).

// post::tonemap: a soft shoulder above 0.8.
fn tonemap(x: f32) -> f32 {
    if !(x > 0.0) {
        return 0.0;
    }
    if x < 0.8 {
        return x;
    }
    return 0.8 + 0.2 * (1.0 - exp(-(x - 0.8) / 0.2));
}

// post::srgb of the tonemapped value, as the 8-bit output files store it.
fn to_srgb(c: f32) -> f32 {
    let x = clamp(tonemap(c), 0.0, 1.0);
    return select(1.055 * pow(x, 1.0 / 2.4) - 0.055, 12.92 * x, x <= 0.0031308);
}
