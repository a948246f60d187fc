//! The GPU path tracer: fathom-pathtrace's integrator in WGSL (`wgsl/path.wgsl`) on the
//! renderer's own tape and parameter buffers, accumulating samples in a buffer on the device
//! and showing the running mean in a texture a window can sample.
//!
//! What a scene means is decided once, on the CPU: [`Renderer::path_begin`] builds a
//! [`fathom_pathtrace::PathTracer`] (validation, looks from the materials, lights with their
//! angular size, the sky as environment, the thin lens, the march parameters) and bakes what
//! it prepared into the path pipeline's buffers. An edit is a new `path_begin` (and a
//! [`Renderer::set_tape`]): buffer writes only; the shader module and pipeline are built once
//! per renderer, the first time a path is traced.
//!
//! Not yet on the GPU (refused with [`GpuError::PathUnsupported`], never silently dropped):
//! sphere lights, environment maps, fog, gradient-stop colouring, more than one colouring
//! layer per node and more than [`MAX_CONE_LIGHTS`] directional lights.
//!
//! One dispatch adds one sample to every pixel; the sample index is the pass number, so the
//! per-pixel Owen-scrambled Sobol sequence is the CPU's (same hashes, same dimension order)
//! and an image depends only on (scene, size, seed, samples), not on how the passes were
//! split into calls or bands.

use crate::error::GpuError;
use crate::precision;
use crate::renderer::Renderer;
use crate::shader;
use fathom_core::{Scene, Tape, limits};
use fathom_pathtrace::colour::{Gradient, Input, Look, Target};
use fathom_pathtrace::lights::Environment;
use fathom_pathtrace::microfacet::AlbedoTables;
use fathom_pathtrace::{Control, Frame, PathSettings, PathTracer, Stats};
use std::sync::atomic::Ordering;
use std::time::Instant;

pub use crate::path_state::{MATERIAL_VEC4S, MAX_CONE_LIGHTS, MAX_PATH_EVALUATIONS, MAX_SAMPLES};
use crate::path_state::{PIXEL_BYTES, PathState, PathTargets, PtCone, PtGlobals, PtPx};

/// The layouts of the Rust mirrors of path.wgsl's structs, for the layout test.
#[cfg(test)]
pub(crate) fn rust_layouts() -> Vec<crate::passes::Layout> {
    use std::mem::{offset_of, size_of};
    vec![
        (
            "PtGlobals",
            size_of::<PtGlobals>(),
            vec![
                ("eye", offset_of!(PtGlobals, eye), 16),
                ("forward", offset_of!(PtGlobals, forward), 16),
                ("right", offset_of!(PtGlobals, right), 16),
                ("up", offset_of!(PtGlobals, up), 16),
                ("env_top", offset_of!(PtGlobals, env_top), 16),
                ("env_bottom", offset_of!(PtGlobals, env_bottom), 16),
                ("dims", offset_of!(PtGlobals, dims), 16),
                ("dims2", offset_of!(PtGlobals, dims2), 16),
                ("pass_info", offset_of!(PtGlobals, pass_info), 16),
                (
                    "cones",
                    offset_of!(PtGlobals, cones),
                    size_of::<[PtCone; MAX_CONE_LIGHTS]>(),
                ),
            ],
        ),
        (
            "PtCone",
            size_of::<PtCone>(),
            vec![
                ("dir", offset_of!(PtCone, dir), 16),
                ("radiance", offset_of!(PtCone, radiance), 16),
            ],
        ),
        (
            "PtPx",
            size_of::<PtPx>(),
            vec![
                ("sum", offset_of!(PtPx, sum), 16),
                ("stats", offset_of!(PtPx, stats), 16),
                ("albedo", offset_of!(PtPx, albedo), 16),
                ("normal", offset_of!(PtPx, normal), 16),
            ],
        ),
    ]
}

fn unsupported(what: impl Into<String>) -> GpuError {
    GpuError::PathUnsupported(what.into())
}

