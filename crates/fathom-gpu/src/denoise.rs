//! The path tracer's à-trous denoiser on the device (`wgsl/denoise.wgsl`, fathom-pathtrace's
//! `denoise.rs` pass for pass): it reads the accumulation buffer the path tracer writes, so a
//! window can show a denoised image without reading anything back, and
//! [`Renderer::path_denoise`] returns the same colours the CPU's `denoise` computes from
//! [`Renderer::path_frame`], within f32 rounding.

use crate::error::GpuError;
use crate::renderer::Renderer;
use crate::shader;
use fathom_pathtrace::DenoiseSettings;

/// `struct DnGlobals` of denoise.wgsl.
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
pub(crate) struct DnGlobals {
    /// Width, height, step, 0.
    pub dims: [u32; 4],
    /// Normal exponent, depth scale, luminance scale, 0.
    pub sigmas: [f32; 4],
}

/// `struct DnPx` of denoise.wgsl.
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
pub(crate) struct DnPx {
    /// Demodulated colour, variance.
    pub irr: [f32; 4],
    /// Normal, depth.
    pub guide: [f32; 4],
    /// Albedo, depth gradient.
    pub albedo: [f32; 4],
}

/// The layouts of the Rust mirrors of denoise.wgsl's structs, for the layout test.
#[cfg(test)]
pub(crate) fn rust_layouts() -> Vec<crate::passes::Layout> {
    use std::mem::{offset_of, size_of};
    vec![
        (
            "DnGlobals",
            size_of::<DnGlobals>(),
            vec![
                ("dims", offset_of!(DnGlobals, dims), 16),
                ("sigmas", offset_of!(DnGlobals, sigmas), 16),
            ],
        ),
        (
            "DnPx",
            size_of::<DnPx>(),
            vec![
                ("irr", offset_of!(DnPx, irr), 16),
                ("guide", offset_of!(DnPx, guide), 16),
                ("albedo", offset_of!(DnPx, albedo), 16),
            ],
        ),
    ]
}

use crate::path_state::DenoiseState;

