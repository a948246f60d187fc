//! The GPU renderer, the seed's method: the shell's tetrahedra are rasterised with wgpu (back
//! faces culled, so each fragment is a ray entering one tetrahedron), the fragment shader
//! marches the texture inside its tetrahedron with fathom-gpu's WGSL tape interpreter
//! (`fathom_gpu::shader::interpreter_source`, not a second interpreter) and writes the hit's
//! depth, so the depth test keeps the nearest hit over every tetrahedron. `micro.wgsl` mirrors
//! `march.rs` and `shade.rs`, so the two renderers agree pixel for pixel up to f32 rounding.

use crate::error::MicroError;
use crate::render::{BASE_ID, MicroScene, MicroStats, RenderOptions, t_max};
use crate::shell::Shell;
use fathom_core::Tape;
use fathom_core::frame::{Frame, NO_ID};
use fathom_gpu::{Gpu, GpuError};
use glam::{DMat4, DVec3, DVec4};
use std::time::Instant;

/// The shader after the interpreter library.
pub const MICRO_WGSL: &str = include_str!("micro.wgsl");

const COLOUR: wgpu::TextureFormat = wgpu::TextureFormat::Rgba32Float;
const NORMAL: wgpu::TextureFormat = wgpu::TextureFormat::Rgba16Float;
const ID: wgpu::TextureFormat = wgpu::TextureFormat::Rg32Uint;
const DEPTH: wgpu::TextureFormat = wgpu::TextureFormat::Depth32Float;

/// The whole WGSL program.
pub fn source() -> String {
    fathom_gpu::shader::interpreter_source() + MICRO_WGSL
}

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct Globals {
    view_proj: [[f32; 4]; 4],
    v: [[f32; 4]; 7],
    lights: [[f32; 4]; 16],
}

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct GTet {
    planes: [[f32; 4]; 4],
    tex: [[f32; 4]; 4],
    normals: [[f32; 4]; 4],
}

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct Vertex {
    pos: [f32; 3],
    tet: u32,
}

struct ShellBuffers {
    vertices: wgpu::Buffer,
    tets: wgpu::Buffer,
    count: u32,
    /// Identity of the shell uploaded (tetrahedron count and first vertex).
    key: (usize, [u64; 3]),
}

/// The microgeometry renderer on one device.
pub struct MicroGpu {
    gpu: Gpu,
    pipeline: wgpu::RenderPipeline,
    tape_layout: wgpu::BindGroupLayout,
    micro_layout: wgpu::BindGroupLayout,
    globals: wgpu::Buffer,
    counters: wgpu::Buffer,
    tape: Option<(wgpu::Buffer, wgpu::Buffer, wgpu::Buffer, Vec<u32>)>,
    shell: Option<ShellBuffers>,
    uploads: TapeUploads,
}

/// How texture tapes reached the device: whole new buffers (a new instruction stream) or a
/// rewrite of the parameter and material buffers only (an animation frame).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct TapeUploads {
    /// Uploads that created new tape buffers.
    pub tapes_created: u64,
    /// Uploads that rewrote only the parameter and material buffers.
    pub params_rewritten: u64,
}

fn entry(
    binding: u32,
    vis: wgpu::ShaderStages,
    ty: wgpu::BufferBindingType,
) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility: vis,
        ty: wgpu::BindingType::Buffer {
            ty,
            has_dynamic_offset: false,
            min_binding_size: None,
        },
        count: None,
    }
}

fn e(binding: u32, b: &wgpu::Buffer) -> wgpu::BindGroupEntry<'_> {
    wgpu::BindGroupEntry {
        binding,
        resource: b.as_entire_binding(),
    }
}

impl MicroGpu {
    /// A headless renderer on Vulkan (lavapipe without a GPU), failing loudly without one.
    pub fn headless() -> Result<MicroGpu, MicroError> {
        Ok(MicroGpu::new(Gpu::headless_vulkan()?)?)
    }