/// The GPU table rows of one look: `[base, metallic]`, `[roughness, specular, specular
/// tint, transmission]`, `[emitted radiance, ior]`, `[absorption, layer weight]`, then the
/// layer `[input, target, range start, range end]` and its cosine palette rows a, b, c, d.
/// Inputs: trap 0, height 1, radius 2, normal-up 3; targets: base colour 0, roughness 1,
/// metallic 2, emission 3 (as `colour::Look::at` applies them). No layer: weight 0.
pub fn material_rows(node: usize, look: &Look) -> Result<[[f32; 4]; 9], GpuError> {
    if look.layers.len() > 1 {
        return Err(unsupported(format!(
            "node {node}: {} colouring layers (one at most)",
            look.layers.len()
        )));
    }
    let m = &look.material;
    let e = m.emitted();
    let f = |v: f64| v as f32;
    let mut rows = [[0.0f32; 4]; 9];
    rows[0] = [
        f(m.base_colour[0]),
        f(m.base_colour[1]),
        f(m.base_colour[2]),
        f(m.metallic),
    ];
    rows[1] = [
        f(m.roughness),
        f(m.specular),
        f(m.specular_tint),
        f(m.transmission),
    ];
    rows[2] = [f(e.x), f(e.y), f(e.z), f(m.ior)];
    rows[3] = [
        f(m.absorption[0]),
        f(m.absorption[1]),
        f(m.absorption[2]),
        0.0,
    ];
    if let Some(l) = look.layers.first() {
        let Gradient::Cosine(p) = &l.gradient else {
            return Err(unsupported(format!(
                "node {node}: a colouring gradient of stops (cosine palettes only)"
            )));
        };
        let input = match l.input {
            Input::Trap => 0.0,
            Input::Height => 1.0,
            Input::Radius => 2.0,
            Input::NormalUp => 3.0,
        };
        let target = match l.target {
            Target::BaseColour => 0.0,
            Target::Roughness => 1.0,
            Target::Metallic => 2.0,
            Target::Emission => 3.0,
        };
        rows[3][3] = f(l.weight);
        rows[4] = [input, target, f(l.range[0]), f(l.range[1])];
        for (k, row) in p.iter().enumerate() {
            rows[5 + k] = [f(row[0]), f(row[1]), f(row[2]), 0.0];
        }
    }
    Ok(rows)
}

/// The albedo tables as the shader reads them: E, W, E_avg, W_avg.
fn table_words() -> Vec<f32> {
    AlbedoTables::get()
        .raw()
        .iter()
        .flat_map(|t| t.iter().map(|&v| v as f32))
        .collect()
}

/// The uniform block for a prepared tracer (pass fields left 0).
fn globals(tracer: &PathTracer) -> Result<PtGlobals, GpuError> {
    if !tracer.sphere_lights().is_empty() {
        return Err(unsupported("sphere lights"));
    }
    if tracer.medium().is_some() {
        return Err(unsupported("fog (render.fog > 0 or a medium)"));
    }
    let (top, bottom) = match tracer.environment() {
        Environment::Sky { top, bottom } => (*top, *bottom),
        Environment::Uniform(c) => (*c, *c),
        Environment::Map { .. } => return Err(unsupported("environment maps")),
    };
    let cones_in = tracer.cone_lights();
    if cones_in.len() > MAX_CONE_LIGHTS {
        return Err(unsupported(format!(
            "{} directional lights (at most {MAX_CONE_LIGHTS})",
            cones_in.len()
        )));
    }
    let mut cones = [PtCone::default(); MAX_CONE_LIGHTS];
    for (c, l) in cones.iter_mut().zip(cones_in) {
        let d = l.direction;
        let r = l.radiance;
        *c = PtCone {
            dir: [d.x as f32, d.y as f32, d.z as f32, l.one_minus_cos as f32],
            radiance: [r.x as f32, r.y as f32, r.z as f32, l.shadows as u32 as f32],
        };
    }
    let lens = tracer.lens();
    let fr = &lens.frame;
    let mp = tracer.march_params();
    let env_light = tracer.environment_light();
    let v = |v: glam::DVec3, w: f64| [v.x as f32, v.y as f32, v.z as f32, w as f32];
    let (w, h) = tracer.size();
    Ok(PtGlobals {
        eye: v(fr.eye, lens.aperture),
        forward: v(fr.forward, lens.focus),
        right: v(fr.right, fr.tan_half_fov),
        up: v(fr.up, mp.eps_slope),
        env_top: v(top, env_light),
        env_bottom: v(bottom, mp.t_max.min(f32::MAX as f64)),
        dims: [w, h, mp.max_steps, tracer.max_bounces()],
        dims2: [
            cones_in.len() as u32,
            tracer.looks().len() as u32,
            tracer.seed(),
            tracer.light_sampling() as u32,
        ],
        pass_info: [
            0,
            0,
            0,
            (!tracer.environment().is_black() && env_light > 0.0) as u32,
        ],
        cones,
    })
}

