//! A device too small for the tape or the image, and a destroyed device: each gives a clear
//! [`GpuError`], never a panic or a hang. These tests build their own devices and never
//! dispatch a pass, so they run in seconds.

mod common;

use fathom_core::primitives::Primitive;
use fathom_core::scene::{Call, DomainOp, Node, Shape};
use fathom_core::transforms::Transform;
use fathom_core::{Scene, Tape};
use fathom_gpu::{Gpu, GpuError, Projection, RenderOptions, Renderer};
use std::time::Instant;

fn opts(width: u32, height: u32) -> RenderOptions {
    RenderOptions {
        width,
        height,
        projection: Projection::Mono,
        prepass: true,
        fog: true,
    }
}

/// A union of `n` translated spheres: about 5 instructions per sphere.
fn many_spheres(n: usize) -> Scene {
    let mut root = Node::new(Primitive::Sphere);
    for i in 0..n {
        let mut c = Node::new(Call {
            kind: Shape::Primitive(Primitive::Sphere),
            params: vec![0.1],
        });
        c.ops.push(Call {
            kind: DomainOp::Transform(Transform::Translate),
            params: vec![i as f64 * 0.01, 0.0, 0.0],
        });
        root.children.push(c);
    }
    let mut s = Scene::new(root);
    s.camera.eye = glam::DVec3::new(0.0, 0.5, 4.0);
    s
}

#[test]
fn a_device_too_small_for_the_tape_or_the_image_gives_clear_errors() {
    const STORAGE: u64 = 64 << 10;
    const TEXTURE: u32 = 256;
    let gpu = Gpu::headless_vulkan_limited(|l| {
        l.max_storage_buffer_binding_size = STORAGE;
        l.max_texture_dimension_2d = TEXTURE;
    })
    .unwrap_or_else(|e| panic!("GPU tests need a Vulkan adapter: {e}"));
    assert_eq!(gpu.limits.max_storage_buffer_binding_size, STORAGE);
    let mut r = Renderer::new(gpu).unwrap();

    // A tape of more than 4096 instructions (16 bytes each) does not fit 64 KiB.
    let big = many_spheres(1000);
    let tape = Tape::compile(&big).unwrap();
    assert!(
        tape.instrs().len() * 16 > STORAGE as usize,
        "the tape is big enough"
    );
    let e = r.set_tape(&tape).unwrap_err();
    assert!(matches!(e, GpuError::BufferTooLarge { .. }), "{e:?}");
    let msg = e.to_string();
    assert!(
        msg.contains("the tape") && msg.contains(&STORAGE.to_string()),
        "{msg}"
    );
    let e = r.render_scene(&big, &opts(32, 24)).unwrap_err();
    assert!(e.to_string().contains("the tape"), "{e}");

    // An image wider than the texture limit.
    let small = many_spheres(1);
    let e = r.render_scene(&small, &opts(TEXTURE + 1, 8)).unwrap_err();
    assert!(matches!(e, GpuError::ImageTooLarge { .. }), "{e:?}");
    assert!(e.to_string().contains(&format!("{TEXTURE} pixels")), "{e}");
    // Stereo doubles the output: two 200-wide views side by side exceed 256.
    let o = RenderOptions {
        projection: Projection::SideBySide {
            eye_separation: 0.1,
        },
        ..opts(200, 8)
    };
    let e = r.render_scene(&small, &o).unwrap_err();
    assert!(e.to_string().contains("400x8"), "{e}");
    // An image within the texture limit whose G-buffer (48 bytes a pixel) exceeds 64 KiB.
    let e = r.render_scene(&small, &opts(64, 48)).unwrap_err();
    assert!(matches!(e, GpuError::BufferTooLarge { .. }), "{e:?}");
    let msg = e.to_string();
    assert!(
        msg.contains("G-buffer") && msg.contains(&STORAGE.to_string()),
        "{msg}"
    );
}

#[test]
fn a_device_with_storage_buffers_too_small_for_any_tape_is_refused() {
    let gpu = Gpu::headless_vulkan_limited(|l| l.max_storage_buffer_binding_size = 256)
        .unwrap_or_else(|e| panic!("GPU tests need a Vulkan adapter: {e}"));
    let e = Renderer::new(gpu)
        .err()
        .expect("a 256-byte storage limit is refused");
    assert!(e.to_string().contains("256 bytes"), "{e}");
}

#[test]
fn a_destroyed_device_gives_an_error_not_a_panic_or_a_hang() {
    let mut r = common::fresh_renderer();
    let scene = many_spheres(1);
    let start = Instant::now();
    r.gpu().device.destroy();
    let e = r
        .render_scene(&scene, &opts(16, 12))
        .expect_err("rendering on a destroyed device must fail");
    eprintln!("destroyed device: {e}");
    assert!(
        matches!(e, GpuError::DeviceLost(_) | GpuError::Driver { .. }),
        "{e:?}"
    );
    // And again, without hanging either.
    let e = r.render_scene(&scene, &opts(16, 12)).unwrap_err();
    assert!(!e.to_string().is_empty());
    assert!(start.elapsed().as_secs() < 60, "took {:?}", start.elapsed());
}