    /// Builds the shader and pipeline on `gpu`.
    pub fn new(gpu: Gpu) -> Result<MicroGpu, GpuError> {
        let src = source();
        fathom_gpu::shader::validate(&src)?;
        let dev = &gpu.device;
        let scope = dev.push_error_scope(wgpu::ErrorFilter::Validation);
        // SAFETY: as fathom-gpu's renderer: the interpreter's indices come from tapes the
        // compiler validated against fathom-core's limits, and its loops are bounded; this
        // shader's own indices are tetrahedron numbers from the vertex buffer built with the
        // tetrahedron buffer, material ids clamped to the table, and loops bounded by the
        // step limit. Without per-access checks the interpreter runs several times faster.
        let module = unsafe {
            dev.create_shader_module_trusted(
                wgpu::ShaderModuleDescriptor {
                    label: Some("fathom micro"),
                    source: wgpu::ShaderSource::Wgsl(src.into()),
                },
                wgpu::ShaderRuntimeChecks::unchecked(),
            )
        };
        use wgpu::BufferBindingType as B;
        use wgpu::ShaderStages as S;
        let ro = B::Storage { read_only: true };
        let tape_layout = dev.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("fathom micro tape"),
            entries: &[entry(0, S::FRAGMENT, ro), entry(1, S::FRAGMENT, ro)],
        });
        let micro_layout = dev.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("fathom micro"),
            entries: &[
                entry(0, S::VERTEX | S::FRAGMENT, B::Uniform),
                entry(1, S::FRAGMENT, ro),
                entry(2, S::FRAGMENT, ro),
                entry(3, S::FRAGMENT, B::Storage { read_only: false }),
            ],
        });
        let layout = dev.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: None,
            bind_group_layouts: &[Some(&tape_layout), Some(&micro_layout)],
            immediate_size: 0,
        });
        let target = |format| {
            Some(wgpu::ColorTargetState {
                format,
                blend: None,
                write_mask: wgpu::ColorWrites::ALL,
            })
        };
        let pipeline = dev.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some("fathom micro"),
            layout: Some(&layout),
            vertex: wgpu::VertexState {
                module: &module,
                entry_point: Some("vs_main"),
                compilation_options: Default::default(),
                buffers: &[Some(wgpu::VertexBufferLayout {
                    array_stride: std::mem::size_of::<Vertex>() as u64,
                    step_mode: wgpu::VertexStepMode::Vertex,
                    attributes: &wgpu::vertex_attr_array![0 => Float32x3, 1 => Uint32],
                })],
            },
            primitive: wgpu::PrimitiveState {
                topology: wgpu::PrimitiveTopology::TriangleList,
                front_face: wgpu::FrontFace::Ccw,
                cull_mode: Some(wgpu::Face::Back),
                ..Default::default()
            },
            depth_stencil: Some(wgpu::DepthStencilState {
                format: DEPTH,
                depth_write_enabled: Some(true),
                depth_compare: Some(wgpu::CompareFunction::Less),
                stencil: Default::default(),
                bias: Default::default(),
            }),
            multisample: Default::default(),
            fragment: Some(wgpu::FragmentState {
                module: &module,
                entry_point: Some("fs_main"),
                compilation_options: Default::default(),
                targets: &[target(COLOUR), target(NORMAL), target(ID)],
            }),
            multiview_mask: None,
            cache: None,
        });
        if let Some(e) = pollster::block_on(scope.pop()) {
            return Err(GpuError::Driver {
                what: "the fathom micro shader".into(),
                message: e.to_string(),
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
        let globals = buf(
            "fathom micro globals",
            std::mem::size_of::<Globals>() as u64,
            U::UNIFORM | U::COPY_DST,
        );
        let counters = buf(
            "fathom micro counters",
            16,
            U::STORAGE | U::COPY_SRC | U::COPY_DST,
        );
        Ok(MicroGpu {
            gpu,
            pipeline,
            tape_layout,
            micro_layout,
            globals,
            counters,
            tape: None,
            shell: None,
            uploads: TapeUploads::default(),
        })
    }

    /// How many texture tapes were uploaded whole and how many only rewrote parameters.
    pub fn tape_uploads(&self) -> TapeUploads {
        self.uploads
    }

    /// Whether the adapter is a CPU implementation (its timings are CPU timings).
    pub fn is_software(&self) -> bool {
        self.gpu.is_software()
    }

    /// The adapter's name.
    pub fn adapter_name(&self) -> String {
        self.gpu.adapter_name()
    }

    fn storage(
        &self,
        label: &str,
        bytes: &[u8],
        usage: wgpu::BufferUsages,
        what: String,
    ) -> Result<wgpu::Buffer, GpuError> {
        let limit = self
            .gpu
            .limits
            .max_storage_buffer_binding_size
            .min(self.gpu.limits.max_buffer_size);
        let size = (bytes.len() as u64).max(16).next_multiple_of(4);
        if size > limit {
            return Err(GpuError::BufferTooLarge {
                what,
                bytes: size,
                limit,
            });
        }
        let b = self.gpu.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some(label),
            size,
            usage: usage | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        self.gpu.queue.write_buffer(&b, 0, bytes);
        Ok(b)
    }

    /// Uploads a texture's tape. A tape with the same instruction stream (an animation frame)
    /// rewrites only its parameters and materials.
    pub fn set_tape(&mut self, tape: &Tape) -> Result<(), GpuError> {
        let words = tape.words();
        let params = tape.params_f32();
        let mats: Vec<f32> = tape
            .materials()
            .iter()
            .flat_map(|m| {
                let a = m.albedo.map(|c| c as f32);
                [
                    a[0],
                    a[1],
                    a[2],
                    m.specular as f32,
                    m.shininess as f32,
                    0.0,
                    0.0,
                    0.0,
                ]
            })
            .collect();
        if let Some((_, p, m, w)) = &self.tape
            && *w == words
            && p.size() >= (params.len() as u64 * 4).max(16)
        {
            self.gpu
                .queue
                .write_buffer(p, 0, bytemuck::cast_slice(&params));
            self.gpu
                .queue
                .write_buffer(m, 0, bytemuck::cast_slice(&mats));
            self.uploads.params_rewritten += 1;
            return Ok(());
        }
        use wgpu::BufferUsages as U;
        let i = self.storage(
            "fathom micro instrs",
            bytemuck::cast_slice(&words),
            U::STORAGE,
            format!("the tape ({} instructions)", words.len() / 4),
        )?;
        let p = self.storage(
            "fathom micro params",
            bytemuck::cast_slice(&params),
            U::STORAGE,
            format!("the parameter buffer ({} parameters)", params.len()),
        )?;
        let m = self.storage(
            "fathom micro materials",
            bytemuck::cast_slice(&mats),
            U::STORAGE,
            format!("the material table ({} materials)", mats.len() / 8),
        )?;
        self.tape = Some((i, p, m, words));
        self.uploads.tapes_created += 1;
        Ok(())
    }

    /// Uploads a shell: four outward faces per tetrahedron, and the tetrahedra's maps.
    pub fn set_shell(&mut self, shell: &Shell) -> Result<(), GpuError> {
        let key = (
            shell.tets.len(),
            shell
                .tets
                .first()
                .map_or([0; 3], |t| t.verts[0].to_array().map(f64::to_bits)),
        );
        if self.shell.as_ref().is_some_and(|s| s.key == key) {
            return Ok(());
        }
        let f4 = |v: DVec3, w: f64| [v.x as f32, v.y as f32, v.z as f32, w as f32];
        let mut verts = Vec::with_capacity(shell.tets.len() * 12);
        let mut gt = Vec::with_capacity(shell.tets.len());
        for (ti, t) in shell.tets.iter().enumerate() {
            for k in 0..4 {
                for i in t.face_outward(k) {
                    verts.push(Vertex {
                        pos: t.verts[i].as_vec3().to_array(),
                        tet: ti as u32,
                    });
                }
            }
            gt.push(GTet {
                planes: t.planes.map(|w| w.map(|x| x as f32)),
                tex: t.tex.map(|s| f4(s, 0.0)),
                normals: std::array::from_fn(|k| {
                    let w = match k {
                        0 => t.lipschitz,
                        1 => t.bottom_face as f64,
                        _ => 0.0,
                    };
                    f4(t.normals[k], w)
                }),
            });
        }
        use wgpu::BufferUsages as U;
        let n = shell.tets.len();
        let vertices = self.storage(
            "fathom micro vertices",
            bytemuck::cast_slice(&verts),
            U::VERTEX,
            format!("the vertex buffer of {n} tetrahedra"),
        )?;
        let tets = self.storage(
            "fathom micro tetrahedra",
            bytemuck::cast_slice(&gt),
            U::STORAGE,
            format!("the buffer of {n} tetrahedra"),
        )?;
        self.shell = Some(ShellBuffers {
            vertices,
            tets,
            count: verts.len() as u32,
            key,
        });
        Ok(())
    }

    /// Renders `scene` with its texture's tape `tape` (the GPU path takes exact textures).
    pub fn render(
        &mut self,
        scene: &MicroScene,
        tape: &Tape,
        o: &RenderOptions,
    ) -> Result<(Frame, MicroStats), MicroError> {
        let start = Instant::now();
        o.validate()?;
        let (w, h) = (o.width, o.height);
        let tex_max = self.gpu.limits.max_texture_dimension_2d;
        if w > tex_max || h > tex_max {
            return Err(GpuError::ImageTooLarge {
                width: w,
                height: h,
                limit: tex_max,
            }
            .into());
        }
        self.gpu.check_lost()?;
        self.set_tape(tape)?;
        self.set_shell(&scene.shell)?;
        let cam = &o.camera;
        let frame_c = cam.frame();
        let (lo, hi) = scene.shell.bounds;
        let radius = 0.5 * (hi - lo).length();
        let dist = (cam.eye - 0.5 * (lo + hi)).length();
        let near = ((dist - radius) * 0.5).max(1e-4 * radius.max(1e-9));
        let far = t_max(&scene.shell, cam) * 1.01;
        let view_proj = view_projection(&frame_c, w as f64 / h as f64, near, far);
        let l = &scene.lighting;
        let f4 = |v: DVec3, w: f64| [v.x as f32, v.y as f32, v.z as f32, w as f32];
        let mut lights = [[0f32; 4]; 16];
        for (i, (d, c)) in l.lights.iter().enumerate().take(8) {
            lights[2 * i] = f4(*d, 0.0);
            lights[2 * i + 1] = f4(*c, 0.0);
        }
        let p = o.march_params();
        let cell = scene.shell.tiling.cell;
        let base = scene.base.clone().unwrap_or_default();
        let n_mats = tape.materials().len().max(1);
        let g = Globals {
            view_proj: view_proj.as_mat4().to_cols_array_2d(),
            v: [
                f4(cam.eye, p.eps_slope),
                f4(l.sky_top, l.ambient),
                f4(l.sky_bottom, o.pixel_angle()),
                f4(cell.min, p.max_steps as f64),
                f4(cell.size(), scene.base.is_some() as u8 as f64),
                [
                    base.albedo[0] as f32,
                    base.albedo[1] as f32,
                    base.albedo[2] as f32,
                    base.specular as f32,
                ],
                [
                    base.shininess as f32,
                    n_mats as f32,
                    l.lights.len().min(8) as f32,
                    o.smooth_normals as u8 as f32,
                ],
            ],
            lights,
        };
        let dev = &self.gpu.device;
        let q = &self.gpu.queue;
        q.write_buffer(&self.globals, 0, bytemuck::bytes_of(&g));
        q.write_buffer(&self.counters, 0, &[0u8; 16]);
        let (instrs, params, mats, _) = self.tape.as_ref().expect("set above");
        let sb = self.shell.as_ref().expect("set above");
        let bind = |layout, entries: &[wgpu::BindGroupEntry]| {
            dev.create_bind_group(&wgpu::BindGroupDescriptor {
                label: None,
                layout,
                entries,
            })
        };
        let g0 = bind(&self.tape_layout, &[e(0, instrs), e(1, params)]);
        let g1 = bind(
            &self.micro_layout,
            &[
                e(0, &self.globals),
                e(1, &sb.tets),
                e(2, mats),
                e(3, &self.counters),
            ],
        );
        let target = |format, usage: wgpu::TextureUsages| {
            dev.create_texture(&wgpu::TextureDescriptor {
                label: None,
                size: wgpu::Extent3d {
                    width: w,
                    height: h,
                    depth_or_array_layers: 1,
                },
                mip_level_count: 1,
                sample_count: 1,
                dimension: wgpu::TextureDimension::D2,
                format,
                usage,
                view_formats: &[],
            })
        };
        use wgpu::TextureUsages as T;
        let colour = target(COLOUR, T::RENDER_ATTACHMENT | T::COPY_SRC);
        let normal = target(NORMAL, T::RENDER_ATTACHMENT | T::COPY_SRC);
        let ids = target(ID, T::RENDER_ATTACHMENT | T::COPY_SRC);
        let depth = target(DEPTH, T::RENDER_ATTACHMENT);
        let views = [&colour, &normal, &ids].map(|t| t.create_view(&Default::default()));
        let dview = depth.create_view(&Default::default());
        let clears = [
            wgpu::Color {
                r: 0.0,
                g: 0.0,
                b: 0.0,
                a: -1.0,
            },
            wgpu::Color::TRANSPARENT,
            wgpu::Color {
                r: NO_ID as f64,
                g: 0.0,
                b: 0.0,
                a: 0.0,
            },
        ];
        let mut enc = dev.create_command_encoder(&Default::default());
        {
            let atts: Vec<Option<wgpu::RenderPassColorAttachment>> = views
                .iter()
                .zip(clears)
                .map(|(v, c)| {
                    Some(wgpu::RenderPassColorAttachment {
                        view: v,
                        depth_slice: None,
                        resolve_target: None,
                        ops: wgpu::Operations {
                            load: wgpu::LoadOp::Clear(c),
                            store: wgpu::StoreOp::Store,
                        },
                    })
                })
                .collect();
            let mut pass = enc.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("fathom micro"),
                color_attachments: &atts,
                depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                    view: &dview,
                    depth_ops: Some(wgpu::Operations {
                        load: wgpu::LoadOp::Clear(1.0),
                        store: wgpu::StoreOp::Store,
                    }),
                    stencil_ops: None,
                }),
                timestamp_writes: None,
                occlusion_query_set: None,
                multiview_mask: None,
            });
            pass.set_pipeline(&self.pipeline);
            pass.set_bind_group(0, &g0, &[]);
            pass.set_bind_group(1, &g1, &[]);
            pass.set_vertex_buffer(0, sb.vertices.slice(..));
            pass.draw(0..sb.count, 0..1);
        }
        // Copy the targets out, rows padded to wgpu's alignment.
        let readbacks: Vec<(wgpu::Buffer, u32)> = [(&colour, 16u32), (&normal, 8), (&ids, 8)]
            .iter()
            .map(|(t, bpp)| {
                let row = (w * bpp).next_multiple_of(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT);
                let b = dev.create_buffer(&wgpu::BufferDescriptor {
                    label: None,
                    size: row as u64 * h as u64,
                    usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::COPY_SRC,
                    mapped_at_creation: false,
                });
                enc.copy_texture_to_buffer(
                    t.as_image_copy(),
                    wgpu::TexelCopyBufferInfo {
                        buffer: &b,
                        layout: wgpu::TexelCopyBufferLayout {
                            offset: 0,
                            bytes_per_row: Some(row),
                            rows_per_image: None,
                        },
                    },
                    wgpu::Extent3d {
                        width: w,
                        height: h,
                        depth_or_array_layers: 1,
                    },
                );
                (b, row)
            })
            .collect();
        q.submit([enc.finish()]);
        self.gpu.wait(900)?;
        let mut data = Vec::new();
        for (b, row) in &readbacks {
            data.push((self.gpu.read_buffer(b, b.size())?, *row as usize));
        }
        let counts: Vec<u32> =
            bytemuck::cast_slice(&self.gpu.read_buffer(&self.counters, 16)?).to_vec();
        let mut frame = Frame::new(w, h);
        let mut stats = MicroStats {
            de_march: counts[0] as u64,
            de_shade: counts[1] as u64,
            tets_visited: counts[2] as u64,
            ..MicroStats::new(&scene.shell, w, h)
        };
        for y in 0..h as usize {
            for x in 0..w as usize {
                let i = y * w as usize + x;
                let c: &[f32] = bytemuck::cast_slice(&data[0].0[y * data[0].1 + x * 16..][..16]);
                let n: &[u16] = bytemuck::cast_slice(&data[1].0[y * data[1].1 + x * 8..][..8]);
                let id: &[u32] = bytemuck::cast_slice(&data[2].0[y * data[2].1 + x * 8..][..8]);
                frame.steps[i] = id[1];
                if c[3] < 0.0 {
                    let d = frame_c.ray_dir(x as f64 + 0.5, y as f64 + 0.5, w, h);
                    frame.colour[i] = l.sky(d).as_vec3().to_array();
                    continue;
                }
                frame.colour[i] = [c[0], c[1], c[2]];
                frame.depth[i] = c[3];
                frame.normal[i] = [0, 1, 2].map(|k| half::f16::from_bits(n[k]).to_f32());
                frame.id[i] = id[0];
                stats.hits += 1;
                if id[0] == BASE_ID {
                    stats.base_hits += 1;
                } else {
                    stats.texture_hits += 1;
                }
            }
        }
        stats.ms_total = start.elapsed().as_secs_f64() * 1e3;
        Ok((frame, stats))
    }
}

/// The clip-space transform matching `CameraFrame::ray_dir`: right-handed, looking down
/// `forward`, vertical field of view from `tan_half_fov`, depth 0 at `near` and 1 at `far`.
pub fn view_projection(c: &fathom_core::CameraFrame, aspect: f64, near: f64, far: f64) -> DMat4 {
    let (r, u, f, e) = (c.right, c.up, c.forward, c.eye);
    let view = DMat4::from_cols(
        DVec4::new(r.x, u.x, -f.x, 0.0),
        DVec4::new(r.y, u.y, -f.y, 0.0),
        DVec4::new(r.z, u.z, -f.z, 0.0),
        DVec4::new(-r.dot(e), -u.dot(e), f.dot(e), 1.0),
    );
    let (sy, sx) = (1.0 / c.tan_half_fov, 1.0 / (c.tan_half_fov * aspect));
    let a = far / (near - far);
    let proj = DMat4::from_cols(
        DVec4::new(sx, 0.0, 0.0, 0.0),
        DVec4::new(0.0, sy, 0.0, 0.0),
        DVec4::new(0.0, 0.0, a, -1.0),
        DVec4::new(0.0, 0.0, a * near, 0.0),
    );
    proj * view
}