fn entry(binding: u32, ty: wgpu::BindingType) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::COMPUTE,
        ty,
        count: None,
    }
}

fn storage(read_only: bool) -> wgpu::BindingType {
    wgpu::BindingType::Buffer {
        ty: wgpu::BufferBindingType::Storage { read_only },
        has_dynamic_offset: false,
        min_binding_size: None,
    }
}

impl PathState {
    fn new(r: &Renderer) -> Result<PathState, GpuError> {
        let src = shader::path_source();
        shader::validate(&src)?;
        let dev = &r.gpu.device;
        let scope = dev.push_error_scope(wgpu::ErrorFilter::Validation);
        // SAFETY: as for the render passes (renderer.rs): the interpreter's indices come from
        // tapes validated against `limits`; the path's own indices are pixel indices checked
        // against the image size, material ids clamped to the table's length, and table
        // lookups clamped to the table; every loop is bounded (steps, bounces, lights, and
        // MAX_PATH_EVALUATIONS).
        let module = unsafe {
            dev.create_shader_module_trusted(
                wgpu::ShaderModuleDescriptor {
                    label: Some("fathom path tracer"),
                    source: wgpu::ShaderSource::Wgsl(src.into()),
                },
                wgpu::ShaderRuntimeChecks::unchecked(),
            )
        };
        let layout = dev.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("fathom path"),
            entries: &[
                entry(
                    0,
                    wgpu::BindingType::Buffer {
                        ty: wgpu::BufferBindingType::Uniform,
                        has_dynamic_offset: false,
                        min_binding_size: None,
                    },
                ),
                entry(1, storage(true)),
                entry(2, storage(true)),
                entry(3, storage(false)),
                entry(
                    4,
                    wgpu::BindingType::StorageTexture {
                        access: wgpu::StorageTextureAccess::WriteOnly,
                        format: wgpu::TextureFormat::Rgba8Unorm,
                        view_dimension: wgpu::TextureViewDimension::D2,
                    },
                ),
                entry(5, storage(false)),
            ],
        });
        let pl = dev.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("fathom path"),
            bind_group_layouts: &[Some(&r.pipes.tape_layout), Some(&layout)],
            immediate_size: 0,
        });
        let pipeline = dev.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
            label: Some("path_trace"),
            layout: Some(&pl),
            module: &module,
            entry_point: Some("path_trace"),
            compilation_options: Default::default(),
            cache: None,
        });
        if let Some(e) = pollster::block_on(scope.pop()) {
            return Err(GpuError::Driver {
                what: "the path tracer's shader".into(),
                message: e.to_string(),
            });
        }
        use wgpu::BufferUsages as U;
        let buf = |label: &str, size: u64, usage: U| {
            dev.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size,
                usage,
                mapped_at_creation: false,
            })
        };
        let tables = table_words();
        Ok(PathState {
            pipeline,
            layout,
            globals_buf: buf(
                "fathom path globals",
                std::mem::size_of::<PtGlobals>() as u64,
                U::UNIFORM | U::COPY_DST,
            ),
            materials: buf(
                "fathom path materials",
                limits::MAX_NODES as u64 * MATERIAL_VEC4S as u64 * 16,
                U::STORAGE | U::COPY_DST,
            ),
            tables: {
                let b = buf(
                    "fathom path albedo tables",
                    tables.len() as u64 * 4,
                    U::STORAGE | U::COPY_DST,
                );
                r.gpu
                    .queue
                    .write_buffer(&b, 0, bytemuck::cast_slice(&tables));
                b
            },
            counters: buf(
                "fathom path counters",
                16,
                U::STORAGE | U::COPY_SRC | U::COPY_DST,
            ),
            targets: None,
            globals: None,
            stats: Stats::default(),
        })
    }

    /// The accumulation buffer, texture and bind group for a `w` x `h` image; `true` when
    /// they were (re)built.
    fn targets(&mut self, r: &Renderer, w: u32, h: u32) -> Result<bool, GpuError> {
        if self.targets.as_ref().is_some_and(|t| t.size == (w, h)) {
            return Ok(false);
        }
        self.targets = None;
        let tex_max = r.gpu.limits.max_texture_dimension_2d;
        if w > tex_max || h > tex_max {
            return Err(GpuError::ImageTooLarge {
                width: w,
                height: h,
                limit: tex_max,
            });
        }
        let bytes = w as u64 * h as u64 * PIXEL_BYTES;
        let max = r.gpu.limits.max_storage_buffer_binding_size;
        if bytes > max {
            return Err(GpuError::BufferTooLarge {
                what: format!("the path tracer's accumulation buffer of a {w}x{h} image"),
                bytes,
                limit: max,
            });
        }
        let dev = &r.gpu.device;
        let accum = dev.create_buffer(&wgpu::BufferDescriptor {
            label: Some("fathom path accumulation"),
            size: bytes,
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
            mapped_at_creation: false,
        });
        let texture = dev.create_texture(&wgpu::TextureDescriptor {
            label: Some("fathom path image"),
            size: wgpu::Extent3d {
                width: w,
                height: h,
                depth_or_array_layers: 1,
            },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: wgpu::TextureFormat::Rgba8Unorm,
            usage: wgpu::TextureUsages::STORAGE_BINDING
                | wgpu::TextureUsages::TEXTURE_BINDING
                | wgpu::TextureUsages::COPY_SRC,
            view_formats: &[],
        });
        let view = texture.create_view(&wgpu::TextureViewDescriptor::default());
        let e = |binding, resource| wgpu::BindGroupEntry { binding, resource };
        let group = dev.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("fathom path"),
            layout: &self.layout,
            entries: &[
                e(0, self.globals_buf.as_entire_binding()),
                e(1, self.materials.as_entire_binding()),
                e(2, self.tables.as_entire_binding()),
                e(3, accum.as_entire_binding()),
                e(4, wgpu::BindingResource::TextureView(&view)),
                e(5, self.counters.as_entire_binding()),
            ],
        });
        self.targets = Some(PathTargets {
            size: (w, h),
            accum,
            texture,
            group,
        });
        Ok(true)
    }
}