impl DenoiseState {
    pub(crate) fn new(r: &Renderer) -> Result<DenoiseState, GpuError> {
        let src = shader::denoise_source();
        shader::validate(&src)?;
        let dev = &r.gpu.device;
        let scope = dev.push_error_scope(wgpu::ErrorFilter::Validation);
        let module = dev.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("fathom denoiser"),
            source: wgpu::ShaderSource::Wgsl(src.into()),
        });
        let buffer = |binding, read_only| wgpu::BindGroupLayoutEntry {
            binding,
            visibility: wgpu::ShaderStages::COMPUTE,
            ty: wgpu::BindingType::Buffer {
                ty: match read_only {
                    Some(read_only) => wgpu::BufferBindingType::Storage { read_only },
                    None => wgpu::BufferBindingType::Uniform,
                },
                has_dynamic_offset: false,
                min_binding_size: None,
            },
            count: None,
        };
        let layout = dev.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("fathom denoiser"),
            entries: &[
                buffer(0, None),
                buffer(1, Some(true)),
                buffer(2, Some(false)),
                buffer(3, Some(false)),
                wgpu::BindGroupLayoutEntry {
                    binding: 4,
                    visibility: wgpu::ShaderStages::COMPUTE,
                    ty: wgpu::BindingType::StorageTexture {
                        access: wgpu::StorageTextureAccess::WriteOnly,
                        format: wgpu::TextureFormat::Rgba8Unorm,
                        view_dimension: wgpu::TextureViewDimension::D2,
                    },
                    count: None,
                },
                buffer(5, Some(false)),
            ],
        });
        let pl = dev.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("fathom denoiser"),
            bind_group_layouts: &[Some(&layout)],
            immediate_size: 0,
        });
        let pipe = |entry: &str| {
            dev.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
                label: Some(entry),
                layout: Some(&pl),
                module: &module,
                entry_point: Some(entry),
                compilation_options: Default::default(),
                cache: None,
            })
        };
        let state = DenoiseState {
            prepare: pipe("dn_prepare"),
            gradient: pipe("dn_gradient"),
            atrous: pipe("dn_atrous"),
            finish: pipe("dn_finish"),
            layout,
            globals: dev.create_buffer(&wgpu::BufferDescriptor {
                label: Some("fathom denoiser globals"),
                size: std::mem::size_of::<DnGlobals>() as u64,
                usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            }),
            targets: None,
        };
        if let Some(e) = pollster::block_on(scope.pop()) {
            return Err(GpuError::Driver {
                what: "the denoiser's shader".into(),
                message: e.to_string(),
            });
        }
        Ok(state)
    }

    /// Runs the filter over `accum` (a `w` x `h` image) into the colour buffer and `texture`;
    /// returns the colour buffer.
    pub(crate) fn run(
        &mut self,
        r: &Renderer,
        accum: &wgpu::Buffer,
        texture: &wgpu::Texture,
        (w, h): (u32, u32),
        s: &DenoiseSettings,
    ) -> Result<&wgpu::Buffer, GpuError> {
        let dev = &r.gpu.device;
        if self.targets.as_ref().is_none_or(|t| t.0 != (w, h)) {
            self.targets = None;
            let px = w as u64 * h as u64;
            let bytes = px * std::mem::size_of::<DnPx>() as u64;
            let max = r.gpu.limits.max_storage_buffer_binding_size;
            if bytes > max {
                return Err(GpuError::BufferTooLarge {
                    what: format!("the denoiser's buffers of a {w}x{h} image"),
                    bytes,
                    limit: max,
                });
            }
            let buf = |label, size, usage| {
                dev.create_buffer(&wgpu::BufferDescriptor {
                    label: Some(label),
                    size,
                    usage,
                    mapped_at_creation: false,
                })
            };
            use wgpu::BufferUsages as U;
            let a = buf("fathom denoiser A", bytes, U::STORAGE);
            let b = buf("fathom denoiser B", bytes, U::STORAGE);
            let colour = buf("fathom denoised colour", px * 16, U::STORAGE | U::COPY_SRC);
            let view = texture.create_view(&wgpu::TextureViewDescriptor::default());
            let group = |from: &wgpu::Buffer, to: &wgpu::Buffer| {
                let e = |binding, resource| wgpu::BindGroupEntry { binding, resource };
                dev.create_bind_group(&wgpu::BindGroupDescriptor {
                    label: Some("fathom denoiser"),
                    layout: &self.layout,
                    entries: &[
                        e(0, self.globals.as_entire_binding()),
                        e(1, accum.as_entire_binding()),
                        e(2, from.as_entire_binding()),
                        e(3, to.as_entire_binding()),
                        e(4, wgpu::BindingResource::TextureView(&view)),
                        e(5, colour.as_entire_binding()),
                    ],
                })
            };
            let groups = [group(&a, &b), group(&b, &a)];
            self.targets = Some(((w, h), colour, groups));
        }
        let (_, colour, groups) = self.targets.as_ref().expect("made above");
        let q = &r.gpu.queue;
        // `current`: the group whose input (binding 2) holds the latest result.
        let mut current = 1;
        let step = |pipe: &wgpu::ComputePipeline, group: usize, stride: u32| {
            let g = DnGlobals {
                dims: [w, h, stride, 0],
                sigmas: [s.sigma_normal, s.sigma_depth, s.sigma_luminance, 0.0],
            };
            q.write_buffer(&self.globals, 0, bytemuck::bytes_of(&g));
            let mut enc = dev.create_command_encoder(&wgpu::CommandEncoderDescriptor::default());
            {
                let mut pass = enc.begin_compute_pass(&wgpu::ComputePassDescriptor::default());
                pass.set_pipeline(pipe);
                pass.set_bind_group(0, &groups[group], &[]);
                pass.dispatch_workgroups(w.div_ceil(8), h.div_ceil(8), 1);
            }
            q.submit([enc.finish()]);
        };
        // prepare writes B's partner: with group 1 (B -> A) it writes A.
        step(&self.prepare, 1, 0);
        current = 1 - current; // A holds the result: group 0 reads it.
        step(&self.gradient, current, 0);
        current = 1 - current;
        for pass in 0..s.passes {
            step(&self.atrous, current, 1 << pass);
            current = 1 - current;
        }
        step(&self.finish, current, 0);
        r.gpu.wait(900)?;
        Ok(colour)
    }
}

impl Renderer {
    /// Denoises the path tracer's current accumulation on the device (the window's texture,
    /// [`Renderer::path_texture`], then shows the denoised image until the next pass) and
    /// returns the denoised linear colour, row-major.
    pub fn path_denoise(&mut self, s: &DenoiseSettings) -> Result<Vec<[f32; 3]>, GpuError> {
        if self.denoise.is_none() {
            self.denoise = Some(DenoiseState::new(self)?);
        }
        let mut dn = self.denoise.take().expect("built above");
        let out = (|| {
            let (accum, texture, size) = self
                .path_buffers()
                .ok_or_else(|| GpuError::Invalid("path_denoise before path_begin".into()))?;
            let colour = dn.run(self, accum, texture, size, s)?;
            let bytes = self.gpu.read_buffer(colour, colour.size())?;
            let px: &[[f32; 4]] = bytemuck::cast_slice(&bytes);
            Ok(px.iter().map(|c| [c[0], c[1], c[2]]).collect())
        })();
        self.denoise = Some(dn);
        out
    }
}
