//! The GPU path tracer's data: the Rust mirrors of `path.wgsl`'s structs and constants, and
//! the long-lived state a [`crate::Renderer`] keeps for the path tracer ([`PathState`]) and
//! its denoiser ([`DenoiseState`]). Plain data below the renderer, so the renderer can hold it
//! while `path.rs` and `denoise.rs` (which need the renderer) implement what it does.

use fathom_pathtrace::Stats;

/// Most directional lights the GPU path tracer takes.
pub const MAX_CONE_LIGHTS: usize = 8;
/// vec4s per material in the GPU table (see [`material_rows`]).
pub const MATERIAL_VEC4S: u32 = 9;
/// Most distance evaluations of one path: every march is bounded by the scene's step limit,
/// this only keeps a corrupt tape from hanging the device.
pub const MAX_PATH_EVALUATIONS: u32 = 1 << 24;
/// Most samples per pixel one image accumulates (the command line's `--spp` range).
pub const MAX_SAMPLES: u32 = 1 << 20;
/// Bytes of one pixel's running sums (`struct PtPx`).
pub(crate) const PIXEL_BYTES: u64 = std::mem::size_of::<PtPx>() as u64;

/// The constants `path.wgsl` shares with this module.
pub(crate) fn wgsl_declarations() -> String {
    format!(
        "// GENERATED from fathom_gpu::path.\nconst PT_MATERIAL_VEC4S: u32 = {MATERIAL_VEC4S}u;\n\
         const PT_MAX_EVALUATIONS: u32 = {MAX_PATH_EVALUATIONS}u;\n"
    )
}

/// `struct PtCone` of path.wgsl.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, bytemuck::Pod, bytemuck::Zeroable)]
pub(crate) struct PtCone {
    /// Unit direction towards the light; w: 1 - cos(angular radius), 0 for a delta light.
    pub dir: [f32; 4],
    /// Radiance (irradiance for a delta light); w: 1 when it casts shadows.
    pub radiance: [f32; 4],
}

/// The uniform block of the path tracer: `struct PtGlobals` of path.wgsl, field for field.
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
pub(crate) struct PtGlobals {
    /// Eye; w: lens radius.
    pub eye: [f32; 4],
    /// w: focus distance.
    pub forward: [f32; 4],
    /// w: tan(fov / 2).
    pub right: [f32; 4],
    /// w: hit threshold per unit distance.
    pub up: [f32; 4],
    /// Sky straight up; w: environment light scale.
    pub env_top: [f32; 4],
    /// Sky at and below the horizon; w: t_max.
    pub env_bottom: [f32; 4],
    /// Width, height, max steps, max bounces.
    pub dims: [u32; 4],
    /// Directional lights, materials, seed, light sampling.
    pub dims2: [u32; 4],
    /// Sample index, first row, end row, environment sampled.
    pub pass_info: [u32; 4],
    pub cones: [PtCone; MAX_CONE_LIGHTS],
}

/// One pixel's running sums: `struct PtPx` of path.wgsl.
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
pub(crate) struct PtPx {
    /// Radiance sum, finite samples.
    pub sum: [f32; 4],
    /// Welford mean and M2 of luminance, distance evaluations, hits.
    pub stats: [f32; 4],
    /// First-hit albedo sum, first-hit depth sum.
    pub albedo: [f32; 4],
    /// First-hit normal sum, material id bits.
    pub normal: [f32; 4],
}

/// The path pipeline and the buffers that do not depend on the image size.
pub(crate) struct PathState {
    pub(crate) pipeline: wgpu::ComputePipeline,
    pub(crate) layout: wgpu::BindGroupLayout,
    pub(crate) globals_buf: wgpu::Buffer,
    pub(crate) materials: wgpu::Buffer,
    pub(crate) tables: wgpu::Buffer,
    pub(crate) counters: wgpu::Buffer,
    pub(crate) targets: Option<PathTargets>,
    /// The prepared frame (None until `path_begin`).
    pub(crate) globals: Option<PtGlobals>,
    pub(crate) stats: Stats,
}

/// The accumulation buffer and display texture of one image size.
pub(crate) struct PathTargets {
    pub(crate) size: (u32, u32),
    pub(crate) accum: wgpu::Buffer,
    pub(crate) texture: wgpu::Texture,
    pub(crate) group: wgpu::BindGroup,
}

/// The denoiser's pipelines (built once per renderer) and its buffers for one image size.
pub(crate) struct DenoiseState {
    pub(crate) prepare: wgpu::ComputePipeline,
    pub(crate) gradient: wgpu::ComputePipeline,
    pub(crate) atrous: wgpu::ComputePipeline,
    pub(crate) finish: wgpu::ComputePipeline,
    pub(crate) layout: wgpu::BindGroupLayout,
    pub(crate) globals: wgpu::Buffer,
    /// (size, colour buffer, bind groups reading A writing B and reading B writing A); they
    /// bind the path tracer's accumulation and texture, so they are dropped when those are
    /// rebuilt.
    pub(crate) targets: Option<((u32, u32), wgpu::Buffer, [wgpu::BindGroup; 2])>,
}