impl Renderer {
    /// Starts a path-traced image of `scene` with `settings` from the scene's camera: bakes
    /// the scene's lights, sky, materials and camera into the path tracer's buffers and
    /// forgets every sample. `tape` must be the tape last given to [`Renderer::set_tape`]
    /// (the path tracer reads the same instruction and parameter buffers). Builds the path
    /// pipeline on the first call only; later calls (edits, new views) write buffers.
    pub fn path_begin(
        &mut self,
        scene: &Scene,
        tape: &Tape,
        settings: PathSettings,
    ) -> Result<(), GpuError> {
        self.gpu.check_lost()?;
        let tracer = PathTracer::new(scene, tape, settings)?;
        let (w, h) = tracer.size();
        let cam = &scene.camera;
        let footprint = tracer.lens().frame.pixel_angle(h) * (cam.target - cam.eye).length();
        if precision::too_deep(footprint, cam.eye.length()) {
            return Err(GpuError::TooDeep {
                footprint,
                distance: cam.eye.length(),
            });
        }
        let g = globals(&tracer)?;
        let mut rows = Vec::with_capacity(tracer.looks().len());
        for (node, look) in tracer.looks().iter().enumerate() {
            rows.extend(material_rows(node, look)?);
        }
        if rows.len() as u64 * 16 > limits::MAX_NODES as u64 * MATERIAL_VEC4S as u64 * 16 {
            return Err(GpuError::BufferTooLarge {
                what: format!(
                    "the path tracer's table of {} materials",
                    tape.materials().len()
                ),
                bytes: rows.len() as u64 * 16,
                limit: limits::MAX_NODES as u64 * MATERIAL_VEC4S as u64 * 16,
            });
        }
        if self.path.is_none() {
            self.path = Some(PathState::new(self)?);
        }
        let mut state = self.path.take().expect("built above");
        match state.targets(self, w, h) {
            Ok(true) => {
                // The denoiser's bind groups held the old accumulation and texture.
                if let Some(d) = self.denoise.as_mut() {
                    d.targets = None;
                }
            }
            Ok(false) => {}
            Err(e) => {
                self.path = Some(state);
                return Err(e);
            }
        }
        let q = &self.gpu.queue;
        q.write_buffer(&state.materials, 0, bytemuck::cast_slice(&rows));
        q.write_buffer(&state.counters, 0, &[0u8; 16]);
        state.globals = Some(g);
        state.stats = Stats::default();
        self.path = Some(state);
        Ok(())
    }

