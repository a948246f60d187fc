//! The GPU renderer against the CPU tracer on every preset at 320x240, plus the promise that
//! scene edits never build a shader module or pipeline.

mod common;

use common::{COLOUR_TOL, compare, renderer};

use fathom_core::frame::Frame;
use fathom_core::presets::{self, PRESETS};
use fathom_core::primitives::Primitive;
use fathom_core::scene::{Call, DomainOp, Node, Shape};
use fathom_core::transforms::Transform;
use fathom_core::{Scene, Tape};
use fathom_gpu::{Projection, RenderOptions};
use fathom_trace::post::to_rgb8;

fn cpu(scene: &Scene, w: u32, h: u32) -> Frame {
    let o = fathom_trace::Options {
        width: w,
        height: h,
        ..Default::default()
    };
    fathom_trace::render(scene, &o, &|_, _| {}).unwrap().0
}

fn mono(w: u32, h: u32) -> RenderOptions {
    RenderOptions {
        width: w,
        height: h,
        projection: Projection::Mono,
        prepass: true,
        fog: true,
    }
}

#[test]
fn every_preset_matches_the_cpu_tracer_at_320x240() {
    let mut r = renderer();
    let mut report = Vec::new();
    let mut ok = true;
    for p in PRESETS {
        let scene = presets::load(p.name).unwrap();
        let c = cpu(&scene, 320, 240);
        let (g, _) = r.render_scene(&scene, &mono(320, 240)).unwrap();
        let (same, hit_bad, hit_sil) = compare(&c, &g);
        report.push(format!(
            "{}: {:.2}% of pixels within {COLOUR_TOL}/255, {hit_bad} hit/miss disagreements off silhouettes, {hit_sil} on them",
            p.name,
            same * 100.0
        ));
        ok &= same >= 0.99 && hit_bad == 0;
    }
    eprintln!("{}", report.join("\n"));
    assert!(ok, "{}", report.join("\n"));
}

fn sphere_scene() -> Scene {
    let mut s = Scene::new(Node::new(Primitive::Sphere));
    s.camera.eye = glam::DVec3::new(0.0, 0.5, 3.5);
    s
}

#[test]
fn scene_edits_build_no_shader_or_pipeline() {
    let mut r = renderer();
    let mut scene = sphere_scene();
    let o = mono(64, 48);
    let (first, _) = r.render_scene(&scene, &o).unwrap();
    let built = r.objects_built();
    assert!(built.0 >= 1 && built.1 >= 5, "counters are live: {built:?}");

    // A parameter edit: same instruction stream, new parameter buffer.
    let mut tape = Tape::compile(&scene).unwrap();
    scene.root.shape.set("radius", &[0.5]).unwrap();
    tape.update_params(&scene).unwrap();
    r.set_tape(&tape).unwrap();
    let (smaller, _) = r.render(&scene, &tape, &scene.camera, &o).unwrap();
    let hits = |f: &Frame| (0..f.len()).filter(|&i| f.is_hit(i)).count();
    assert!(hits(&smaller) < hits(&first), "the radius edit shows");

    // A structure edit: a new child, a different shape kind, a new tape.
    let mut child = Node::new(Call::<Shape>::from(Primitive::Box));
    child.ops.push(Call {
        kind: DomainOp::Transform(Transform::Translate),
        params: vec![0.8, 0.0, 0.0],
    });
    scene.root.children.push(child);
    let (grown, _) = r.render_scene(&scene, &o).unwrap();
    assert!(hits(&grown) > hits(&smaller), "the structure edit shows");
    assert_eq!(
        r.objects_built(),
        built,
        "(shader modules, compute pipelines) must not change on edits"
    );
}

#[test]
fn bad_sizes_give_errors_not_panics() {
    // Its own renderer: the simulated loss must not reach the other tests.
    let mut r = common::fresh_renderer();
    let scene = sphere_scene();
    let e = r.render_scene(&scene, &mono(0, 10)).unwrap_err();
    assert!(e.to_string().contains("empty"), "{e}");
    let max = r.gpu().limits.max_texture_dimension_2d;
    let e = r.render_scene(&scene, &mono(max + 1, 4)).unwrap_err();
    assert!(e.to_string().contains("largest texture"), "{e}");
    // A lost device is reported, not waited on.
    r.gpu().simulate_loss("test");
    let e = r.render_scene(&scene, &mono(8, 8)).unwrap_err();
    assert!(e.to_string().contains("lost"), "{e}");
}

#[test]
fn too_deep_a_zoom_hands_off_to_the_cpu() {
    let mut r = renderer();
    let mut scene = sphere_scene();
    // A camera 1e-6 from its target near the sphere: pixel footprints of ~1e-9.
    scene.camera.eye = glam::DVec3::new(0.0, 0.0, 1.000_001);
    scene.camera.target = glam::DVec3::new(0.0, 0.0, 1.0);
    let e = r.render_scene(&scene, &mono(64, 48)).unwrap_err();
    assert!(e.to_string().contains("on the CPU"), "{e}");
}

