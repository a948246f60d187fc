//! The renderer's long-lived state: one shader module and its pipelines (built once per run),
//! the tape buffers (sized once to the documented tape limits, so a structure edit is a buffer
//! write and never a new buffer, bind group or pipeline), and point evaluation.

use crate::device::Gpu;
use crate::error::GpuError;
use crate::shader;
use fathom_core::limits;
use fathom_core::tape::Tape;

pub use fathom_core::Projection;

/// Bytes of one material in the GPU table: albedo + specular, shininess + trap colour + 2 pad.
pub(crate) const MATERIAL_BYTES: u64 = 32;

/// The compute pipelines of the one shader module.
pub(crate) struct Pipelines {
    pub eval_points: wgpu::ComputePipeline,
    pub prepass: [wgpu::ComputePipeline; 3],
    pub depth: wgpu::ComputePipeline,
    pub shade: wgpu::ComputePipeline,
    pub tape_layout: wgpu::BindGroupLayout,
    pub eval_layout: wgpu::BindGroupLayout,
    pub render_layout: wgpu::BindGroupLayout,
}

/// The GPU renderer: device, pipelines, tape buffers.
pub struct Renderer {
    pub(crate) gpu: Gpu,
    pub(crate) pipes: Pipelines,
    instrs: wgpu::Buffer,
    params: wgpu::Buffer,
    pub(crate) materials: wgpu::Buffer,
    pub(crate) tape_group: wgpu::BindGroup,
    /// Instruction words last uploaded, to skip identical uploads.
    uploaded: Vec<u32>,
    /// Number of materials of the current tape.
    pub(crate) n_materials: u32,
    /// Render targets of the last image size, reused while the size stays.
    pub(crate) targets: Option<Targets>,
    /// The path tracer's pipeline and accumulation (built on first use).
    pub(crate) path: Option<crate::path_state::PathState>,
    /// The path tracer's denoiser (built on first use).
    pub(crate) denoise: Option<crate::path_state::DenoiseState>,
}

/// Buffers and the output texture for one output size (rebuilt only when it changes).
pub(crate) struct Targets {
    pub(crate) key: (u32, u32, u32),
    pub(crate) globals: wgpu::Buffer,
    pub(crate) gbuf: wgpu::Buffer,
    pub(crate) counters: wgpu::Buffer,
    /// The displayable result (8-bit sRGB), for a window to sample.
    pub texture: wgpu::Texture,
    pub(crate) group: wgpu::BindGroup,
}

fn storage_entry(binding: u32, read_only: bool) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::COMPUTE,
        ty: wgpu::BindingType::Buffer {
            ty: wgpu::BufferBindingType::Storage { read_only },
            has_dynamic_offset: false,
            min_binding_size: None,
        },
        count: None,
    }
}

impl Pipelines {
    fn new(gpu: &Gpu) -> Result<Pipelines, GpuError> {
        let src = shader::source();
        // Validate first: naga's report names the registry entry, the driver's would not.
        shader::validate(&src)?;
        let dev = &gpu.device;
        let scope = dev.push_error_scope(wgpu::ErrorFilter::Validation);
        // SAFETY: the shader's only indices come from tapes the compiler validated against
        // `limits` (stack depths, loop nesting, parameter offsets inside the parameter buffer,
        // which is allocated at its largest size) and from loops bounded by uniforms the host
        // checks; the instruction loop is bounded by `MAX_EXECUTED`. Without wgpu's per-access
        // bounds checks and forced loop bounding the interpreter runs several times faster.
        let module = unsafe {
            dev.create_shader_module_trusted(
                wgpu::ShaderModuleDescriptor {
                    label: Some("fathom tape interpreter"),
                    source: wgpu::ShaderSource::Wgsl(src.into()),
                },
                wgpu::ShaderRuntimeChecks::unchecked(),
            )
        };
        let tape_layout = dev.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("fathom tape"),
            entries: &[storage_entry(0, true), storage_entry(1, true)],
        });
        let eval_layout = dev.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("fathom eval points"),
            entries: &[storage_entry(0, true), storage_entry(1, false)],
        });
        let render_layout = dev.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("fathom render"),
            entries: &[
                wgpu::BindGroupLayoutEntry {
                    binding: 2,
                    visibility: wgpu::ShaderStages::COMPUTE,
                    ty: wgpu::BindingType::Buffer {
                        ty: wgpu::BufferBindingType::Uniform,
                        has_dynamic_offset: false,
                        min_binding_size: None,
                    },
                    count: None,
                },
                storage_entry(3, true),
                storage_entry(4, false),
                storage_entry(5, false),
                wgpu::BindGroupLayoutEntry {
                    binding: 6,
                    visibility: wgpu::ShaderStages::COMPUTE,
                    ty: wgpu::BindingType::StorageTexture {
                        access: wgpu::StorageTextureAccess::WriteOnly,
                        format: wgpu::TextureFormat::Rgba8Unorm,
                        view_dimension: wgpu::TextureViewDimension::D2,
                    },
                    count: None,
                },
                storage_entry(7, false),
            ],
        });
        let layout = |g1: &wgpu::BindGroupLayout| {
            dev.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                label: None,
                bind_group_layouts: &[Some(&tape_layout), Some(g1)],
                immediate_size: 0,
            })
        };
        let eval_pl = layout(&eval_layout);
        let render_pl = layout(&render_layout);
        let pipe = |pl: &wgpu::PipelineLayout, entry: &str| {
            dev.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
                label: Some(entry),
                layout: Some(pl),
                module: &module,
                entry_point: Some(entry),
                compilation_options: Default::default(),
                cache: None,
            })
        };
        let p = Pipelines {
            eval_points: pipe(&eval_pl, "eval_points"),
            prepass: [
                pipe(&render_pl, "prepass_0"),
                pipe(&render_pl, "prepass_1"),
                pipe(&render_pl, "prepass_2"),
            ],
            depth: pipe(&render_pl, "depth"),
            shade: pipe(&render_pl, "shade"),
            tape_layout,
            eval_layout,
            render_layout,
        };
        if let Some(e) = pollster::block_on(scope.pop()) {
            return Err(GpuError::Driver {
                what: "the fathom shader".into(),
                message: e.to_string(),
            });
        }
        Ok(p)
    }
}

