//! One frame on the GPU: the multi-resolution cone-marching prepass (blocks of 8, 4 and 2
//! pixels), the depth pass (enhanced sphere tracing), and the colour pass, then the readback of
//! the G-buffer into a [`Frame`]. The passes mirror fathom-trace's, constant for constant, so
//! the two renderers agree pixel for pixel up to f32 rounding.
//!
//! Projections ([`Projection`], defined with its f64 ray generation in fathom-core's camera
//! module and mirrored by `view_ray` and `cone_base` in trace.wgsl): a pinhole camera,
//! side-by-side stereo, and omni-directional stereo (ODS) as an equirectangular top/bottom pair.

use crate::error::GpuError;
use crate::precision;
use crate::renderer::{Renderer, Targets};
use fathom_core::frame::{Frame, NO_ID};
use fathom_core::shared::PREPASS_LEVELS;
use fathom_core::{Camera, Evaluator, Projection, Scene, Tape, V3};
use std::time::Instant;

/// The projection's number in the shader's globals (`dims.z`).
fn mode(p: Projection) -> u32 {
    match p {
        Projection::Mono => 0,
        Projection::SideBySide { .. } => 1,
        Projection::Ods { .. } => 2,
    }
}

/// What to render.
#[derive(Clone, Copy, Debug)]
pub struct RenderOptions {
    /// Width of one eye's view in pixels.
    pub width: u32,
    /// Height of one eye's view in pixels.
    pub height: u32,
    /// Mono or one of the stereo layouts.
    pub projection: Projection,
    /// Run the cone-marching prepass.
    pub prepass: bool,
    /// Apply the scene's distance fog in the colour pass. A caller that reads the frame back
    /// and runs the shared post effects (fathom-image's `post::finish_view`, which fogs after SSAO
    /// as the CPU tracer does) turns this off; the displayable texture wants it on.
    pub fog: bool,
}

impl Default for RenderOptions {
    fn default() -> Self {
        RenderOptions {
            width: 640,
            height: 480,
            projection: Projection::Mono,
            prepass: true,
            fog: true,
        }
    }
}

/// Counters and timings of one GPU frame.
#[derive(Clone, Debug, Default)]
pub struct RenderStats {
    /// Output width in pixels.
    pub width: u32,
    /// Output height in pixels.
    pub height: u32,
    /// Distance evaluations of the prepass.
    pub de_prepass: u64,
    /// Distance evaluations of the depth pass.
    pub de_trace: u64,
    /// Distance evaluations of the colour pass.
    pub de_shade: u64,
    /// Primary rays that hit.
    pub hits: u64,
    /// From submission to the device finishing the passes.
    pub ms_gpu: f64,
    /// The whole frame: uploads, passes and readback.
    pub ms_total: f64,
}

impl RenderStats {
    /// Distance evaluations of the depth passes (prepass and primary rays) per pixel, the
    /// CPU tracer's definition.
    pub fn de_per_pixel(&self) -> f64 {
        (self.de_prepass + self.de_trace) as f64 / (self.width as f64 * self.height as f64)
    }
}

/// The uniform block of the render passes: `struct Globals` of trace.wgsl, field for field (a
/// test checks names, offsets and sizes against naga's layout of the WGSL declaration).
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
pub(crate) struct Globals {
    /// Eye position, high f32 part; w: pixel angle (footprint per unit distance).
    pub eye_hi: [f32; 4],
    /// Eye position, low f32 part; w: tan(fov / 2).
    pub eye_lo: [f32; 4],
    /// w: t_max.
    pub forward: [f32; 4],
    /// w: eps_slope (0.5 * pixel angle * pixel_epsilon).
    pub right: [f32; 4],
    /// w: t_start (distance bound at the eye).
    pub up: [f32; 4],
    /// w: ambient.
    pub sky_top: [f32; 4],
    /// w: AO strength.
    pub sky_bottom: [f32; 4],
    /// w: AO range.
    pub pal_a: [f32; 4],
    /// w: shadow softness.
    pub pal_b: [f32; 4],
    /// w: fog density (0: no fog in the shader).
    pub pal_c: [f32; 4],
    /// w: eye separation (stereo).
    pub pal_d: [f32; 4],
    /// View width, view height, projection (0 mono, 1 side-by-side, 2 ODS), max steps.
    pub dims: [u32; 4],
    /// Lights, materials, eyes, prepass on.
    pub dims2: [u32; 4],
    pub lights: [GpuLight; 8],
    /// The output rows `[x, y)` the depth and colour passes of one submit cover.
    pub rows: [u32; 4],
}