/// Copies an RGBA8 texture into host memory (rows padded to wgpu's copy alignment on the
/// device, unpadded here) and returns its RGB bytes, row-major.
fn read_rgb(r: &fathom_gpu::Renderer, tex: &wgpu::Texture) -> Vec<u8> {
    let gpu = r.gpu();
    let (w, h) = (tex.width(), tex.height());
    let row =
        (w * 4).div_ceil(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT) * wgpu::COPY_BYTES_PER_ROW_ALIGNMENT;
    let buf = gpu.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("test texture copy"),
        size: (row * h) as u64,
        usage: wgpu::BufferUsages::COPY_SRC | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    let mut enc = gpu
        .device
        .create_command_encoder(&wgpu::CommandEncoderDescriptor::default());
    enc.copy_texture_to_buffer(
        tex.as_image_copy(),
        wgpu::TexelCopyBufferInfo {
            buffer: &buf,
            layout: wgpu::TexelCopyBufferLayout {
                offset: 0,
                bytes_per_row: Some(row),
                rows_per_image: Some(h),
            },
        },
        tex.size(),
    );
    gpu.queue.submit([enc.finish()]);
    let bytes = gpu.read_buffer(&buf, (row * h) as u64).unwrap();
    let mut rgb = Vec::with_capacity((w * h * 3) as usize);
    for y in 0..h {
        for x in 0..w {
            let i = (y * row + x * 4) as usize;
            rgb.extend_from_slice(&bytes[i..i + 3]);
        }
    }
    rgb
}

#[test]
fn the_texture_left_for_a_window_is_the_image_a_readback_renders() {
    // A window presents `render_to_texture`'s image without reading anything back; it must be
    // the picture `render` returns for files (same passes, tonemap and sRGB encoding).
    let mut r = renderer();
    for (name, projection) in [
        ("menger", Projection::Mono),
        (
            "mandelbulb",
            Projection::SideBySide {
                eye_separation: 0.06,
            },
        ),
    ] {
        let scene = presets::load(name).unwrap();
        let tape = Tape::compile(&scene).unwrap();
        r.set_tape(&tape).unwrap();
        let o = RenderOptions {
            projection,
            ..mono(96, 64)
        };
        let (frame, _) = r.render(&scene, &tape, &scene.camera, &o).unwrap();
        let want = to_rgb8(&frame);
        let tex = r
            .render_to_texture(&scene, &tape, &scene.camera, &o)
            .unwrap();
        assert_eq!(
            (tex.width(), tex.height()),
            (frame.width, frame.height),
            "{name}: texture size"
        );
        let tex = tex.clone();
        let got = read_rgb(&r, &tex);
        let worst = want
            .iter()
            .zip(&got)
            .map(|(a, b)| a.abs_diff(*b))
            .max()
            .unwrap();
        // Both encode the same f32 colour; the shader's pow and the CPU's powf may round apart.
        assert!(
            worst <= 1,
            "{name}: texture and readback differ by up to {worst}/255"
        );
        assert!(
            got.iter().any(|&v| v > 40) && got.iter().any(|&v| v < 200),
            "{name}: the texture holds a picture, not a flat colour"
        );
    }
}

/// A frame rendered in bands of rows (how a window on a software adapter shows progress and
/// drops a stale frame) is the frame rendered at once, bit for bit, in every projection; a
/// band callback that answers `false` abandons the frame with `Cancelled` after that band.
#[test]
fn a_frame_in_bands_is_the_whole_frame_and_a_cancel_stops_it() {
    let mut r = renderer();
    let scene = presets::load("menger").unwrap();
    let tape = Tape::compile(&scene).unwrap();
    r.set_tape(&tape).unwrap();
    for projection in [
        Projection::Mono,
        Projection::SideBySide {
            eye_separation: 0.1,
        },
        Projection::Ods {
            eye_separation: 0.1,
        },
    ] {
        let o = RenderOptions {
            projection,
            ..mono(72, 50)
        };
        let (whole, _) = r.render(&scene, &tape, &scene.camera, &o).unwrap();
        let mut bands = Vec::new();
        let (banded, _) = r
            .render_in_bands(&scene, &tape, &scene.camera, &o, 16, &mut |done, total| {
                bands.push((done, total));
                true
            })
            .unwrap();
        assert_eq!(to_rgb8(&whole), to_rgb8(&banded), "{projection:?}");
        assert_eq!(whole.depth, banded.depth, "{projection:?}");
        let rows = whole.height;
        let expect: Vec<(u32, u32)> = (1..rows.div_ceil(16)).map(|i| (16 * i, rows)).collect();
        assert_eq!(bands, expect, "{projection:?}");
    }
    let mut calls = 0;
    let e = r
        .render_in_bands(
            &scene,
            &tape,
            &scene.camera,
            &mono(72, 50),
            16,
            &mut |_, _| {
                calls += 1;
                false
            },
        )
        .unwrap_err();
    assert!(matches!(e, fathom_gpu::GpuError::Cancelled), "{e}");
    assert_eq!(calls, 1, "the frame stopped at its first band");
}
