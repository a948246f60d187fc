// The path tracer's running sums of one pixel (fathom-pathtrace progressive.rs's Pixel), written
// by path.wgsl and read by the denoiser (denoise.wgsl).
struct PtPx {
    sum: vec4f,    // radiance sum, finite samples
    stats: vec4f,  // Welford mean and M2 of luminance, distance evaluations, hits
    albedo: vec4f, // first-hit albedo sum, first-hit depth sum
    normal: vec4f, // first-hit normal sum, material id of the latest sample that hit (bits)
}