/// A point's value as the GPU computed it (mirrors `fathom_core::Value<f32>`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct GpuValue {
    /// Signed distance bound in world units.
    pub d: f32,
    /// Material id of the node that won the combine.
    pub id: f32,
    /// Second material id, blended in with weight `blend`.
    pub id2: f32,
    /// Weight of `id2`.
    pub blend: f32,
    /// Orbit trap: the smallest `|z|` an iteration reached.
    pub trap: f32,
}

impl Renderer {
    /// Builds the shader module and every pipeline, and the tape buffers at their largest size:
    /// the documented tape limits, or less on a device whose storage buffers are smaller (then
    /// a tape that does not fit is refused by [`Renderer::set_tape`] naming the limit).
    pub fn new(gpu: Gpu) -> Result<Renderer, GpuError> {
        let max_storage = gpu.limits.max_storage_buffer_binding_size;
        // (what, bytes at the documented limit, bytes of one entry, fewest entries usable)
        let wanted = [
            (
                "the tape's instruction buffer",
                limits::MAX_TAPE_LEN as u64 * 16,
                16,
                64,
            ),
            ("the parameter buffer", limits::MAX_PARAMS as u64 * 4, 4, 64),
            (
                "the material table",
                limits::MAX_NODES as u64 * MATERIAL_BYTES,
                MATERIAL_BYTES,
                16,
            ),
        ];
        let mut sizes = [("", 0u64); 3];
        for (i, (what, bytes, entry, fewest)) in wanted.into_iter().enumerate() {
            let fit = bytes.min(max_storage / entry * entry);
            if fit < fewest * entry {
                return Err(GpuError::BufferTooLarge {
                    what: format!("{what} (at least {fewest} entries)"),
                    bytes: fewest * entry,
                    limit: max_storage,
                });
            }
            sizes[i] = (what, fit);
        }
        let pipes = Pipelines::new(&gpu)?;
        let buf = |label: &str, size: u64| {
            gpu.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size,
                usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            })
        };
        let instrs = buf("fathom instrs", sizes[0].1);
        let params = buf("fathom params", sizes[1].1);
        let materials = buf("fathom materials", sizes[2].1);
        let tape_group = gpu.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("fathom tape"),
            layout: &pipes.tape_layout,
            entries: &[
                wgpu::BindGroupEntry {
                    binding: 0,
                    resource: instrs.as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 1,
                    resource: params.as_entire_binding(),
                },
            ],
        });
        Ok(Renderer {
            gpu,
            pipes,
            instrs,
            params,
            materials,
            tape_group,
            uploaded: Vec::new(),
            n_materials: 0,
            targets: None,
            path: None,
            denoise: None,
        })
    }

    /// Headless set-up in one call.
    pub fn headless() -> Result<Renderer, GpuError> {
        Renderer::new(Gpu::headless()?)
    }

    /// The device this renderer runs on.
    pub fn gpu(&self) -> &Gpu {
        &self.gpu
    }

    /// Shader modules and compute pipelines the device has created so far (wgpu's internal
    /// counters): the proof that editing a scene builds nothing.
    pub fn objects_built(&self) -> (isize, isize) {
        let c = self.gpu.device.get_internal_counters();
        (c.hal.shader_modules.read(), c.hal.compute_pipelines.read())
    }

    /// Uploads a tape. Parameter edits (same instruction stream) write only the parameter
    /// buffer and material table; structure edits also write the instruction buffer. Neither
    /// creates a buffer, bind group, shader module or pipeline.
    pub fn set_tape(&mut self, tape: &Tape) -> Result<(), GpuError> {
        let words = tape.words();
        let checks = [
            (
                format!("the tape ({} instructions)", words.len() / 4),
                words.len() as u64 * 4,
                self.instrs.size(),
            ),
            (
                format!("the parameter buffer ({} parameters)", tape.params().len()),
                tape.params().len() as u64 * 4,
                self.params.size(),
            ),
            (
                format!("the material table ({} materials)", tape.materials().len()),
                tape.materials().len() as u64 * MATERIAL_BYTES,
                self.materials.size(),
            ),
        ];
        for (what, bytes, limit) in checks {
            if bytes > limit {
                return Err(GpuError::BufferTooLarge { what, bytes, limit });
            }
        }
        self.gpu.check_lost()?;
        if words != self.uploaded {
            self.gpu
                .queue
                .write_buffer(&self.instrs, 0, bytemuck::cast_slice(&words));
            self.uploaded = words;
        }
        let p = tape.params_f32();
        if !p.is_empty() {
            self.gpu
                .queue
                .write_buffer(&self.params, 0, bytemuck::cast_slice(&p));
        }
        let mats: Vec<f32> = tape
            .materials()
            .iter()
            .flat_map(|m| {
                [
                    m.albedo[0] as f32,
                    m.albedo[1] as f32,
                    m.albedo[2] as f32,
                    m.specular as f32,
                    m.shininess as f32,
                    m.trap_colour as f32,
                    0.0,
                    0.0,
                ]
            })
            .collect();
        self.gpu
            .queue
            .write_buffer(&self.materials, 0, bytemuck::cast_slice(&mats));
        self.n_materials = tape.materials().len() as u32;
        Ok(())
    }

    /// Evaluates the current tape at world points on the GPU.
    pub fn eval_points(&mut self, points: &[[f32; 3]]) -> Result<Vec<GpuValue>, GpuError> {
        if points.is_empty() {
            return Ok(Vec::new());
        }
        let n = points.len() as u64;
        let max = self.gpu.limits.max_storage_buffer_binding_size;
        if n * 20 > max || n * 16 > max {
            return Err(GpuError::BufferTooLarge {
                what: format!("{n} points"),
                bytes: n * 20,
                limit: max,
            });
        }
        let groups = n.div_ceil(64);
        if groups > self.gpu.limits.max_compute_workgroups_per_dimension as u64 {
            return Err(GpuError::Invalid(format!(
                "{n} points is more than one dispatch can evaluate"
            )));
        }
        let dev = &self.gpu.device;
        let pts: Vec<[f32; 4]> = points.iter().map(|p| [p[0], p[1], p[2], 0.0]).collect();
        let input = dev.create_buffer(&wgpu::BufferDescriptor {
            label: Some("fathom points"),
            size: n * 16,
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        self.gpu
            .queue
            .write_buffer(&input, 0, bytemuck::cast_slice(&pts));
        let output = dev.create_buffer(&wgpu::BufferDescriptor {
            label: Some("fathom values"),
            size: n * 20,
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
            mapped_at_creation: false,
        });
        let group = dev.create_bind_group(&wgpu::BindGroupDescriptor {
            label: None,
            layout: &self.pipes.eval_layout,
            entries: &[
                wgpu::BindGroupEntry {
                    binding: 0,
                    resource: input.as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 1,
                    resource: output.as_entire_binding(),
                },
            ],
        });
        let mut enc = dev.create_command_encoder(&wgpu::CommandEncoderDescriptor::default());
        {
            let mut pass = enc.begin_compute_pass(&wgpu::ComputePassDescriptor::default());
            pass.set_pipeline(&self.pipes.eval_points);
            pass.set_bind_group(0, &self.tape_group, &[]);
            pass.set_bind_group(1, &group, &[]);
            pass.dispatch_workgroups(groups as u32, 1, 1);
        }
        self.gpu.queue.submit([enc.finish()]);
        let bytes = self.gpu.read_buffer(&output, n * 20)?;
        Ok(bytemuck::cast_slice(&bytes).to_vec())
    }
}