    /// Adds `n` samples to every pixel of the image [`Renderer::path_begin`] started, one
    /// dispatch per sample, each submitted in bands of `band_rows` rows (a software adapter
    /// takes seconds per pass; bands let `control.progress` report in between). Cancellation
    /// is checked between passes: the accumulation always holds whole passes, and a cancel
    /// returns [`GpuError::Cancelled`] keeping the passes already done.
    pub fn path_add_samples(
        &mut self,
        n: u32,
        band_rows: u32,
        control: &Control,
    ) -> Result<(), GpuError> {
        let start = Instant::now();
        let state = self
            .path
            .as_mut()
            .ok_or_else(|| GpuError::Invalid("path_add_samples before path_begin".into()))?;
        let g = state
            .globals
            .ok_or_else(|| GpuError::Invalid("path_add_samples before path_begin".into()))?;
        let t = state
            .targets
            .as_ref()
            .expect("path_begin built the targets");
        let (w, h) = t.size;
        let band = band_rows.clamp(8, h.max(8)) / 8 * 8;
        let bands = h.div_ceil(band) as usize;
        let total = n as usize * bands;
        let first = state.stats.samples_per_pixel;
        if (first as u64 + n as u64) > MAX_SAMPLES as u64 {
            return Err(GpuError::Invalid(format!(
                "{} samples per pixel is more than the path tracer accumulates ({})",
                first as u64 + n as u64,
                MAX_SAMPLES
            )));
        }
        let mut result = Ok(());
        for k in 0..n {
            if control.cancel.is_some_and(|c| c.load(Ordering::Relaxed)) {
                result = Err(GpuError::Cancelled);
                break;
            }
            let mut y0 = 0;
            let mut b = 0;
            while y0 < h {
                let y1 = h.min(y0 + band);
                let mut gb = g;
                gb.pass_info[0] = first + k;
                gb.pass_info[1] = y0;
                gb.pass_info[2] = y1;
                self.gpu
                    .queue
                    .write_buffer(&state.globals_buf, 0, bytemuck::bytes_of(&gb));
                let mut enc = self
                    .gpu
                    .device
                    .create_command_encoder(&wgpu::CommandEncoderDescriptor::default());
                {
                    let mut pass = enc.begin_compute_pass(&wgpu::ComputePassDescriptor::default());
                    pass.set_pipeline(&state.pipeline);
                    pass.set_bind_group(0, &self.tape_group, &[]);
                    pass.set_bind_group(1, &t.group, &[]);
                    pass.dispatch_workgroups(w.div_ceil(8), (y1 - y0).div_ceil(8), 1);
                }
                self.gpu.queue.submit([enc.finish()]);
                b += 1;
                if let Some(p) = control.progress {
                    // Generous: a software adapter compiles the pipeline on its first dispatch.
                    self.gpu.wait(900)?;
                    p(k as usize * bands + b, total);
                }
                y0 = y1;
            }
            state.stats.samples_per_pixel += 1;
            state.stats.paths += w as u64 * h as u64;
        }
        self.gpu.wait(900)?;
        state.stats.seconds += start.elapsed().as_secs_f64();
        result
    }