/// `struct Light` of trace.wgsl.
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
pub(crate) struct GpuLight {
    /// Unit direction towards the light; w = 1 when it casts shadows.
    pub dir: [f32; 4],
    /// Colour times intensity.
    pub colour: [f32; 4],
}

/// One pixel of the G-buffer: `struct GPx` of trace.wgsl.
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
pub(crate) struct GPx {
    /// Linear colour, depth (-1 = miss).
    pub cd: [f32; 4],
    /// Normal, 0.
    pub n: [f32; 4],
    /// Material id, steps, hit, 0.
    pub misc: [u32; 4],
}

/// A Rust mirror of a WGSL struct: its name, size, and (name, byte offset, byte size) of every
/// field in declaration order.
#[cfg(test)]
pub(crate) type Layout = (&'static str, usize, Vec<(&'static str, usize, usize)>);

/// The layouts of the Rust mirrors of the WGSL structs, for the layout test.
#[cfg(test)]
pub(crate) fn rust_layouts() -> Vec<Layout> {
    macro_rules! layout {
        ($t:ty { $($f:ident: $ft:ty),* $(,)? }) => {
            (
                stringify!($t),
                std::mem::size_of::<$t>(),
                vec![$((stringify!($f), std::mem::offset_of!($t, $f), std::mem::size_of::<$ft>())),*],
            )
        };
    }
    vec![
        layout!(Globals {
            eye_hi: [f32; 4],
            eye_lo: [f32; 4],
            forward: [f32; 4],
            right: [f32; 4],
            up: [f32; 4],
            sky_top: [f32; 4],
            sky_bottom: [f32; 4],
            pal_a: [f32; 4],
            pal_b: [f32; 4],
            pal_c: [f32; 4],
            pal_d: [f32; 4],
            dims: [u32; 4],
            dims2: [u32; 4],
            lights: [GpuLight; 8],
            rows: [u32; 4],
        }),
        layout!(GpuLight {
            dir: [f32; 4],
            colour: [f32; 4],
        }),
        layout!(GPx {
            cd: [f32; 4],
            n: [f32; 4],
            misc: [u32; 4],
        }),
    ]
}

/// Cells of all prepass levels for a `w` x `h` view and `eyes` eyes.
fn grid_cells(w: u32, h: u32, eyes: u32) -> u64 {
    PREPASS_LEVELS
        .iter()
        .map(|b| (w.div_ceil(*b) * h.div_ceil(*b)) as u64 * eyes as u64)
        .sum()
}