    /// Samples per pixel accumulated since [`Renderer::path_begin`] (0 before it).
    pub fn path_samples(&self) -> u32 {
        self.path.as_ref().map_or(0, |s| s.stats.samples_per_pixel)
    }

    /// The accumulated image (colour, albedo, normal, depth, variance, material ids, mean
    /// evaluations per path), as [`fathom_pathtrace::Progressive::frame`] makes it, and the
    /// counters (paths, non-finite paths dropped, distance evaluations, seconds).
    pub fn path_frame(&self) -> Result<(Frame, Stats), GpuError> {
        let state = self
            .path
            .as_ref()
            .filter(|s| s.globals.is_some())
            .ok_or_else(|| GpuError::Invalid("path_frame before path_begin".into()))?;
        let t = state
            .targets
            .as_ref()
            .expect("path_begin built the targets");
        let (w, h) = t.size;
        let bytes = self.gpu.read_buffer(&t.accum, t.accum.size())?;
        let counters = self.gpu.read_buffer(&state.counters, 16)?;
        let px: &[PtPx] = bytemuck::cast_slice(&bytes);
        let samples = state.stats.samples_per_pixel;
        let n_px = w as usize * h as usize;
        let mut f = Frame {
            width: w,
            height: h,
            colour: Vec::with_capacity(n_px),
            albedo: Vec::with_capacity(n_px),
            normal: Vec::with_capacity(n_px),
            depth: Vec::with_capacity(n_px),
            variance: Vec::with_capacity(n_px),
            id: Vec::with_capacity(n_px),
            steps: Vec::with_capacity(n_px),
            samples,
        };
        let mut evaluations = 0.0f64;
        for p in px.iter().take(n_px) {
            // Before the first pass the buffer holds no sums at all.
            let p = if samples == 0 {
                PtPx {
                    sum: [0.0; 4],
                    stats: [0.0; 4],
                    albedo: [0.0; 4],
                    normal: [0.0, 0.0, 0.0, f32::from_bits(fathom_core::frame::NO_ID)],
                }
            } else {
                *p
            };
            let count = p.sum[3];
            let nn = count.max(1.0);
            f.colour.push([p.sum[0] / nn, p.sum[1] / nn, p.sum[2] / nn]);
            f.albedo.push(if count > 0.0 {
                [p.albedo[0] / nn, p.albedo[1] / nn, p.albedo[2] / nn]
            } else {
                [1.0; 3]
            });
            let nv = glam::Vec3::new(p.normal[0], p.normal[1], p.normal[2]).normalize_or_zero();
            f.normal.push(nv.to_array());
            let hits = p.stats[3];
            let hit = hits * 2.0 > count;
            f.depth.push(if hit {
                p.albedo[3] / hits
            } else {
                f32::INFINITY
            });
            let id = p.normal[3].to_bits();
            f.id.push(if hit { id } else { fathom_core::frame::NO_ID });
            evaluations += p.stats[2] as f64;
            f.steps
                .push((p.stats[2] as f64 / samples.max(1) as f64).min(u32::MAX as f64) as u32);
            f.variance.push(if count > 1.0 {
                p.stats[1] / (count - 1.0) / nn
            } else {
                0.0
            });
        }
        let c: &[u32] = bytemuck::cast_slice(&counters);
        let mut stats = state.stats.clone();
        stats.dropped_non_finite = c[0] as u64;
        stats.evaluations = evaluations as u64;
        Ok((f, stats))
    }

    /// The accumulation buffer, display texture and size of the current image.
    pub(crate) fn path_buffers(&self) -> Option<(&wgpu::Buffer, &wgpu::Texture, (u32, u32))> {
        let s = self.path.as_ref().filter(|s| s.globals.is_some())?;
        let t = s.targets.as_ref()?;
        Some((&t.accum, &t.texture, t.size))
    }

    /// The running mean of the path-traced image (8-bit sRGB, tonemapped as the output files
    /// are), updated by every pass, for a window to sample; `None` before
    /// [`Renderer::path_begin`].
    pub fn path_texture(&self) -> Option<&wgpu::Texture> {
        self.path
            .as_ref()
            .and_then(|s| s.targets.as_ref())
            .map(|t| &t.texture)
    }
}