impl Renderer {
    fn targets(&mut self, o: &RenderOptions) -> Result<&Targets, GpuError> {
        let (ow, oh) = o.projection.output_size(o.width, o.height);
        let key = (o.width, o.height, mode(o.projection));
        if self.targets.as_ref().is_some_and(|t| t.key == key) {
            return Ok(self.targets.as_ref().unwrap());
        }
        self.targets = None;
        let dev = &self.gpu.device;
        let max = self.gpu.limits.max_storage_buffer_binding_size;
        let px = ow as u64 * oh as u64;
        let gbytes = px * std::mem::size_of::<GPx>() as u64;
        if gbytes > max {
            return Err(GpuError::BufferTooLarge {
                what: format!("the G-buffer of a {ow}x{oh} image"),
                bytes: gbytes,
                limit: max,
            });
        }
        let buf = |label: &str, size: u64, usage: wgpu::BufferUsages| {
            dev.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size,
                usage,
                mapped_at_creation: false,
            })
        };
        use wgpu::BufferUsages as U;
        let globals = buf(
            "fathom globals",
            std::mem::size_of::<Globals>() as u64,
            U::UNIFORM | U::COPY_DST,
        );
        let grid = buf(
            "fathom prepass grid",
            grid_cells(o.width, o.height, o.projection.eyes()) * 4,
            U::STORAGE,
        );
        let gbuf = buf("fathom gbuffer", gbytes, U::STORAGE | U::COPY_SRC);
        let counters = buf(
            "fathom counters",
            16,
            U::STORAGE | U::COPY_SRC | U::COPY_DST,
        );
        let texture = dev.create_texture(&wgpu::TextureDescriptor {
            label: Some("fathom image"),
            size: wgpu::Extent3d {
                width: ow,
                height: oh,
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
        let entry = |binding, resource| wgpu::BindGroupEntry { binding, resource };
        let group = dev.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("fathom render"),
            layout: &self.pipes.render_layout,
            entries: &[
                entry(2, globals.as_entire_binding()),
                entry(3, self.materials.as_entire_binding()),
                entry(4, grid.as_entire_binding()),
                entry(5, gbuf.as_entire_binding()),
                entry(6, wgpu::BindingResource::TextureView(&view)),
                entry(7, counters.as_entire_binding()),
            ],
        });
        self.targets = Some(Targets {
            key,
            globals,
            gbuf,
            counters,
            texture,
            group,
        });
        Ok(self.targets.as_ref().unwrap())
    }

    /// Compiles `scene`, uploads its tape and renders it from its own camera.
    pub fn render_scene(
        &mut self,
        scene: &Scene,
        o: &RenderOptions,
    ) -> Result<(Frame, RenderStats), GpuError> {
        let tape = Tape::compile(scene).map_err(|e| GpuError::Invalid(e.to_string()))?;
        self.set_tape(&tape)?;
        self.render(scene, &tape, &scene.camera, o)
    }

    /// Renders the tape last given to [`Renderer::set_tape`] (`tape` must be that tape; it is
    /// read on the CPU for the eye's distance bound) from `camera`, with `scene`'s lights and
    /// settings, and reads the G-buffer back into a [`Frame`].
    pub fn render(
        &mut self,
        scene: &Scene,
        tape: &Tape,
        camera: &Camera,
        o: &RenderOptions,
    ) -> Result<(Frame, RenderStats), GpuError> {
        self.render_in_bands(scene, tape, camera, o, u32::MAX, &mut |_, _| true)
    }

    /// Renders like [`Renderer::render`], but submits the depth and colour passes `band`
    /// output rows at a time (a multiple of 8) and waits for each: after every band but the
    /// last, `each(rows_done, rows)` is called, and `false` abandons the frame
    /// ([`GpuError::Cancelled`]). On a software adapter a frame can take seconds; bands let a
    /// window show its progress and drop it as soon as it goes stale. On a GPU a band costs a
    /// submission and a wait, so callers ask for bands only where a frame is slow.
    pub fn render_in_bands(
        &mut self,
        scene: &Scene,
        tape: &Tape,
        camera: &Camera,
        o: &RenderOptions,
        band: u32,
        each: &mut dyn FnMut(u32, u32) -> bool,
    ) -> Result<(Frame, RenderStats), GpuError> {
        let start = Instant::now();
        let globals = self.prepare(scene, tape, camera, o)?;
        let (_, oh) = o.projection.output_size(o.width, o.height);
        let band = band.max(8) / 8 * 8;
        let gpu_start = Instant::now();
        let mut y0 = 0;
        while y0 < oh {
            let y1 = oh.min(y0.saturating_add(band));
            self.submit_passes(&globals, o, y0 == 0, (y0, y1));
            if y1 < oh {
                // Generous: a software adapter compiles the pipelines on their first dispatch.
                self.gpu.wait(900)?;
                if !each(y1, oh) {
                    return Err(GpuError::Cancelled);
                }
            }
            y0 = y1;
        }
        self.gpu.wait(900)?;
        let ms_gpu = gpu_start.elapsed().as_secs_f64() * 1e3;
        let t = self.targets.as_ref().expect("submit built the targets");
        let gbytes = self.gpu.read_buffer(&t.gbuf, t.gbuf.size())?;
        let cbytes = self.gpu.read_buffer(&t.counters, 16)?;
        let px: &[GPx] = bytemuck::cast_slice(&gbytes);
        let counts: &[u32] = bytemuck::cast_slice(&cbytes);
        let (ow, oh) = o.projection.output_size(o.width, o.height);
        let mut frame = Frame::new(ow, oh);
        for (i, p) in px.iter().enumerate().take(frame.len()) {
            frame.colour[i] = [p.cd[0], p.cd[1], p.cd[2]];
            frame.steps[i] = p.misc[1];
            if p.misc[2] == 1 {
                frame.depth[i] = p.cd[3];
                frame.normal[i] = [p.n[0], p.n[1], p.n[2]];
                frame.id[i] = p.misc[0];
            } else {
                frame.id[i] = NO_ID;
            }
        }
        let stats = RenderStats {
            width: ow,
            height: oh,
            de_prepass: counts[0] as u64,
            de_trace: counts[1] as u64,
            de_shade: counts[2] as u64,
            hits: frame.depth.iter().filter(|d| d.is_finite()).count() as u64,
            ms_gpu,
            ms_total: start.elapsed().as_secs_f64() * 1e3,
        };
        Ok((frame, stats))
    }

    /// Renders like [`Renderer::render`] but leaves the image on the device: the passes are
    /// submitted and this returns at once, without waiting or reading anything back. The
    /// tonemapped image is [`Renderer::output_texture`]; commands a window submits later on the
    /// same queue (sampling it to present) run after these passes.
    pub fn render_to_texture(
        &mut self,
        scene: &Scene,
        tape: &Tape,
        camera: &Camera,
        o: &RenderOptions,
    ) -> Result<&wgpu::Texture, GpuError> {
        let globals = self.prepare(scene, tape, camera, o)?;
        let (_, oh) = o.projection.output_size(o.width, o.height);
        self.submit_passes(&globals, o, true, (0, oh));
        Ok(&self
            .targets
            .as_ref()
            .expect("submit built the targets")
            .texture)
    }

    /// Checks the request, builds the targets and computes the globals of a frame.
    fn prepare(
        &mut self,
        scene: &Scene,
        tape: &Tape,
        camera: &Camera,
        o: &RenderOptions,
    ) -> Result<Globals, GpuError> {
        if o.width == 0 || o.height == 0 {
            return Err(GpuError::Invalid(format!(
                "image size {}x{} is empty",
                o.width, o.height
            )));
        }
        o.projection
            .validate()
            .map_err(|e| GpuError::Invalid(e.to_string()))?;
        let sep = o.projection.separation();
        let (ow, oh) = o.projection.output_size(o.width, o.height);
        let tex_max = self.gpu.limits.max_texture_dimension_2d;
        if ow > tex_max || oh > tex_max {
            return Err(GpuError::ImageTooLarge {
                width: ow,
                height: oh,
                limit: tex_max,
            });
        }
        scene
            .validate()
            .map_err(|e| GpuError::Invalid(e.to_string()))?;
        camera
            .validate()
            .map_err(|e| GpuError::Invalid(e.to_string()))?;
        self.gpu.check_lost()?;
        let cam = o.projection.frame(camera);
        let pixel_angle = o.projection.pixel_angle(&cam, o.width, o.height);
        let footprint = pixel_angle * (camera.target - camera.eye).length();
        let eye_dist = camera.eye.length();
        if precision::too_deep(footprint, eye_dist) {
            return Err(GpuError::TooDeep {
                footprint,
                distance: eye_dist,
            });
        }
        let e = cam.eye;
        let d_eye = Evaluator::<f64>::new()
            .distance(tape, V3::new(e.x, e.y, e.z))
            .max(0.0);
        // Stereo eyes sit up to half the separation away from the camera position.
        let d_eye = (d_eye - 0.5 * sep).max(0.0);
        let t_start = if d_eye.is_finite() {
            (d_eye * 0.999) as f32
        } else {
            0.0
        };
        let r = &scene.render;
        let split = |v: glam::DVec3| {
            let (x, y, z) = (
                precision::split(v.x),
                precision::split(v.y),
                precision::split(v.z),
            );
            ([x.0, y.0, z.0], [x.1, y.1, z.1])
        };
        let (hi, lo) = split(e);
        let v3 = |v: glam::DVec3, w: f64| [v.x as f32, v.y as f32, v.z as f32, w as f32];
        let c3 = |c: [f64; 3], w: f64| [c[0] as f32, c[1] as f32, c[2] as f32, w as f32];
        let view_scale = (camera.target - camera.eye).length();
        let mut lights = [GpuLight {
            dir: [0.0; 4],
            colour: [0.0; 4],
        }; 8];
        for (i, l) in scene.lights.iter().enumerate().take(8) {
            let d = l.direction.normalize();
            lights[i] = GpuLight {
                dir: [d.x as f32, d.y as f32, d.z as f32, l.shadows as u32 as f32],
                colour: c3(l.colour.map(|c| c * l.intensity), 0.0),
            };
        }
        let g = Globals {
            eye_hi: [hi[0], hi[1], hi[2], pixel_angle as f32],
            eye_lo: [lo[0], lo[1], lo[2], cam.tan_half_fov as f32],
            forward: v3(cam.forward, r.max_distance),
            right: v3(cam.right, 0.5 * pixel_angle * r.pixel_epsilon),
            up: [cam.up.x as f32, cam.up.y as f32, cam.up.z as f32, t_start],
            sky_top: c3(r.sky_top, r.ambient),
            sky_bottom: c3(r.sky_bottom, r.ao),
            pal_a: c3(r.palette[0], 0.05 * view_scale),
            pal_b: c3(r.palette[1], r.shadow_softness),
            pal_c: c3(r.palette[2], if o.fog { r.fog } else { 0.0 }),
            pal_d: c3(r.palette[3], sep),
            dims: [o.width, o.height, mode(o.projection), r.max_steps],
            dims2: [
                scene.lights.len().min(8) as u32,
                self.n_materials.max(1),
                o.projection.eyes(),
                o.prepass as u32,
            ],
            lights,
            rows: [0, 0, 0, 0],
        };
        self.targets(o)?;
        Ok(g)
    }

    /// Submits the passes of one band of output rows `[y0, y1)`: the prepass too (for the
    /// whole frame, with the counters reset) when `first`. The writes of the globals are
    /// ordered with the submissions, so each band reads its own rows.
    fn submit_passes(&self, g: &Globals, o: &RenderOptions, first: bool, (y0, y1): (u32, u32)) {
        let eyes = o.projection.eyes();
        let (ow, _) = o.projection.output_size(o.width, o.height);
        let t = self.targets.as_ref().expect("prepare built the targets");
        let q = &self.gpu.queue;
        let g = Globals {
            rows: [y0, y1, 0, 0],
            ..*g
        };
        q.write_buffer(&t.globals, 0, bytemuck::bytes_of(&g));
        if first {
            q.write_buffer(&t.counters, 0, &[0u8; 16]);
        }
        let mut enc = self
            .gpu
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor::default());
        {
            let mut pass = enc.begin_compute_pass(&wgpu::ComputePassDescriptor::default());
            pass.set_bind_group(0, &self.tape_group, &[]);
            pass.set_bind_group(1, &t.group, &[]);
            if o.prepass && first {
                for (l, b) in PREPASS_LEVELS.iter().enumerate() {
                    pass.set_pipeline(&self.pipes.prepass[l]);
                    let cw = o.width.div_ceil(*b);
                    let ch = o.height.div_ceil(*b) * eyes;
                    pass.dispatch_workgroups(cw.div_ceil(8), ch.div_ceil(8), 1);
                }
            }
            let rows = y1 - y0;
            pass.set_pipeline(&self.pipes.depth);
            pass.dispatch_workgroups(ow.div_ceil(8), rows.div_ceil(8), 1);
            pass.set_pipeline(&self.pipes.shade);
            pass.dispatch_workgroups(ow.div_ceil(8), rows.div_ceil(8), 1);
        }
        q.submit([enc.finish()]);
    }

    /// The displayable image of the last render (8-bit sRGB), for a window to show.
    pub fn output_texture(&self) -> Option<&wgpu::Texture> {
        self.targets.as_ref().map(|t| &t.texture)
    }
}
